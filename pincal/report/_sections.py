"""Sections of a calibration report, built from an :class:`IdentificationRecord`.

One convention everywhere: lengths in µm, angles in µrad, uncertainties as 2σ (≈ 95 %
for Gaussian errors); every table header names its unit.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from pincal.identification import (
    COVARIANCE_KINDS,
    IdentificationRecord,
    covariance_kind,
    held_at_nominal,
)
from pincal.report._document import Section, Table
from pincal.report._gate_text import gate_sentences
from pincal.report._parameter_plots import plot_correlation, plot_parameters
from pincal.report._plots import plot_error_histogram, plot_errors_before_after
from pincal.report._render import PlotJobs
from pincal.report._uncertainty_text import uncertainty_lines

__all__ = [
    "BLOCKS",
    "POOR_ANGLE_2SIGMA",
    "POOR_LENGTH_2SIGMA",
    "UNITS_NOTE",
    "block_label",
    "components_of",
    "data_section",
    "outlier_section",
    "parameter_section",
    "poorly_determined",
    "prediction_section",
    "quality_section",
    "residual_section",
]

#: a length parameter with 2σ above this is flagged as poorly determined [m]
POOR_LENGTH_2SIGMA = 0.5e-3
#: an angle parameter with 2σ above this is flagged as poorly determined [rad]
POOR_ANGLE_2SIGMA = 1e-3
#: |whitened residual| above this flags an outlier
OUTLIER_LIMIT = 3.0
UNITS_NOTE = "lengths in µm, angles in µrad; uncertainties are 2σ"
_U = 1e6  # m → µm, rad → µrad
_POS, _ORI = ("x", "y", "z"), ("rx", "ry", "rz")


def _r(v: float, digits: int = 3) -> float:
    return round(float(v), digits) if math.isfinite(float(v)) else float("nan")


def _sig(v: float, digits: int = 4) -> float:
    """A joint term's SI value (e.g. 1.2e-5 rad/(N·m)) to ``digits`` significant digits."""
    v = float(v)
    return float(f"{v:.{digits}g}") if math.isfinite(v) else float("nan")


#: the two blocks of a pose: (name, its components, report unit)
BLOCKS = (("position", _POS, "µm"), ("orientation", _ORI, "µrad"))


def components_of(result: IdentificationRecord) -> tuple[str, ...]:
    """Names of the residual columns: the recorded measured components.

    Files written before pincal recorded them fall back to the residual width (3 =
    x y z, 6 = the full pose; other widths are named c0, c1, ...).
    """
    if result.components:
        return tuple(result.components)
    k = result.residuals.shape[1] if result.residuals.ndim == 2 else 0
    return {3: _POS, 6: _POS + _ORI}.get(k, tuple(f"c{j}" for j in range(k)))


def block_label(block: str, comps: tuple[str, ...] | None) -> str:
    """``"position (x y)"``: a block named with the components measured in it.

    Args:
        block: ``"position"`` or ``"orientation"``.
        comps: the measured components (all six, or those of a file), or None (unknown:
            the bare block name).
    """
    if comps is None:
        return block
    names = [c for c in comps if c in (_POS if block == "position" else _ORI)]
    return f"{block} ({' '.join(names) or 'not measured'})"


def _measured_blocks(comps: tuple[str, ...]) -> list[tuple[str, list[int], str]]:
    """(block, its column indices in ``comps``, unit) for each block with a measured column."""
    out = []
    for block, names, unit in BLOCKS:
        cols = [j for j, c in enumerate(comps) if c in names]
        if cols:
            out.append((block, cols, unit))
    return out




def poorly_determined(result: IdentificationRecord) -> list[str]:
    """Identified parameters whose 2σ exceeds 0.5 mm (lengths) or 1 mrad (angles)."""
    units = [u for u, ok in zip(result.units, result.identified, strict=True) if ok]
    limit = np.array([POOR_ANGLE_2SIGMA if u == "rad" else POOR_LENGTH_2SIGMA for u in units])
    bad = 2 * np.asarray(result.std) > limit
    return [n for n, b in zip(result.identified_names, bad, strict=True) if b]


def data_section(result: IdentificationRecord, notes: dict) -> tuple[Section, dict]:
    """Poses, components, instrument and noise (declared or estimated)."""
    comps = components_of(result)
    m = int(result.residuals.shape[0])
    w = result.weighting
    blocks = _measured_blocks(comps)
    rows: list[list[object]] = [
        ["poses", m, ""],
        ["measured components", " ".join(comps), ""],
    ]
    rows += [
        [f"{block} components", " ".join(comps[j] for j in cols), unit]
        for block, cols, unit in blocks
    ]
    rows += [
        ["scalar equations", int(result.n_equations), ""],
        ["identified parameters", int(result.identified.sum()), ""],
    ]
    data = notes.get("data")
    if isinstance(data, (list, tuple)):
        data = ", ".join(map(str, data)) or None
    rows.append(["measurement file", str(data) if data else "simulated (no file)", ""])
    noise: dict[str, object] = {"source": "unknown (not recorded in this file)"}
    if w is not None:
        how = {
            "declared": "declared (instrument / --noise)",
            "estimated": f"estimated from the residuals ({w.rounds} re-weighted fits)",
            "per-pose": "per-pose σ of the measurement file",
        }.get(w.source, w.source)
        rows.append(["noise", how, ""])
        measured = {block for block, _, _ in blocks}
        pos = _r(w.position_std * _U) if "position" in measured else None
        ori = _r(w.orientation_std * _U) if "orientation" in measured else None
        if pos is not None:
            rows.append([f"noise σ {block_label('position', comps)}", pos, "µm"])
        if ori is not None:
            rows.append([f"noise σ {block_label('orientation', comps)}", ori, "µrad"])
        rows.append(["loss", w.loss, ""])
        noise = {"source": w.source, "position_um": pos, "orientation_urad": ori, "loss": w.loss}
    text = (
        "What was measured and how it was weighted. The noise σ is per component "
        "(1σ); when it is estimated, each block's σ² = rᵀr / (n − tr H) at the fit."
    )
    return Section("Data and noise", text, (), [Table(["item", "value", "unit"], rows)]), noise


def residual_section(result: IdentificationRecord, plots: Path, jobs: PlotJobs) -> Section:
    """Residuals before and after per pose (plots), as histograms, and their statistics.

    The plots are recorded in ``jobs`` (files under ``plots``), drawn by the caller.
    """
    comps = components_of(result)
    rows, images = [], []
    for block, cols, shown in _measured_blocks(comps):
        after = np.linalg.norm(result.residuals[:, cols], axis=1)
        before = None
        if result.initial_residuals is not None:
            before = np.linalg.norm(np.asarray(result.initial_residuals)[:, cols], axis=1)
        # the statistics the calibration printed (ResidualStats over the same columns)
        stats = [getattr(s, f"{k}_{block}") for s in (result.before, result.after)
                 for k in ("rms", "max")]  # fmt: skip
        if not math.isfinite(stats[2]):  # a file without them: from the residuals
            stats[2:] = [float(np.sqrt(np.mean(after**2))), float(after.max())]
        rows.append([block_label(block, comps), shown, *(_r(v * _U) for v in stats)])
        if before is not None:
            images += error_images(
                jobs, before, after, "um" if shown == "µm" else "urad",
                plots / f"residual_{block}", f"{block_label(block, comps).capitalize()} residual",
            )  # fmt: skip
    headers = ["residual (norm per pose)", "unit", "RMS before", "max before", "RMS after",
               "max after"]  # fmt: skip
    text = (
        "Residual = measured − model at the measured poses, with the nominal model "
        "(before) and the identified one (after); norms per pose over the measured "
        "components of each block (named in brackets), in µm and µrad."
    )
    return Section("Residuals", text, images, [Table(headers, rows)])


def error_images(
    jobs: PlotJobs,
    before: np.ndarray,
    after: np.ndarray,
    unit: str,
    stem: Path,
    what: str,
    per_pose: bool = True,
    pose_noun: str = "pose",
) -> list[Path]:
    """The per-pose bars and the distribution of before/after error norms.

    Args:
        jobs: where the plots are recorded.
        before: (m,) error norms per pose of the nominal model [``unit``].
        after: (m',) the same of the identified model.
        unit: ``um`` or ``urad``.
        stem: path without suffix; the plots are ``stem.png`` and ``stem_histogram.png``.
        what: e.g. "Position residual" (titles "… per pose", "… distribution").
        per_pose: draw the per-pose bars (needs ``before`` and ``after`` pose by pose).
        pose_noun: the per-pose title's noun ("… per validation pose").

    Returns:
        The images' paths, in order.
    """
    images = []
    if per_pose:
        images.append(
            jobs.add(
                plot_errors_before_after, before, after, unit,
                path=stem.with_name(stem.name + ".png"), title=f"{what} per {pose_noun}",
            )
        )  # fmt: skip
    images.append(
        jobs.add(
            plot_error_histogram, before, after, unit,
            path=stem.with_name(stem.name + "_histogram.png"), title=f"{what} distribution",
        )
    )  # fmt: skip
    return images


LARGE_RESIDUALS = "Large residuals"


def outlier_section(result: IdentificationRecord) -> tuple[Section, list[int], list[int]]:
    """Poses with |whitened residual| > 3 and poses a robust loss down-weighted."""
    w = result.weighting
    if w is None or w.whitened.size == 0:
        text = "No weights recorded in this file: outliers cannot be flagged."
        return Section(LARGE_RESIDUALS, text), [], []
    comps = components_of(result)
    z = np.asarray(w.whitened)
    rows = []
    for i in w.outliers:
        j = int(np.argmax(np.abs(z[i])))
        rows.append([i, comps[j], _r(z[i, j], 2), _r(w.pose_weights[i], 3)])
    text = (
        f"{len(w.outliers)} of {z.shape[0]} poses have a whitened residual |r/σ| > "
        f"{OUTLIER_LIMIT:g} (expected for Gaussian noise: ~{0.0027 * z.size:.1f} "
        "components in all). The quality gate's outlier test (leverage-corrected, robust "
        "scale, Bonferroni bound) is reported in the Quality gate section."
    )
    if w.loss != "linear":
        text += (
            f" Robust loss {w.loss} (f_scale {w.f_scale:.3g}σ) down-weighted "
            f"{len(w.downweighted)} poses below 0.5: {list(w.downweighted)}."
        )
    headers = ["pose", "worst component", "whitened residual [σ]", "robust weight"]
    table = Table(headers, rows) if rows else Table(headers, [["none", "", "", ""]])
    return Section(LARGE_RESIDUALS, text, (), [table]), list(w.outliers), list(w.downweighted)


def parameter_section(
    result: IdentificationRecord, plots: Path, jobs: PlotJobs
) -> tuple[Section, list[str]]:
    """Identified values with 2σ, poorly determined flags, plot and correlation map.

    The plots are recorded in ``jobs`` (files under ``plots``), drawn by the caller.
    """
    names = list(result.identified_names)
    values, std = result.values, result.std
    units = [u for u, ok in zip(result.units, result.identified, strict=True) if ok]
    kinds = ["angle" if u == "rad" else "length" for u in units]
    truth = result.annotations.get("truth") or {}
    true = np.array([float(truth[n]) for n in names]) if all(n in truth for n in names) else None
    geo = [k for k, u in enumerate(units) if u in ("m", "rad")]  # joint terms: SI, own unit
    images = [
        jobs.add(
            plot_parameters, [names[k] for k in geo], values[geo], std[geo],
            None if true is None else true[geo], path=plots / "parameters.png",
            kinds=[kinds[k] for k in geo], length_unit="um", angle_unit="urad",
        )
    ] if geo else []  # fmt: skip
    if len(names) > 1:
        images.append(
            jobs.add(plot_correlation, names, result.covariance, path=plots / "correlation.png")
        )
    poor = set(poorly_determined(result))
    headers = ["parameter", "value [µm | µrad]", "2σ [µm | µrad]", "unit"]
    headers += ["true [µm | µrad]", "error / σ"] if true is not None else []
    headers += ["poorly determined"]
    rows = []
    for k, name in enumerate(names):
        label = "µrad" if units[k] == "rad" else "µm"
        f, rnd = _U, _r
        if units[k] not in ("m", "rad"):  # a joint term (e.g. a compliance): SI, its unit
            label, f, rnd = units[k], 1.0, _sig
        row: list[object] = [name, rnd(values[k] * f), rnd(2 * std[k] * f), label]
        if true is not None:
            row += [
                rnd(true[k] * f),
                _r((values[k] - true[k]) / std[k], 2) if std[k] > 0 else "",
            ]
        row.append("YES" if name in poor else "")
        rows.append(row)
    text = (
        "Displacements of the URDF joint origins (" + UNITS_NOTE + "; joint terms in SI, "
        "their unit named)"
        + (", with the simulated true values" if true is not None else "")
        + f". Poorly determined: 2σ > {POOR_LENGTH_2SIGMA * 1e3:g} mm (lengths) or > "
        f"{POOR_ANGLE_2SIGMA * 1e3:g} mrad (angles) — {len(poor)} parameters"
        + (f": {', '.join(sorted(poor))}." if poor else ".")
    )
    held, why = held_at_nominal(result.annotations)
    unidentifiable = [n for n in result.fixed if n not in held]
    if unidentifiable:
        text += f"\n\nHeld at their start values (not identifiable): {', '.join(unidentifiable)}."
    if held:
        text += f"\n\nHeld at nominal although identifiable ({why}): {', '.join(held)}."
    return Section("Identified parameters", text, images, [Table(headers, rows)]), sorted(poor)


def prediction_section(result: IdentificationRecord) -> Section:
    """Cramér–Rao prediction vs what the calibration achieved."""
    w = result.weighting
    rows: list[list[object]] = []
    if w is not None and w.whitened.size:
        comps = components_of(result)
        for label, cols, unit in _measured_blocks(comps):
            sig = w.position_std if label == "position" else w.orientation_std
            if not math.isfinite(sig) or label not in w.redundancy:
                continue
            n_b = len(cols) * result.residuals.shape[0]
            predicted = sig * math.sqrt(w.redundancy[label] / n_b)
            achieved = float(np.sqrt(np.mean(result.residuals[:, cols] ** 2)))
            rows.append(
                [f"{block_label(label, comps)} residual RMS per component", unit,
                 _r(predicted * _U), _r(achieved * _U)]
            )  # fmt: skip
    rows.append(["reduced χ²", "", 1.0, _r(result.reduced_chi2, 4)])
    truth = result.annotations.get("truth") or {}
    names = result.identified_names
    if names and all(n in truth for n in names) and np.all(result.std > 0):
        e = result.values - np.array([truth[n] for n in names])
        rows.append(["RMS(error / σ) of the parameters", "", 1.0,
                     _r(float(np.sqrt(np.mean((e / result.std) ** 2))), 3)])  # fmt: skip
        maha = float(e @ np.linalg.pinv(result.covariance) @ e) / e.size
        rows.append(["Mahalanobis error / n", "", 1.0, _r(maha, 3)])
    kind = covariance_kind(result.annotations, None if w is None else w.source)
    text = (
        f"The parameter covariance is the {COVARIANCE_KINDS[kind]}. Predicted: residual RMS "
        "σ·√(redundancy / n) and χ² = 1 when the model and noise are right; achieved: what "
        "this calibration gave."
    )
    return Section(
        "Prediction (Cramér–Rao) vs achievement" if kind == "cramer-rao"
        else "Prediction vs achievement",
        text,
        (),
        [Table(["quantity", "unit", "predicted", "achieved"], rows)],
    )


def quality_section(notes: dict) -> Section | None:
    """The quality gate's verdict (``annotations['quality']``): passed, or overridden and why."""
    q = notes.get("quality")
    if not isinstance(q, dict):
        return None
    if q.get("passed") and q.get("held_out"):
        text = "The quality gate passed: the calibration predicts unseen poses better."
    elif q.get("passed"):
        text = "The quality gate passed: the fit is consistent with the data and the noise."
    elif q.get("overridden"):
        text = (
            "OVERRIDDEN: the quality gate refused this calibration and was overridden with "
            "--force. "
            f"{q.get('reason') or ''}"
        )
    else:
        text = f"The quality gate refused this calibration. {q.get('reason') or ''}"
    rows = [["refused", str(i.get("kind")), str(i.get("message"))] for i in q.get("refusals", [])]
    rows += [["warning", str(i.get("kind")), str(i.get("message"))] for i in q.get("warnings", [])]
    if q.get("outlier_poses"):
        limit = q.get("outlier_limit")
        text += (
            f"\n\nOutlier poses (robust normalised residual > {limit if limit else '?'}): "
            f"{q['outlier_poses']}; a robust fit (--loss huber) down-weights them."
        )
    if q.get("duplicate_rows"):
        text += f"\n\nDuplicate rows (copy, original): {q['duplicate_rows']}."
    said = [line.strip().replace("the σ above", "the σ below")
            for line in uncertainty_lines(q.get("uncertainty") or {})]  # fmt: skip
    said += gate_sentences(q)
    if said:  # how the σ were made: method, Student-t / F intervals, a bootstrap beside
        text += "\n\n" + "\n\n".join(s[0].upper() + s[1:] + "." for s in said)
    tables = [Table(["verdict", "check", "finding"], rows)] if rows else []
    return Section("Quality gate", text, (), tables)

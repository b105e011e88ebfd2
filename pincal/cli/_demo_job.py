"""The main job: a full simulated calibration of the bundled Stewart platform.

A seeded "actual" machine is drawn around the nominal model, measurement poses
are chosen from a candidate set by maximising O1 on the noise-whitened Jacobian
(D-optimal design), the Cramér–Rao bound predicts the achievable accuracy before
measuring, a laser-tracker campaign is simulated, the parameters are identified,
the result is validated on fresh poses (predicted vs achieved) and the calibration
directory (:func:`pincal.io.write_calibration`) is written out.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pincal.design import (
    MAX_CANDIDATE_BYTES,
    MAX_CANDIDATES,
    CramerRaoReport,
    DesignScaling,
    PoseDesign,
    candidate_set,
    cramer_rao_from_jacobian,
    select_poses,
)
from pincal.errors import QualityGateError
from pincal.identification import (
    IdentificationResult,
    check_quality,
    identify,
)
from pincal.io import IDENTIFICATION_FILE, MANIFEST, write_calibration
from pincal.measure import (
    DEFAULT_NOISE,
    NoiseModel,
    simulate_measurements,
)
from pincal.model import (
    COMPONENTS,
    Mechanism,
    ParameterSet,
    load_mechanism,
    sample_actuators,
)
from pincal.sensitivity import identification_jacobian, parameters
from pincal.validation import PoseErrors, pose_errors


@dataclass(frozen=True)
class DemoSettings:
    """Settings of the simulated campaign.

    Attributes:
        model: bundled model name; preset: parameter preset.
        seed: random seed.
        n_poses: measurement poses; n_validation: fresh validation poses.
        error_std: std of the drawn geometric errors [mm].
        noise: instrument noise (mm, mrad).
        method: identification method.
        candidates: candidate spec for pose selection (``grid:4``, ``random:300``,
            ``oa:5``) or ``"none"`` for random measurement poses.
        index: observability index maximised on the noise-whitened Jacobian.
        bounded: refuse a candidate set past the default bounds of
            :func:`pincal.design.candidate_set` (False: ``--yes``).
        force: write the calibration even when the quality gate refuses it (recorded).
    """

    model: str = "stewart_6ups"
    preset: str = "stewart42"
    seed: int = 7
    n_poses: int = 30
    n_validation: int = 60
    error_std: float = 0.5
    noise: NoiseModel = DEFAULT_NOISE
    method: str = "gauss-newton"
    report: bool = True
    candidates: str = "grid:4"
    index: str = "O1"
    bounded: bool = True
    force: bool = False


@dataclass(frozen=True)
class DemoResult:
    """Everything the demo computed (SI inside)."""

    settings: DemoSettings
    nominal: Mechanism
    params: ParameterSet
    true_values: np.ndarray
    result: IdentificationResult
    before: PoseErrors
    after: PoseErrors
    files: tuple[Path, ...]
    design: PoseDesign | None = None
    crb: CramerRaoReport | None = None


def draw_errors(params: ParameterSet, std_mm: float, rng: np.random.Generator) -> np.ndarray:
    """Random errors: N(0, std) on lengths [mm → m]; angles get std/100 mm per rad."""
    scale = np.array([std_mm * 1e-3 if u == "m" else std_mm * 1e-3 / 0.1 for u in params.units])
    return rng.normal(0.0, 1.0, len(params)) * scale


def run_demo(
    settings: DemoSettings = DemoSettings(),
    out_dir: str | Path | None = "pincal-out",
    progress: Callable[[str], None] | None = None,
) -> DemoResult:
    """Run the simulated calibration and write the calibrated model to ``out_dir``.

    BLAS runs single-threaded throughout: every dense solve here is small, and a
    threaded BLAS on a busy machine made them several times slower. The report's
    plots are drawn in this process.
    """
    from threadpoolctl import threadpool_limits

    with threadpool_limits(1):
        return _run_demo(settings, out_dir, progress)


def _run_demo(
    settings: DemoSettings,
    out_dir: str | Path | None,
    progress: Callable[[str], None] | None,
) -> DemoResult:
    say = progress or (lambda _msg: None)
    rng = np.random.default_rng(settings.seed)
    nominal = load_mechanism(settings.model)
    params = parameters(nominal, settings.preset)
    true = draw_errors(params, settings.error_std, rng)
    actual = params.apply(nominal, true)
    q_val = sample_actuators(nominal, settings.n_validation, rng)
    design = None
    if settings.candidates == "none":
        say(f"sampling {settings.n_poses} random measurement poses")
        q_meas = sample_actuators(nominal, settings.n_poses, rng)
    else:
        say(f"candidate poses {settings.candidates}")
        cands = candidate_set(
            nominal, params, settings.candidates, rng,
            max_candidates=MAX_CANDIDATES if settings.bounded else None,
            max_bytes=MAX_CANDIDATE_BYTES if settings.bounded else None,
        )  # fmt: skip
        sig = settings.noise.std(("x", "rx"))
        scaling = DesignScaling("noise", position_std=sig[0], orientation_std=sig[1])
        say(f"selecting {settings.n_poses} of {len(cands)} poses by {settings.index}")
        design = select_poses(cands, settings.n_poses, settings.index, scaling, rng=rng)
        q_meas = design.q_act
    comps = nominal.measured_components
    if design is not None:  # the selected candidates' Jacobian blocks, already computed
        J_meas = design.candidates.jacobians
    else:
        J_meas = identification_jacobian(nominal, params, q_meas).reshape(
            len(q_meas), len(comps), len(params)
        )
    J_val = identification_jacobian(nominal, params, q_val, components=COMPONENTS).reshape(
        len(q_val), 6, len(params)
    )
    # the prediction, like the validation, is over the measured components only
    J_val[:, [k for k, c in enumerate(COMPONENTS) if c not in comps], :] = 0.0
    crb = cramer_rao_from_jacobian(J_meas, comps, settings.noise, J_val, params.names, params.units)
    meas = simulate_measurements(actual, q_meas, settings.noise, rng)
    say(f"identifying {len(params)} parameters ({settings.method})")
    result = identify(nominal, params, meas, settings.method)
    verdict = check_quality(result, meas, mech=nominal)
    if not verdict.passed and not settings.force and out_dir is not None:
        raise QualityGateError(verdict.reason(), verdict)
    say(f"validating on {settings.n_validation} fresh poses")
    before = pose_errors(nominal, actual, q_val, comps)
    after = pose_errors(result.calibrated, actual, q_val, comps)
    files: list[Path] = []
    if out_dir is not None:
        out = Path(out_dir)
        notes: dict[str, object] = {
            "quality": verdict.to_dict(overridden=settings.force),
            "truth": dict(zip(params.names, (float(t) for t in true), strict=True)),
            "validation_before": before.summary(),
            "validation_after": after.summary(),
            "validation_components": list(before.components),
            "validation_source": f"{settings.n_validation} fresh poses of the simulated actual "
            "machine (truth)",
            "validation_errors": {
                "before": {
                    "position": before.position.tolist(),
                    "orientation": before.orientation.tolist(),
                },
                "after": {
                    "position": after.position.tolist(),
                    "orientation": after.orientation.tolist(),
                },
            },
        }
        if design is not None:
            notes["index_history"] = {settings.index: list(design.selection.history)}
        cal = write_calibration(
            out, result, model_source=settings.model, noise=settings.noise, annotations=notes
        )
        files += [out / MANIFEST, cal.calibrated_urdf, cal.calibrated_urdf.with_suffix(".yaml")]
        files.append(out / IDENTIFICATION_FILE)
        if settings.report:
            from pincal.report import calibration_report

            say("writing the report (plots)")
            written = calibration_report(out)
            files += [written.html, written.markdown]
            if written.json is not None:
                files.append(written.json)
    return DemoResult(
        settings, nominal, params, true, result, before, after, tuple(files), design, crb
    )


def _f(v: float | None) -> str:
    return f"{'-':>8s}" if v is None else f"{v:8.4f}"


def _row(label: str, s: dict[str, float | None]) -> str:
    return (
        f"    {label:30s} {_f(s['rms_position_mm'])}  {_f(s['max_position_mm'])}"
        f"   {_f(s['rms_orientation_mrad'])}  {_f(s['max_orientation_mrad'])}"
    )


def _prediction_lines(
    d: DemoResult, err: np.ndarray, after: dict[str, float | None]
) -> list[str]:
    """Predicted (Cramér–Rao, before measuring) vs achieved accuracy."""
    from pincal.report import block_label

    if d.crb is None:
        return []
    c = d.crb
    idx = [c.names.index(n) for n in d.result.params.names]
    pred_std = float(np.sqrt(np.mean(c.std[idx] ** 2)))
    lines = [
        "  predicted before measuring (Cramér–Rao) vs achieved:",
        f"    {'':46s} predicted   achieved",
        f"    {'RMS parameter error [µm]':46s} {pred_std * 1e6:9.3f}  "
        f"{np.sqrt(np.mean(err**2)) * 1e6:9.3f}",
    ]
    comps = d.before.components
    for block, unit, pred in (
        ("position", "mm", c.validation_position_rms),
        ("orientation", "mrad", c.validation_orientation_rms),
    ):
        got = after[f"rms_{block}_{unit}"]
        if got is not None:
            label = f"validation {block_label(block, comps)} RMS [{unit}]"
            lines.append(f"    {label:46s} {pred * 1e3:9.5f}  {got:9.5f}")
    return lines


def format_demo(d: DemoResult) -> str:
    """The printed report of a demo run."""
    from pincal.report import block_label

    r, s = d.result, d.settings
    b, a = d.before.summary(), d.after.summary()
    idx = [d.params.index(n) for n in r.params.names]
    err = r.values - d.true_values[idx]
    z = err / r.std
    if d.design is not None:
        sel = d.design.selection
        poses_text = (
            f"poses chosen by {sel.index_name} ({sel.method}) from {d.design.n_candidates} "
            f"{s.candidates} candidates; {sel.index_name} {sel.history[0]:.4g} → {sel.value:.4g}"
        )
    else:
        poses_text = "random workspace poses"
    lines = [
        f"pincal demo — simulated calibration of {d.nominal.name} ({len(d.params)} parameters, "
        f"preset {d.params.label!r})",
        f"  actual machine: errors N(0, {s.error_std} mm) drawn with seed {s.seed}",
        f"  measurements: {s.n_poses} {poses_text}, noise {s.noise.position} mm / "
        f"{s.noise.orientation} mrad (1σ)",
        f"  identification: {r.method}, {r.iterations} iterations, {r.message}; reduced χ² "
        f"{r.reduced_chi2:.3f}",
        "",
        f"  validation on {s.n_validation} fresh poses, over the measured components "
        f"{' '.join(d.before.components)}:",
        f"    {'':30s} {block_label('position', d.before.components) + ' [mm]':20s} "
        f"{block_label('orientation', d.before.components)} [mrad]",
        "                                      RMS       max        RMS       max",
        _row("nominal model", b),
        _row("calibrated model", a),
        "",
        *_prediction_lines(d, err, a),
        *([""] if d.crb is not None else []),
        "  parameter errors after identification vs predicted std (Cramér–Rao):",
        f"    RMS |error|/σ = {np.sqrt(np.mean(z**2)):.3f} (expected ≈ 1); "
        f"{np.mean(np.abs(z) < 2) * 100:.0f} % within 2σ (expected ≈ 95 %)",
        "    name                      true [µm]   identified [µm]   error [µm]   σ [µm]",
    ]
    for k, name in enumerate(r.params.names):
        unit = "µm" if r.params.units[k] == "m" else "µrad"
        lines.append(
            f"    {name:24s} {d.true_values[idx[k]] * 1e6:10.2f}   {r.values[k] * 1e6:12.2f}"
            f"      {err[k] * 1e6:9.2f}  {r.std[k] * 1e6:8.2f} {unit if unit != 'µm' else ''}"
        )
    if d.files:
        lines += ["", "  wrote: " + ", ".join(str(f) for f in d.files)]
    return "\n".join(lines)

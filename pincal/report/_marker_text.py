"""The marker lines of the plain-text report of a marker calibration (`calibrate --link`).

Rendered from the run (:class:`pincal.workflow.MarkerRun`): the registration, the
identified instrument frame and marker(s) with 2σ [mm, mrad], the prior (and its
cross-validation table), the loss, the held-out comparison with the registration
alone, the solver, the notes.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence

import pinocchio as pin

from pincal.identification import MarkerFit
from pincal.measure import MarkerSetup, marker_frame
from pincal.model import BASE_JOINT, TOOL_JOINT
from pincal.workflow import MarkerRun

__all__ = ["marker_lines", "solver_line"]


def _nums(v: Sequence[float | None]) -> str:
    return ", ".join("–" if a is None else f"{a:.2f}" for a in v)


def _identified(fit: MarkerFit, setup: MarkerSetup) -> list[str]:
    """The identified instrument frame and marker(s) [mm, mrad] with 2σ where identified."""
    joints = fit.calibrated.tree.joints
    two_sigma = dict(zip(fit.result.identified_names, 2 * fit.result.std, strict=True))

    def sig(prefix: str, dofs: str) -> list[float | None]:
        out = [two_sigma.get(f"{prefix}.{d}") for d in dofs.split()]
        return [None if v is None else float(v) * 1e3 for v in out]

    def mm(v: Iterable[float]) -> list[float | None]:
        return [float(x) * 1e3 for x in v]

    T = joints[BASE_JOINT].origin
    lines = [
        f"identified instrument frame: translation [{_nums(mm(T.translation))}] mm, rotation "
        f"rpy [{_nums(mm(pin.rpy.matrixToRpy(T.rotation)))}] mrad; 2σ of base_frame tx ty tz "
        f"rx ry rz [{_nums(sig(BASE_JOINT, 'tx ty tz rx ry rz'))}] mm/mrad",
        f"identified marker [{_nums(mm(joints[TOOL_JOINT].origin.translation))}] mm in "
        f"{setup.link}; 2σ of tool_frame tx ty tz [{_nums(sig(TOOL_JOINT, 'tx ty tz'))}] mm "
        "(–: held, or absorbed by another parameter)",
    ]
    if setup.measures_orientation:
        R = joints[TOOL_JOINT].origin.rotation
        lines.append(f"identified body rotation rpy [{_nums(mm(pin.rpy.matrixToRpy(R)))}] mrad "
                     f"in {setup.link}; 2σ of tool_frame rx ry rz "
                     f"[{_nums(sig(TOOL_JOINT, 'rx ry rz'))}] mrad")  # fmt: skip
    for k in range(1, 1 + len(setup.more_columns)):
        joint = marker_frame(k)[0]
        lines.append(f"identified marker {k + 1} [{_nums(mm(joints[joint].origin.translation))}]"
                     f" mm in {setup.marker_links[k]}; 2σ of marker{k + 1}_frame tx ty tz "
                     f"[{_nums(sig(joint, 'tx ty tz'))}] mm")  # fmt: skip
    return lines


def marker_lines(run: MarkerRun) -> list[str]:
    """The report lines of a marker calibration: registration, prior, loss, held-out, notes.

    Args:
        run: the calibration (:class:`pincal.workflow.MarkerRun`).

    Returns:
        The lines, the first one blank.
    """
    fit, setup, prior = run.fit, run.setup, run.prior
    reg = fit.registration
    mk = ", ".join(f"{float(v) * 1e3:.2f}" for v in reg.marker)
    links = setup.marker_links
    also = "".join(f"; marker {k + 2}: columns {' '.join(c)}"
                   + (f" on {links[k + 1]}" if links[k + 1] != setup.link else "")
                   for k, c in enumerate(setup.more_columns))  # fmt: skip
    body = ""
    if setup.measures_orientation:
        body = f"; orientation {' '.join(setup.orientation_columns)}, {setup.orientation}"
        also += body
    turned = "" if reg.orientation_rms is None else (
        f", rotation angle RMS {reg.orientation_rms * 1e3:.3f} mrad")  # fmt: skip
    lines = [
        "",
        f"{'marker body' if body else 'marker'} on {setup.link} (columns "
        f"{' '.join(setup.columns)}, {setup.length_unit}{also}); instrument frame "
        f"{setup.instrument_frame}",
        f"registration (closed form, {reg.iterations} alternations): RMS "
        f"{reg.fit.rms * 1e3:.3f} mm{turned}; marker [{mk}] mm in {setup.link}",
        *_identified(fit, setup),
    ]
    if prior is None:
        lines.append("prior: none")
    else:
        lines.append(f"prior on the machine's parameters: σ {prior.length * 1e3:.3g} mm, "
                     f"{prior.angle * 1e3:.3g} mrad about nominal")  # fmt: skip
    k, seed = run.settings.folds, run.settings.seed
    if run.choice.chosen:
        tried = "; ".join(f"σ {s:g} → {rms:.3f} mm" for s, rms in run.choice.table)
        lines.append(f"  chosen by {k}-fold cross-validation (seed {seed}), held-out RMS: {tried}")
    if run.settings.loss == "auto":
        lines.append(f"loss: {run.loss} (auto: least squares unless the outlier test names "
                     "poses)")  # fmt: skip
    held = run.verdict.held_out
    if held is not None:
        cal, base = held["calibrated"], held["baseline"]
        nested = "; the prior chosen again in each fold" if run.choice.chosen else ""
        lines.append(
            f"held-out ({k}-fold, seed {seed}, every fold refitted{nested}): RMS "
            f"{cal['held_out_rms_mm']:.3f} mm calibrated, {base['held_out_rms_mm']:.3f} mm "
            f"{base['name']}"
        )
        if "held_out_orientation_rms_mrad" in cal and "held_out_orientation_rms_mrad" in base:
            lines.append(f"  rotation angle held-out RMS {cal['held_out_orientation_rms_mrad']:.3f}"
                         f" mrad calibrated, {base['held_out_orientation_rms_mrad']:.3f} mrad "
                         f"{base['name']}")  # fmt: skip
    solver = solver_line(fit.method, run.settings.method, run.loss)
    lines += [solver] if solver else []
    lines += [f"note: {n}" for n in (*run.notes, *run.warnings)]
    return lines


def solver_line(used: str, asked: str, loss: str) -> str | None:
    """Why the solver ``used`` is not the one ``asked`` for (None when it is)."""
    if used == asked:
        return None
    if loss != "linear":
        return f"solver: {used} (the {loss} loss runs Levenberg–Marquardt)"
    return f"solver: {used} (switched from {asked})"

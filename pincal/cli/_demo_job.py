"""The main job of ``pincal demo``: the simulated calibration, written and printed.

:func:`pincal.workflow.simulate_demo` computes; here its result becomes the calibration
directory (:func:`pincal.io.write_calibration`) and report, and the printed text.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from pincal.workflow import DemoAccuracy, DemoResult, DemoSettings

__all__ = ["collections_skip_the_imports", "demo_summary", "format_demo", "run_demo"]


@contextmanager
def collections_skip_the_imports() -> Iterator[None]:
    """Within: the objects that exist now (the imported modules) are frozen; at exit, all.

    Collections of Python's oldest generation scan every tracked object — the array
    library, Pinocchio and pincal loaded, ≈ 25 ms each — though during the demo they
    can only find the run's own garbage; and finalisation runs a last full collection
    (≈ 70 ms) just before the process ends and its memory goes back anyway. The objects
    frozen here are unfrozen on leaving unless the caller had frozen some (a process
    that runs the command and goes on, a test session, collects them again); the freeze
    at exit is registered once with :mod:`atexit`.
    """
    import atexit
    import gc

    atexit.unregister(gc.freeze)
    atexit.register(gc.freeze)
    frozen_before = gc.get_freeze_count()
    gc.freeze()
    try:
        yield
    finally:
        if not frozen_before:  # not undoing a freeze of the caller's
            gc.unfreeze()


def run_demo(
    settings: DemoSettings | None = None,
    out_dir: str | Path | None = "pincal-out",
    progress: Callable[[str], None] | None = None,
) -> tuple[DemoResult, tuple[Path, ...]]:
    """Run the simulated calibration and write the calibration directory ``out_dir``.

    BLAS runs single-threaded throughout (see :func:`pincal.workflow.simulate_demo`);
    the report's plots are drawn in this process.

    Returns:
        The result and the files written (none when ``out_dir`` is None: then the
        quality gate does not refuse either).
    """
    from threadpoolctl import threadpool_limits

    from pincal.io import IDENTIFICATION_FILE, MANIFEST, write_calibration
    from pincal.workflow import DemoSettings, simulate_demo

    settings = settings or DemoSettings()
    say = progress or (lambda _msg: None)
    files: list[Path] = []
    with threadpool_limits(1):
        d = simulate_demo(settings, say, gate=out_dir is not None)
        if out_dir is not None:
            out = Path(out_dir)
            cal = write_calibration(out, d.result, model_source=settings.model,
                                    noise=settings.noise, annotations=d.annotations())  # fmt: skip
            files += [out / MANIFEST, cal.calibrated_urdf, cal.calibrated_urdf.with_suffix(".yaml")]
            files.append(out / IDENTIFICATION_FILE)
            if settings.report:
                from pincal.report import calibration_report

                say("writing the report (plots)")
                written = calibration_report(out)
                files += [written.html, written.markdown]
                if written.json is not None:
                    files.append(written.json)
    return d, tuple(files)


def demo_summary(d: DemoResult, files: tuple[Path, ...], out: str) -> dict[str, Any]:
    """The JSON summary of a demo run (``pincal demo --json``)."""
    r = d.result
    return {
        "model": d.nominal.name,
        "parameters": len(d.params),
        "iterations": int(r.iterations),
        "reduced_chi2": float(r.reduced_chi2),
        "validation_before": d.before.summary(),
        "validation_after": d.after.summary(),
        "calibration": str(out),
        "files": [str(f) for f in files],
    }


def _f(v: float | None) -> str:
    return f"{'-':>8s}" if v is None else f"{v:8.4f}"


def _row(label: str, s: dict[str, float | None]) -> str:
    return (
        f"    {label:30s} {_f(s['rms_position_mm'])}  {_f(s['max_position_mm'])}"
        f"   {_f(s['rms_orientation_mrad'])}  {_f(s['max_orientation_mrad'])}"
    )


def _prediction_lines(
    d: DemoResult, acc: DemoAccuracy, after: dict[str, float | None]
) -> list[str]:
    """Predicted (Cramér–Rao, before measuring) vs achieved accuracy."""
    from pincal.report import block_label

    if d.crb is None or acc.predicted_std is None:
        return []
    c = d.crb
    lines = [
        "  predicted before measuring (Cramér–Rao) vs achieved:",
        f"    {'':46s} predicted   achieved",
        f"    {'RMS parameter error [µm]':46s} {acc.predicted_std * 1e6:9.3f}  "
        f"{acc.achieved_rms * 1e6:9.3f}",
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


def format_demo(d: DemoResult, files: tuple[Path, ...] = ()) -> str:
    """The printed report of a demo run (``files``: those written, listed last)."""
    from pincal.report import block_label

    r, s, acc = d.result, d.settings, d.accuracy()
    b, a = d.before.summary(), d.after.summary()
    if d.design is not None:
        sel = d.design.selection
        poses_text = (
            f"poses chosen by {sel.index_name} ({sel.method}) from {d.design.n_candidates} "
            f"{d.design.candidates.source} candidates; "
            f"{sel.index_name} {sel.history[0]:.4g} → {sel.value:.4g}"
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
        *_prediction_lines(d, acc, a),
        *([""] if d.crb is not None else []),
        "  parameter errors after identification vs predicted std (Cramér–Rao):",
        f"    RMS |error|/σ = {acc.z_rms:.3f} (expected ≈ 1); "
        f"{acc.within_2sigma:.0f} % within 2σ (expected ≈ 95 %)",
        "    name                      true [µm]   identified [µm]   error [µm]   σ [µm]",
    ]
    for k, name in enumerate(acc.names):
        unit = "µm" if acc.units[k] == "m" else "µrad"
        lines.append(
            f"    {name:24s} {acc.true[k] * 1e6:10.2f}   {acc.identified[k] * 1e6:12.2f}"
            f"      {acc.error[k] * 1e6:9.2f}  {acc.std[k] * 1e6:8.2f} "
            f"{unit if unit != 'µm' else ''}"
        )
    if files:
        lines += ["", "  wrote: " + ", ".join(str(f) for f in files)]
    return "\n".join(lines)

"""The quality gate on the command line: options, printing, refusal and override.

The verdict itself is :func:`pincal.identification.check_quality`'s; this module only
prints it and raises :class:`pincal.errors.QualityGateError` for a refusal without
``--force``; its lines in ``report.txt`` are :func:`pincal.report.quality_lines`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import click

from pincal.errors import QualityGateError

if TYPE_CHECKING:  # imported in the calls: the CLI starts without the identification stack
    from pincal.identification import GateLimits, QualityVerdict

__all__ = ["apply_gate", "bootstrap_lines", "gate_limits"]


def gate_limits(max_change: str | None, significance: float | None = None) -> GateLimits:
    """:class:`GateLimits` from ``--max-change 'mm,rad'`` and ``--significance P``.

    ``--significance`` sets both the χ² test's (declared noise) and the
    misspecification probes' significance; None keeps the defaults (1e-3).

    Raises:
        click.BadParameter: not two positive numbers, or a significance outside (0, 0.5].
    """
    from pincal.errors import SolverOptionError
    from pincal.identification import GateLimits

    opts: dict[str, Any] = {}
    if max_change is not None:
        try:
            mm, rad = (float(v) for v in max_change.split(","))
            opts.update(max_length_change=mm * 1e-3, max_angle_change=rad)
            GateLimits(**opts)
        except (ValueError, SolverOptionError):
            raise click.BadParameter(
                "give 'length_mm,angle_rad', two numbers > 0, e.g. 20,0.1",
                param_hint="--max-change",
            ) from None
    if significance is not None:
        try:
            return GateLimits(
                **opts, chi2_significance=significance, probe_significance=significance
            )
        except SolverOptionError:
            raise click.BadParameter(
                f"{significance!r} is not a probability in (0, 0.5], e.g. 1e-3",
                param_hint="--significance",
            ) from None
    return GateLimits(**opts)


def apply_gate(verdict: QualityVerdict, force: bool, *, before_fit: bool = False) -> dict[str, Any]:
    """Print the verdict's warnings; refuse (raise) or record a forced override.

    Args:
        verdict: a :class:`pincal.identification.QualityVerdict`.
        force: ``--force`` was given: write anyway and say so.
        before_fit: the data check before fitting (its refusal stops before the fit).

    Returns:
        The verdict as JSON (``overridden`` True when forced past a refusal).

    Raises:
        QualityGateError: the verdict refuses and ``force`` is False.
    """
    if not verdict.passed and not force:
        raise QualityGateError(verdict.reason(), verdict)
    if before_fit:  # the verdict after fitting repeats the data's issues
        return verdict.to_dict(overridden=force)
    for issue in verdict.warnings:
        click.echo(f"pincal: warning: {issue.message}", err=True)
    if not verdict.passed:
        click.echo(
            "pincal: warning: --force: writing despite the quality gate: "
            + "; ".join(i.message for i in verdict.refusals),
            err=True,
        )
    return verdict.to_dict(overridden=force)


def bootstrap_lines(uncertainty: dict | None, top: int = 8) -> list[str]:
    """The printed bootstrap summary: per-parameter bootstrap σ beside the written σ.

    Lists the ``top`` parameters whose bootstrap σ differs most from the linear σ
    (lengths in µm, angles in µrad); empty without a bootstrap.
    """
    import math

    boot = (uncertainty or {}).get("bootstrap")
    if not boot:
        return []
    lin, sb = boot["linear_std"], boot["std"]
    lines = [f"parametric bootstrap ({boot['draws']} seeded refits, {boot['failed']} failed; "
             "beside, not written): σ [µm | µrad]"]  # fmt: skip
    if boot["draws"] < 2:
        return [*lines, "  the refits failed: no bootstrap σ"]
    rows = [(n, lin[n], sb.get(n)) for n in lin if sb.get(n) is not None and lin[n] > 0]
    rows.sort(key=lambda r: -abs(math.log(r[2] / r[1])) if r[2] > 0 else 0.0)
    lines.append(f"  {'parameter':32s} {'linear σ':>12s} {'bootstrap σ':>12s} {'ratio':>7s}")
    lines += [f"  {n:32s} {1e6 * a:12.4g} {1e6 * b:12.4g} {b / a:7.3f}" for n, a, b in rows[:top]]
    if len(rows) > top:
        lines.append(f"  … {len(rows) - top} more in calibration.json (quality.uncertainty."
                     "bootstrap)")  # fmt: skip
    return lines

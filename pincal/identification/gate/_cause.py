"""The likely cause of a refusal of the quality gate, named from what it measured.

The cause is chosen from the refusals actually found, in order of how directly they
explain the others: a frame offset, a singular pose, a few outliers, a fired
misspecification probe, a robust-fit breakdown, a χ² beyond the declared noise, an
estimated noise beyond the instrument profile, a joint zero moved (the joint readings
relative to another zero than declared: ``joint_reference``), a parameter change, a
registration change, and last an unfinished solve (often a consequence of the others). A
refusal names "the declared noise" only when noise was declared.
"""

from __future__ import annotations

import math

import numpy as np

from pincal.identification._verdict import QualityVerdict
from pincal.identification.gate._coordinate_probe import is_trend
from pincal.identification.results import IdentificationResult

__all__ = ["likely_cause"]

_FRAME_ANGLE = 0.05  # mean measured-vs-nominal rotation that names the frame [rad]


def likely_cause(v: QualityVerdict, result: IdentificationResult, m: int) -> tuple[str, str]:
    """(cause, one sentence with what to try) for a refused verdict over m poses."""
    lim = v.limits
    kinds = {i.kind for i in v.refusals}
    shifted = math.isfinite(v.frame_offset) and v.frame_offset > lim.max_length_change
    turned = math.isfinite(v.frame_rotation) and v.frame_rotation > _FRAME_ANGLE
    estimated = v.noise_source == "estimated"
    if (shifted or turned) and kinds & {"change", "chi2", "solver", "model", "noise"}:
        return "frame", (
            f"the measured poses are offset {v.frame_offset * 1e3:.4g} mm and turned "
            f"{v.frame_rotation:.3g} rad from the nominal model's: measured in an "
            "unregistered frame? Register the instrument to the machine base (pincal "
            "import-tracker) or fit the base frame."
        )
    if v.singular_poses:
        return "singular pose", (
            f"poses {list(v.singular_poses[:8])} are near a singular configuration; remove "
            "them or choose poses with `pincal poses`."
        )
    few = v.outlier_poses and len(v.outlier_poses) <= lim.max_downweighted * m
    if few and "outliers" in kinds:
        return "outliers", (
            f"poses {list(v.outlier_poses[:12])} do not fit the others; refit with "
            "--loss huber, or remove them."
        )
    if "model" in kinds and v.probes:
        alpha = lim.probe_significance / len(v.probes)
        hits = [p for p in v.probes if p[2] < alpha and p[1] >= lim.probe_explained]
        named = [p for p in hits if not is_trend(p[0])] or hits or list(v.probes)
        best = max(named, key=lambda p: p[1])  # a named error before a coordinate trend
        also = [f"{p[3]} ({p[1]:.0%})" for p in named if p is not best]
        return "model or instrument", (
            f"{best[3]} explains {best[1]:.0%} of the residual (F-test p = {best[2]:.2g})"
            + (f"; so do {', '.join(also)}, which these poses cannot tell apart" if also else "")
            + ": the model misses an error the data show, or the instrument is off. "
            + ("The residuals follow a pose coordinate: look for an error growing along it "
               "(guide straightness, encoder non-linearity, a range-dependent instrument "
               "error), or fit a larger --params preset." if is_trend(best[0]) else
               "Check the instrument's scale and the actuators' scales (encoder / "
               "lead-screw gains), look for drift, or fit a larger --params preset.")
        )  # fmt: skip
    if "breakdown" in kinds or ("outliers" in kinds and not few):
        return "units, frame or model", (
            "most poses disagree with the model: check the units, the measured frame and "
            "the model."
        )
    if "chi2" in kinds:
        worst = _worst_block(v)
        return "noise or model", (
            f"the {worst} are larger than the declared noise: the instrument is "
            "noisier than declared (check --noise, the file's '# noise:' or '# std:'), or the "
            "model misses an error the data show (check the measured frame and --params)."
        )
    if "noise" in kinds:
        return "instrument or model", (
            f"the noise estimated from the residuals exceeds what the {v.profile!r} "
            "profile typically reaches: the model misses an error the data show, or the "
            "instrument is off (check its calibration, or declare its real noise with --noise)."
        )
    zeros = _moved_zeros(result, lim.max_length_change, lim.max_angle_change)
    if "change" in kinds and zeros:
        return "joint reference", (
            f"joint zeros moved beyond the bound ({zeros}): the joint readings are probably "
            "relative to another zero than the declared joint_reference (a file's "
            "'# joint_reference:' header, the model's sidecar, a campaign's sockets "
            "section) — readings relative to the home pose need 'joint_reference: home', "
            "absolute readings none; if it is right, a large real error: check the model, "
            "or raise the bound with --max-change."
        )
    if "change" in kinds:
        return "parameter change", (
            "parameters moved further than the bound: a large real error, or directions "
            "the poses barely excite (see their 2σ); hold them (a smaller --params preset), "
            "add poses, or raise the bound with --max-change."
        )
    if "registration" in kinds:
        return "registration", (
            "the instrument frame or marker moved further than a registration error can "
            "explain: check the registration (frame, marker link) and its start values."
        )
    if "solver" in kinds:
        chi2 = float(result.reduced_chi2)
        judged = (
            f"with the noise estimated from the residuals (reduced χ² {chi2:.3g} by "
            "construction)"
            if estimated
            else f"at reduced χ² {chi2:.3g} against the declared noise"
        )
        # gauss-newton re-runs lm itself when it stops unconverged: suggest lm only
        # where it has not run
        tried = result.method == "lm" or "levenberg-marquardt from the start" in result.message
        try_lm = "" if tried else "try --method lm, or "
        return "solver", (
            f"the solver stopped before converging, {judged}: {try_lm}a smaller --params "
            "preset (parameters the poses barely excite converge slowly), or poses away "
            "from the workspace's edges and singularities."
        )
    return "data or model", "check the data, the measured frame and the model (--params)."


def _moved_zeros(result: IdentificationResult, length: float, angle: float) -> str:
    """The joint zeros (``JOINT.offset``) moved beyond the bound, worst first, in words.

    Args:
        result: the fit.
        length: the bound on a length change [m].
        angle: the bound on an angle change [rad].

    Returns:
        ``'wrist_2_joint.offset −0.261 rad, …'`` (at most three), '' when none moved so.
    """
    delta = np.asarray(result.full_values, dtype=float) - np.asarray(result.initial_values)
    moved = []
    for name, d, unit in zip(result.names, delta, result.units, strict=True):
        bound = angle if unit == "rad" else length
        if name.endswith(".offset") and not abs(d) <= bound:
            moved.append((abs(d) / bound, f"{name} {d:+.3g} {unit}"))
    moved.sort(reverse=True)
    return ", ".join(t for _, t in moved[:3]) + (" …" if len(moved) > 3 else "")


def _worst_block(v: QualityVerdict) -> str:
    if not v.chi2_blocks:
        return "residuals"
    b = max(v.chi2_blocks, key=lambda t: t[1] / t[2] if t[2] > 0 else 0.0)
    return (
        f"{b[0]} residuals (χ²/ν {b[1] / b[2]:.3g} on {b[2]:.0f} degrees of freedom, "
        f"p = {b[3]:.2g})"
    )

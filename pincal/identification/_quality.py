"""The quality gate: refuse a calibration that is silently wrong.

A fit can "converge" on data that cannot give a calibration: millimetres declared as
metres, a world frame that was never registered, gross outliers, a pose next to a
singularity. :func:`check_measurements` looks at the data before fitting (scale of the
measured positions against the nominal model's at the same poses, duplicate rows);
:func:`check_quality` judges the result (solver success, reduced χ² against the declared
noise, size of the parameter changes, outlying poses, robust-fit breakdown, poses of
outsized sensitivity). Both return a :class:`QualityVerdict`: issues that refuse the
calibration, warnings, and the likely cause named once (``units``, ``frame``,
``outliers``, ``singular pose``, ``noise or model``).

Thresholds (:class:`GateLimits`, defaults):

- reduced χ² > 100 with declared noise (residual RMS 10× the declared σ) refuses;
  < 0.01 warns (the declared noise is 10× too large);
- a parameter moving by more than 20 mm (lengths) or 0.1 rad (angles) refuses;
- measured positions whose spread about their centroid is outside ½–2× the nominal
  model's at the same actuator values (and differs from it by more than 2 mm) refuse
  before fitting (a known unit ratio — 1000, 0.001, 10, 0.1, 1/25.4… — is named);
- a pose is an outlier when one of its residuals — whitened, studentised by its
  leverage and divided by the robust (MAD) scale of its block — exceeds
  ``max(5, Φ⁻¹(1 − 1e-3 / 2N))`` (5σ, or the Bonferroni bound of family-wise risk 1e-3
  over N equations when larger: 5.3 for 10 000); outliers refuse a least-squares fit
  and are listed for a robust one;
- a robust fit that down-weights more than 25 % of the poses has broken down (refuses);
- a pose whose whitened sensitivity (norm of its Jacobian block) exceeds 100× the
  median pose's is near a singular configuration: it dominates the fit with a leverage
  near 1, so its errors cannot show in the residuals (refuses).
"""

from __future__ import annotations

import math
from dataclasses import replace
from statistics import NormalDist

import numpy as np

from pincal.errors import PincalError
from pincal.identification._data_check import check_measurements
from pincal.identification._result import IdentificationResult
from pincal.identification._verdict import GateLimits, QualityIssue, QualityVerdict
from pincal.identification._weighting import hat_diagonal
from pincal.measure._measurements import Measurements
from pincal.model._mechanism import Mechanism

__all__ = ["check_quality", "outlier_poses"]

_MAD = 1.4826  # σ of a Gaussian per median absolute deviation
_FRAME_ANGLE = 0.05  # mean measured-vs-nominal rotation that names the frame [rad]
_MIN_LIMIT = 5.0  # smallest outlier threshold [robust σ]
_EXACT = 1e-9  # residuals below this [m, rad] are exact data: no outlier test


def outlier_poses(
    result: IdentificationResult, risk: float = 1e-3, leverage: np.ndarray | None = None
) -> tuple[tuple[int, ...], float]:
    """Poses with a residual beyond the Bonferroni limit of the normalised residuals.

    The whitened residuals r/σ are studentised by ``√(1 − h)`` (``h`` the leverage of
    each equation, when given) and divided by their robust scale per block (position,
    orientation), 1.4826·median|·|, so outliers cannot hide by inflating an estimated σ;
    a pose is flagged when one of its residuals exceeds ``max(5, Φ⁻¹(1 − risk / 2N))``
    (N equations).

    Args:
        result: an identification result with its weighting.
        risk: family-wise false-alarm probability over the N equations.
        leverage: (m, k) hat-matrix diagonal of the whitened fit, or None.

    Returns:
        (flagged pose indices, the threshold); ``((), nan)`` without weights or for data
        fitted exactly.
    """
    w = result.weighting
    if w is None or w.whitened.size == 0:
        return (), float("nan")
    z = np.asarray(w.whitened, dtype=float)
    raw = np.asarray(result.residuals, dtype=float)
    if raw.shape != z.shape or not np.all(np.isfinite(z)) or np.max(np.abs(raw)) < _EXACT:
        return (), float("nan")
    if leverage is not None and leverage.shape == z.shape:
        z = z / np.sqrt(np.clip(1.0 - leverage, 0.05, 1.0))
    k = z.shape[1]
    blocks = [list(range(min(3, k))), list(range(3, k))] if k == 6 else [list(range(k))]
    u = np.zeros_like(z)
    for cols in blocks:
        scale = _MAD * float(np.median(np.abs(z[:, cols])))
        if scale > 0:
            u[:, cols] = z[:, cols] / scale
    limit = max(_MIN_LIMIT, -NormalDist().inv_cdf(risk / (2 * z.size)))
    bad = np.flatnonzero(np.any(np.abs(u) > limit, axis=1))
    return tuple(int(i) for i in bad), limit


def _whitened_jacobian(
    result: IdentificationResult, mech: Mechanism | None, meas: Measurements | None
) -> np.ndarray | None:
    """(m, k, p) Jacobian of the identified parameters, whitened by the fit's σ, or None."""
    w = result.weighting
    if mech is None or meas is None or result.parameter_set is None or w is None:
        return None
    from pincal.sensitivity._jacobian import identification_jacobian

    try:
        J = identification_jacobian(mech, result.parameter_set, meas.q_act,
                                    result.full_values, meas.components)  # fmt: skip
    except PincalError:
        return None
    m, k = len(meas), len(meas.components)
    raw, z = np.asarray(result.residuals), np.asarray(w.whitened)
    if raw.shape != (m, k) or z.shape != (m, k):
        return None
    with np.errstate(divide="ignore", invalid="ignore"):
        sigma = np.abs(raw / z)
    good = np.isfinite(sigma) & (sigma > 0)
    typical = [float(np.median(sigma[good[:, j], j])) if good[:, j].any() else 1.0
               for j in range(k)]  # fmt: skip
    sigma = np.where(good, sigma, np.array(typical)[None, :])
    return J[:, result.identified].reshape(m, k, -1) / sigma[:, :, None]


def _singular(Jw: np.ndarray | None, ratio: float) -> tuple[int, ...]:
    """Poses whose whitened sensitivity exceeds ``ratio`` × the median pose's."""
    if Jw is None or Jw.shape[0] < 3:
        return ()
    size = np.linalg.norm(Jw, axis=(1, 2))
    med = float(np.median(size))
    if not med > 0:
        return ()
    return tuple(int(i) for i in np.flatnonzero(size > ratio * med))


def _changes(result: IdentificationResult, lim: GateLimits) -> QualityIssue | None:
    d = np.abs(np.asarray(result.full_values) - np.asarray(result.initial_values))
    units = np.asarray(result.units)
    bound = np.where(units == "rad", lim.max_angle_change, lim.max_length_change)
    over = np.flatnonzero((d > bound) | ~np.isfinite(d))
    if over.size == 0:
        return None
    worst = int(over[np.argmax(d[over] / bound[over])])
    size = (
        f"{d[worst]:.3g} rad" if units[worst] == "rad" else f"{d[worst] * 1e3:.4g} mm"
    )
    return QualityIssue(
        "change", True,
        f"{over.size} parameters moved beyond {lim.max_length_change * 1e3:g} mm / "
        f"{lim.max_angle_change:g} rad (worst {result.names[worst]}: {size}; change the "
        "bound with --max-change)",
    )  # fmt: skip


def check_quality(
    result: IdentificationResult,
    measurements: Measurements | None = None,
    *,
    mech: Mechanism | None = None,
    data: QualityVerdict | None = None,
    limits: GateLimits | None = None,
    scalar_instrument: bool = False,
) -> QualityVerdict:
    """Judge an identification result; refusals mean: do not write this calibration.

    Args:
        result: the identification result.
        measurements: the fitted measurements (for the pose-sensitivity test and, with
            ``mech``, the data checks of :func:`check_measurements`).
        mech: the nominal mechanism the result was identified on.
        data: the verdict of :func:`check_measurements` on the same data (computed here
            when None and both ``mech`` and ``measurements`` are given).
        limits: thresholds (default :class:`GateLimits`, or ``data``'s).
        scalar_instrument: the result is a ballbar / probe / plane / gauge fit, whose
            near-gauge directions (an instrument pivot against a translation of the
            machine) let parameters drift and the solver stop at its iteration limit
            without changing the fit: with a reduced χ² within the limit, parameter
            changes and an unfinished solve are warnings, not refusals.

    Returns:
        QualityVerdict with the data issues first, then the result's.
    """
    lim = limits or (data.limits if data is not None else GateLimits())
    if data is None and mech is not None and measurements is not None:
        data = check_measurements(mech, measurements, limits=lim)
    data = data or QualityVerdict(limits=lim)
    issues = list(data.issues)
    w = result.weighting
    loss = w.loss if w is not None else "linear"
    robust = loss != "linear"
    down = w.downweighted if w is not None else ()
    Jw = _whitened_jacobian(result, mech, measurements)
    lev = None
    if Jw is not None:
        lev = hat_diagonal(Jw.reshape(-1, Jw.shape[2])).reshape(Jw.shape[:2])
    out, limit = outlier_poses(result, lim.outlier_risk, lev)
    m = int(np.asarray(result.residuals).shape[0])
    singular = _singular(Jw, lim.singular_ratio)
    declared = w is not None and w.source in ("declared", "per-pose")
    chi2 = float(result.reduced_chi2)
    lenient = scalar_instrument and chi2 <= lim.max_reduced_chi2
    if not result.success:
        issues.append(QualityIssue(
            "solver", not lenient, f"the solver did not succeed ({result.message.strip()[:160]})"
        ))  # fmt: skip
    if w is not None and declared and robust and out:
        keep = np.setdiff1d(np.arange(m), out)  # a robust fit is judged on its inliers
        z = np.asarray(w.whitened)[keep]
        chi2 = float(np.sum(z**2)) / max(z.size - int(result.identified.sum()), 1)
    if declared and not chi2 <= lim.max_reduced_chi2:
        issues.append(QualityIssue(
            "chi2", True,
            f"reduced χ² {chi2:.3g} > {lim.max_reduced_chi2:g} with the declared noise "
            f"(residual RMS {math.sqrt(chi2) if math.isfinite(chi2) else chi2:.3g}× σ)",
        ))  # fmt: skip
    elif declared and chi2 < 1e-2:
        issues.append(QualityIssue(
            "low-chi2", False,
            f"reduced χ² {chi2:.3g} < 0.01: the declared noise is 10× larger than the "
            "residuals; the reported σ are pessimistic",
        ))  # fmt: skip
    change = _changes(result, lim)
    if change is not None:
        issues.append(replace(change, refuse=not lenient))
    if out:
        shown = ", ".join(map(str, out[:12])) + (" …" if len(out) > 12 else "")
        text = (
            f"{len(out)} of {m} poses are outliers (normalised residual > {limit:.2f}: "
            f"poses {shown})"
        )
        if len(out) > lim.max_downweighted * m:
            text += ": too many for outliers, the residuals are not noise (model, units, frame?)"
            issues.append(QualityIssue("outliers", not robust, text))
        elif robust:
            issues.append(QualityIssue("outliers", False, text + f"; down-weighted by {loss}"))
        else:
            issues.append(QualityIssue("outliers", True, text + "; refit with --method lm "
                                       "--loss huber or remove them"))  # fmt: skip
    if robust and m and len(down) > lim.max_downweighted * m:
        issues.append(QualityIssue(
            "breakdown", True,
            f"the {loss} loss down-weighted {len(down)} of {m} poses (more than "
            f"{lim.max_downweighted:.0%}): the fit follows a subset of the data",
        ))  # fmt: skip
    if singular:
        issues.append(QualityIssue(
            "singular", True,
            f"poses {list(singular[:8])} are more than {lim.singular_ratio:g}× as sensitive as "
            "the median pose (near a singular configuration): they dominate the fit and "
            "their errors cannot show in the residuals",
        ))  # fmt: skip
    verdict = replace(data, issues=tuple(issues), outlier_poses=out, outlier_limit=limit,
                      singular_poses=singular, limits=lim)  # fmt: skip
    if verdict.passed:
        return replace(verdict, cause="", cause_text="")
    if data.cause:
        return verdict
    cause, text = _cause(verdict, result, m)
    return replace(verdict, cause=cause, cause_text=text)


def _cause(v: QualityVerdict, result: IdentificationResult, m: int) -> tuple[str, str]:
    """The likely cause of a refusal, in order: frame, singular pose, outliers, else."""
    lim = v.limits
    kinds = {i.kind for i in v.refusals}
    shifted = math.isfinite(v.frame_offset) and v.frame_offset > lim.max_length_change
    turned = math.isfinite(v.frame_rotation) and v.frame_rotation > _FRAME_ANGLE
    if (shifted or turned) and kinds & {"change", "chi2", "solver"}:
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
    if v.outlier_poses and len(v.outlier_poses) <= lim.max_downweighted * m:
        return "outliers", (
            f"poses {list(v.outlier_poses[:12])} do not fit the others; refit with "
            "--method lm --loss huber, or remove them."
        )
    if "breakdown" in kinds:
        return "units, frame or model", (
            "most poses disagree with the model: check the units, the measured frame and "
            "the model."
        )
    return "noise or model", (
        "the residuals are much larger than the declared noise or the solver failed: check "
        "the declared noise (--noise), the measured frame and the model (--params)."
    )

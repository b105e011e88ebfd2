"""The quality gate: refuse a calibration that is silently wrong.

A fit can "converge" on data that cannot give a calibration: millimetres declared as
metres, a world frame that was never registered, gross outliers, a pose next to a
singularity — or on a model that is wrong: an instrument scale, an actuator gain the
model lacks, a noise larger than declared. :func:`check_measurements` looks at the data
before fitting (scale of the measured positions against the nominal model's at the same
poses, duplicate rows); :func:`check_quality` judges the result (solver success, χ²
against the declared noise, misspecification probes, estimated noise against the
instrument's profile, parameter changes, outlying poses, robust-fit breakdown, poses of
outsized sensitivity). Both return a :class:`QualityVerdict`: issues that refuse the
calibration, warnings, and the likely cause named once, from what was measured
(:mod:`pincal.identification.gate._cause`). See ``docs/quality_gate.md`` for the measured
false-alarm and detection rates.

Thresholds (:class:`GateLimits`, defaults):

- declared noise: a block (position, orientation) whose χ² has a p-value for χ²(ν_b)
  below 1e-3 *and* χ²/ν_b > 1.5 refuses (ν_b the block's redundancy), as does a reduced
  χ² > 100 whatever its p-value; a reduced χ² < 0.01 warns (the noise is 10× too large);
- misspecification probes (any noise): a global scale of the measured positions, a
  gain per actuator, a linear drift over the pose order and low-order trends along
  each pose coordinate (``trend:``, :mod:`._coordinate_probe`) are added to the
  linearised fit; one whose F-test p-value is below 1e-3 / (number of probes) *and* that explains
  ≥ 25 % of the residual of the blocks it acts on refuses ("model or instrument error
  suspected", :mod:`pincal.identification.gate._misspecification`);
- estimated noise with an instrument profile (``--instrument``, ``# instrument:``):
  σ̂ above 3× the profile's typical σ refuses (:mod:`._instrument_profiles`);
- a machine parameter moving by more than 20 mm (lengths) or 0.1 rad (angles) refuses;
  registration unknowns (the ``base_frame`` / ``tool_frame`` joints: instrument frame,
  marker) have their own bound, 1 m / π rad (a rough registration moves them far);
- measured positions whose spread about their centroid is outside ½–2× the nominal
  model's at the same actuator values (and differs from it by more than 2 mm) refuse
  before fitting (a known unit ratio — 1000, 0.001, 10, 0.1, 1/25.4… — is named);
- outliers by deletion (:mod:`pincal.identification.gate._outliers`): the pose whose
  deleted (leave-one-out) residual is largest against the others' scale is named when
  its F(k, ν − k) statistic passes the Bonferroni bound of family-wise risk 1e-3 over
  the m poses, removed, and the search repeated; they refuse a least-squares fit and
  are listed for a robust one (without a measured model, the older per-equation MAD
  test of :func:`outlier_poses` is used);
- a robust fit that down-weights more than 25 % of the poses has broken down (refuses);
- a pose whose whitened sensitivity (norm of its Jacobian block) exceeds 100× the
  median pose's is near a singular configuration: it dominates the fit with a leverage
  near 1, so its errors cannot show in the residuals (refuses).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from functools import partial
from statistics import NormalDist

import numpy as np

from pincal.errors import PincalError
from pincal.identification._verdict import GateLimits, QualityIssue, QualityVerdict
from pincal.identification.gate._autocorrelation import SerialCorrelation, serial_correlation
from pincal.identification.gate._cause import likely_cause
from pincal.identification.gate._coordinate_probe import is_trend
from pincal.identification.gate._data_check import check_measurements
from pincal.identification.gate._fit_issues import changes, chi2_issues, left_misfit, profile_issues
from pincal.identification.gate._instrument_profiles import InstrumentProfile, instrument_profile
from pincal.identification.gate._misspecification import (
    Probe,
    chi2_blocks,
    instrument_chi2,
    probe_columns,
    probe_misspecification,
)
from pincal.identification.gate._outlier_refit import confirm_outliers
from pincal.identification.gate._outliers import deletion_outliers
from pincal.identification.results import IdentificationResult
from pincal.measure import Measurements
from pincal.model import Mechanism
from pincal.sensitivity import identification_jacobian

__all__ = ["ConfirmOutliers", "check_quality", "outlier_poses"]

#: (named, risk, cap) → (named, bound, whitened A (m, k, p), z (m, k), σ (m, k)) or None
ConfirmOutliers = Callable[
    [tuple[int, ...], float, int],
    tuple[tuple[int, ...], float, np.ndarray, np.ndarray, np.ndarray] | None,
]

_MAD = 1.4826  # σ of a Gaussian per median absolute deviation
_MIN_LIMIT = 5.0  # smallest outlier threshold [robust σ]
_EXACT = 1e-9  # residuals below this [m, rad] are exact data: no outlier test
_EXACT_RMS = 1e-7  # residual RMS below this [m, rad]: fitted to the solver's precision


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


def _sigma(result: IdentificationResult) -> np.ndarray | None:
    """(m, k) σ of each residual of the fit [m, rad], from raw / whitened, or None."""
    w = result.weighting
    if w is None:
        return None
    raw, z = np.asarray(result.residuals), np.asarray(w.whitened)
    if raw.shape != z.shape or raw.ndim != 2 or raw.size == 0:
        return None
    with np.errstate(divide="ignore", invalid="ignore"):
        sigma = np.abs(raw / z)
    good = np.isfinite(sigma) & (sigma > 0)
    typical = [float(np.median(sigma[good[:, j], j])) if good[:, j].any() else 1.0
               for j in range(raw.shape[1])]  # fmt: skip
    return np.where(good, sigma, np.array(typical)[None, :])


def _whitened_jacobian(
    result: IdentificationResult,
    mech: Mechanism | None,
    meas: Measurements | None,
    sigma: np.ndarray | None,
) -> np.ndarray | None:
    """(m, k, p) Jacobian of the identified parameters, whitened by the fit's σ, or None."""
    if mech is None or meas is None or sigma is None:
        return None

    try:
        J = identification_jacobian(mech, result.parameter_set, meas.q_act,
                                    result.full_values, meas.components)  # fmt: skip
    except PincalError:
        return None
    m, k = len(meas), len(meas.components)
    if sigma.shape != (m, k):
        return None
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


def check_quality(
    result: IdentificationResult,
    measurements: Measurements | None = None,
    *,
    mech: Mechanism | None = None,
    data: QualityVerdict | None = None,
    limits: GateLimits | None = None,
    scalar_instrument: bool = False,
    instrument: str | InstrumentProfile | None = None,
    jacobian: np.ndarray | None = None,
    confirm: ConfirmOutliers | None = None,
) -> QualityVerdict:
    """Judge an identification result; refusals mean: do not write this calibration.

    Args:
        result: the identification result.
        measurements: the fitted measurements (for the pose-sensitivity test, the
            deletion outlier test, the misspecification probes and, with ``mech``, the
            data checks of :func:`check_measurements`).
        mech: the nominal mechanism the result was identified on.
        data: the verdict of :func:`check_measurements` on the same data (computed here
            when None and both ``mech`` and ``measurements`` are given).
        limits: thresholds (default :class:`GateLimits`, or ``data``'s).
        scalar_instrument: the result is an instrument-file fit (ballbar, probe, plane,
            sockets…): its χ² is judged against the files' σ (the result's
            ``redundancy`` annotation gives ν), not by the misspecification probes.
            Parameter changes and an unfinished solve refuse as on the pose route — a
            change within 3σ of its own uncertainty only warns (``changes``) — (they
            were warnings once: the directions near a gauge that let parameters drift
            are now held at nominal by the fit's placement bound, and a wrong
            ``joint_reference`` fits as well as the right one with ≈ 300 mm changes).
        instrument: the instrument's profile (or its name, see
            :data:`INSTRUMENT_PROFILES`): with estimated noise, a σ̂ beyond
            ``limits.noise_factor`` × its typical σ refuses.
        jacobian: (m, k, p) whitened Jacobian of the fitted parameters, for fits whose
            Jacobian cannot be built from ``measurements`` (instrument files; see
            :func:`pincal.identification.instrument_gate`).
        confirm: ``confirm(named, risk, cap)``, the refit that confirms the poses the
            deletion test named (for fits ``measurements`` cannot refit: instrument
            files); it returns what :func:`confirm_outliers` returns, or None to keep
            the first answer. Default: :func:`confirm_outliers` with ``mech`` and
            ``measurements``.

    Returns:
        QualityVerdict with the data issues first, then the result's.

    Raises:
        UnknownNameError: ``instrument`` names no profile.
    """
    lim = limits or (data.limits if data is not None else GateLimits())
    profile = instrument_profile(instrument) if isinstance(instrument, str) else instrument
    if data is None and mech is not None and measurements is not None:
        data = check_measurements(mech, measurements, limits=lim)
    data = data or QualityVerdict(limits=lim)
    issues = list(data.issues)
    w = result.weighting
    loss = w.loss if w is not None else "linear"
    robust = loss != "linear"
    down = w.downweighted if w is not None else ()
    sigma = _sigma(result)
    Jw = _whitened_jacobian(result, mech, measurements, sigma)
    if Jw is None and jacobian is not None:
        Jw = jacobian
    m = int(np.asarray(result.residuals).shape[0])
    source = "" if w is None else ("estimated" if w.source.startswith("estimate") else w.source)
    declared = source in ("declared", "per-pose")
    cap = int(lim.max_downweighted * m)
    probes: list[Probe] = []
    fired: Probe | None = None
    unexplained = ""  # the misfit a refit without the named poses leaves, in words
    stand_out: tuple[int, ...] = ()  # those poses, then not named outliers
    serial: SerialCorrelation | None = None  # correlation left once a drift is fitted
    if Jw is not None and sigma is not None and w is not None and _inexact(result):
        z = np.asarray(w.whitened, dtype=float)
        out, limit = deletion_outliers(Jw, z, lim.outlier_risk, cap)
        Ap, zp, sp = Jw, z, sigma  # the probes' linearisation: at the refit without outliers
        if confirm is None and measurements is not None and mech is not None:
            confirm = partial(confirm_outliers, result, mech, measurements)
        if out and len(out) <= cap and confirm is not None:
            again = confirm(out, lim.outlier_risk, cap)
            out, limit, Ap, zp, sp = again or (out, limit, Jw, z, sigma)
            unexplained = left_misfit(Ap, zp, out, lim) if again and out and declared else ""
            if unexplained:  # they stand out of a misfit, they do not cause it
                stand_out, out = tuple(out), ()
        if not scalar_instrument and measurements is not None:
            rows = np.setdiff1d(np.arange(m), out) if len(out) <= cap else np.arange(m)
            cols = probe_columns(result, measurements)
            probes = probe_misspecification(
                Ap[rows].reshape(-1, Ap.shape[2]), zp[rows].ravel(),
                {n: c[rows] for n, c in cols.items()}, sp[rows], measurements.components,
                lim.probe_significance, lim.probe_explained,
            )  # fmt: skip
            alpha = lim.probe_significance / max(len(probes), 1)
            hits = [p for p in probes if p.p_value < alpha and p.explained >= lim.probe_explained]
            named = [p for p in hits if not is_trend(p.name)] or hits  # a named error first
            fired = max(named, key=lambda p: p.explained) if named else None
            if "drift" in cols:  # AR(1) residuals are not a drift: what a drift leaves
                drift = cols["drift"][rows] / sp[rows][:, :, None]
                serial = serial_correlation(Ap[rows], zp[rows], drift)
                serial = serial if serial and serial.p_value < alpha else None
            if fired is not None:  # judge outliers against the model with the probe's terms
                extra = cols[fired.name] / sp[:, :, None]
                out, limit = deletion_outliers(np.concatenate([Ap, extra], axis=2), zp,
                                               lim.outlier_risk, cap)  # fmt: skip
    elif Jw is None:
        out, limit = outlier_poses(result, lim.outlier_risk)
    else:
        out, limit = (), float("nan")
    singular = _singular(Jw, lim.singular_ratio)
    chi2 = float(result.reduced_chi2)
    inliers = None
    if w is not None and declared and robust and out:
        inliers = np.setdiff1d(np.arange(m), out)  # a robust fit is judged on its inliers
        zi = np.asarray(w.whitened)[inliers]
        chi2 = float(np.sum(zi**2)) / max(zi.size - int(result.identified.sum()), 1)
    if scalar_instrument:  # judged against the instrument file's std
        blocks, declared = instrument_chi2(result), True
    else:
        comps = None if measurements is None else tuple(measurements.components)
        blocks = chi2_blocks(result, comps, inliers) if declared else []
    fit_issues = chi2_issues(chi2, blocks, declared, lim)
    if not result.success:
        issues.append(QualityIssue(
            "solver", True, f"the solver did not succeed ({result.message.strip()[:160]})"
        ))  # fmt: skip
    issues += fit_issues
    if profile is not None and source == "estimated" and w is not None:
        issues += profile_issues(w, profile, lim)
    issues += changes(result, lim)
    if serial is not None:  # refuses when a probe fired on it, warns otherwise
        issues.append(QualityIssue("model", fired is not None, serial.describe()))
    if fired is not None and (serial is None or fired.name != "drift"):
        issues.append(QualityIssue(
            "model", True, f"model or instrument error suspected: {fired.describe()}"
        ))  # fmt: skip
    if out:
        shown = ", ".join(map(str, out[:12])) + (" …" if len(out) > 12 else "")
        text = (
            f"{len(out)} of {m} poses are outliers (normalised residual > {limit:.2f}: "
            f"poses {shown})"
        )
        if fired is not None:  # judged with the probe's term, yet the model error remains
            text += f"; judge them again once the {fired.name} error is fixed"
            issues.append(QualityIssue("outliers", False, text))
        elif len(out) > cap:
            text += ": too many for outliers, the residuals are not noise (model, units, frame?)"
            issues.append(QualityIssue("outliers", not robust, text))
        elif robust:
            issues.append(QualityIssue("outliers", False, text + f"; down-weighted by {loss}"))
        else:
            issues.append(QualityIssue("outliers", True, text + "; refit with --method lm "
                                       "--loss huber or remove them"))  # fmt: skip
    if unexplained:
        shown = ", ".join(map(str, stand_out[:12])) + (" …" if len(stand_out) > 12 else "")
        issues.append(QualityIssue("outliers", False, f"poses {shown} stand out, but "
                                   f"{unexplained}"))  # fmt: skip
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
    verdict = replace(
        data, issues=tuple(issues), outlier_poses=out, outlier_limit=limit,
        singular_poses=singular, limits=lim, noise_source=source,
        chi2_blocks=tuple((b.block, b.chi2, b.dof, b.p_value) for b in blocks),
        probes=tuple((p.name, p.explained, p.p_value, p.size) for p in probes),
        floors=tuple((p.name, p.floor, p.floor_text()) for p in probes if p.floor_text()),
        profile=profile.name if profile is not None else "",
    )  # fmt: skip
    if verdict.passed:
        return replace(verdict, cause="", cause_text="")
    if data.cause:
        return verdict
    cause, text = likely_cause(verdict, result, m)
    return replace(verdict, cause=cause, cause_text=text)


def _inexact(result: IdentificationResult) -> bool:
    """False for data fitted to the solver's precision: no statistics of noise there."""
    raw = np.asarray(result.residuals, dtype=float)
    return raw.size > 0 and bool(np.all(np.isfinite(raw))) and float(
        np.sqrt(np.mean(raw**2))) > _EXACT_RMS  # fmt: skip

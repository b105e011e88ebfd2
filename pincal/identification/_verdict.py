"""The verdict of the quality gate: thresholds, issues, likely cause.

See :mod:`pincal.identification.gate._quality` for what is checked and the default
thresholds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from pincal.identification._options import check_real

__all__ = ["GateLimits", "QualityIssue", "QualityVerdict"]


@dataclass(frozen=True)
class GateLimits:
    """Thresholds of the quality gate.

    Attributes:
        max_reduced_chi2: with declared noise, a reduced χ² above this refuses (> 1),
            whatever its p-value.
        chi2_significance: with declared noise, a block (position, orientation) whose
            χ² has an upper-tail p-value for χ²(ν) below this refuses (0 < · < 0.5) …
        min_chi2_ratio: … when its χ²/ν also exceeds this (≥ 1: a 5 % misfit on 10⁵
            equations is significant but harmless).
        probe_significance: family-wise p-value of the misspecification probes (scale,
            gains, drift, coordinate trends; Bonferroni over the probes run) below which
            a probe fires …
        probe_explained: … when it also explains at least this share of the residual
            sum of squares (0 < · < 1).
        noise_factor: with estimated noise and a named instrument profile, a σ̂ above
            this multiple of the profile's typical σ refuses (> 1).
        max_length_change: largest accepted change of a length parameter [m] (> 0).
        max_angle_change: largest accepted change of an angle parameter [rad] (> 0).
        outlier_risk: family-wise false-alarm probability of the outlier test over all
            equations (0 < risk < 1).
        max_downweighted: largest fraction of poses a robust loss may down-weight.
        scale_band: measured / nominal position spread accepted before fitting is
            [1/band, band] (> 1).
        singular_ratio: a pose whose whitened sensitivity exceeds this multiple of the
            median pose's is called near-singular (> 1).
        registration_joints: joints whose parameters are registration unknowns (the
            instrument frame, the marker / tool offset), judged by their own bounds.
        max_registration_length: largest accepted change of a registration length [m].
        max_registration_angle: largest accepted change of a registration angle [rad].
    """

    max_reduced_chi2: float = 100.0
    max_length_change: float = 0.02
    max_angle_change: float = 0.1
    outlier_risk: float = 1e-3
    max_downweighted: float = 0.25
    scale_band: float = 2.0
    singular_ratio: float = 100.0
    chi2_significance: float = 1e-3
    min_chi2_ratio: float = 1.5
    probe_significance: float = 1e-3
    probe_explained: float = 0.25
    noise_factor: float = 3.0
    registration_joints: tuple[str, ...] = ("base_frame", "tool_frame")
    max_registration_length: float = 1.0
    max_registration_angle: float = math.pi

    def __post_init__(self) -> None:
        o = type(self).__name__
        check_real(o, "max_reduced_chi2", self.max_reduced_chi2, 1.0, open_low=True)
        check_real(o, "max_length_change", self.max_length_change, 0.0, open_low=True)
        check_real(o, "max_angle_change", self.max_angle_change, 0.0, open_low=True)
        check_real(o, "outlier_risk", self.outlier_risk, 0.0, 0.5, open_low=True)
        check_real(o, "max_downweighted", self.max_downweighted, 0.0, 1.0, open_low=True)
        check_real(o, "scale_band", self.scale_band, 1.0, open_low=True)
        check_real(o, "singular_ratio", self.singular_ratio, 1.0, open_low=True)
        check_real(o, "chi2_significance", self.chi2_significance, 0.0, 0.5, open_low=True)
        check_real(o, "min_chi2_ratio", self.min_chi2_ratio, 1.0)
        check_real(o, "probe_significance", self.probe_significance, 0.0, 0.5, open_low=True)
        check_real(o, "probe_explained", self.probe_explained, 0.0, 1.0, open_low=True)
        check_real(o, "noise_factor", self.noise_factor, 1.0, open_low=True)
        check_real(o, "max_registration_length", self.max_registration_length, 0.0,
                   open_low=True)  # fmt: skip
        check_real(o, "max_registration_angle", self.max_registration_angle, 0.0,
                   open_low=True)  # fmt: skip


@dataclass(frozen=True)
class QualityIssue:
    """One finding of the gate.

    Attributes:
        kind: ``units``, ``duplicates``, ``solver``, ``chi2``, ``low-chi2``, ``change``,
            ``registration``, ``model`` (a misspecification probe fired), ``noise``
            (σ̂ beyond the instrument profile), ``outliers``, ``breakdown`` or
            ``singular``.
        refuse: True when it refuses the calibration (else a warning).
        message: one line saying what was found, with the threshold.
    """

    kind: str
    refuse: bool
    message: str


#: what a pose file can do about the probes' blind spot
NOISE_REMEDY = (
    "declare the instrument noise (--noise, # noise:) so that the χ² test and the probes "
    "judge the fit against it, or name the instrument (--instrument, # instrument:) so that "
    "σ̂ is held to its typical σ"
)
#: the same when an instrument profile is named (σ̂ already bounded by it)
PROFILE_REMEDY = "declare the instrument noise (--noise, # noise:) to judge the fit against it"


@dataclass(frozen=True)
class QualityVerdict:
    """What the gate found; :attr:`passed` is False when a calibration must not be written.

    Attributes:
        issues: refusals and warnings, in the order found.
        cause: the likely cause of a refusal: ``units``, ``frame``, ``outliers``,
            ``singular pose``, ``model or instrument``, ``noise or model``, ``solver``,
            ``joint reference``, ``parameter change``, ``units, frame or model`` ("" when passed).
        cause_text: one sentence explaining the cause and what to try.
        outlier_poses: indices of the poses flagged as outliers.
        outlier_limit: the normalised-residual threshold used (NaN when not tested).
        duplicate_rows: (copy, original) row index pairs of exact duplicates.
        scale_ratio: measured / nominal spread of the positions (NaN when not checked).
        likely_unit: the length unit the data seem to be in, when the ratio names one.
        singular_poses: indices of poses of outsized sensitivity.
        frame_offset: distance between the centroids of the measured and nominal
            positions [m] (NaN when not checked).
        frame_rotation: angle of the mean rotation from the nominal to the measured
            orientations, in the world frame [rad] (NaN when not checked).
        limits: the thresholds used.
        noise_source: ``declared``, ``per-pose`` or ``estimated`` ("" when unknown).
        chi2_blocks: per block ``(name, χ², ν, p-value)`` (declared noise only).
        probes: per misspecification probe ``(name, explained share, p-value, size)``.
        floors: per probe ``(name, floor, in words)``: the smallest error of its kind it
            catches with 90 % power on this design and noise (a scale or gain as a
            fraction, a drift or trend in m; :mod:`._probe_floor`).
        profile: the instrument profile the estimated noise was compared with ("").
        held_out: the held-out evidence that judged a fit with estimated noise
            (:meth:`HeldOutEvidence.to_dict`), or None.
    """

    issues: tuple[QualityIssue, ...] = ()
    cause: str = ""
    cause_text: str = ""
    outlier_poses: tuple[int, ...] = ()
    outlier_limit: float = float("nan")
    duplicate_rows: tuple[tuple[int, int], ...] = ()
    scale_ratio: float = float("nan")
    likely_unit: str | None = None
    singular_poses: tuple[int, ...] = ()
    frame_offset: float = float("nan")
    frame_rotation: float = float("nan")
    limits: GateLimits = field(default_factory=GateLimits)
    noise_source: str = ""
    chi2_blocks: tuple[tuple[str, float, float, float], ...] = ()
    probes: tuple[tuple[str, float, float, str], ...] = ()
    floors: tuple[tuple[str, float, str], ...] = ()
    profile: str = ""
    held_out: dict[str, Any] | None = None

    @property
    def passed(self) -> bool:
        """True when no issue refuses the calibration."""
        return not self.refusals

    @property
    def refusals(self) -> tuple[QualityIssue, ...]:
        """The issues that refuse the calibration."""
        return tuple(i for i in self.issues if i.refuse)

    @property
    def warnings(self) -> tuple[QualityIssue, ...]:
        """The issues that only warn."""
        return tuple(i for i in self.issues if not i.refuse)

    def blind_spot(self, remedy: str = NOISE_REMEDY) -> str:
        """With estimated noise, the smooth errors the probes would not see ("" otherwise).

        σ̂ absorbs a model error the probes miss: one that none of them spans (an axis
        tilt, backlash, a periodic screw error) at any size — it only raises σ̂ — and
        those they span below their floors. The sentence says so, names the scale, drift
        and the largest gain and trend floors, and what to do (``remedy``: the route's
        way to see them; with a named instrument profile σ̂ is bounded by it, said).
        """
        if self.noise_source != "estimated" or not self.floors:
            return ""
        if self.profile:
            if remedy == NOISE_REMEDY:
                remedy = PROFILE_REMEDY
            passes = (
                f"while it keeps σ̂ within {self.limits.noise_factor:g}× the "
                f"{self.profile!r} profile's typical σ"
            )
        else:
            passes = "whatever its size (it only raises σ̂)"
        by = {n: (f, t) for n, f, t in self.floors}
        named = [by[n][1] for n in ("scale", "gains", "drift") if n in by]
        trends = [(f, t) for n, (f, t) in by.items() if n.startswith("trend:")]
        if trends:
            named.append(max(trends)[1])
        return (
            f"with the noise estimated, a smooth model error none of the probes spans (an "
            f"axis tilt, backlash, a periodic screw error) can pass {passes}, and of those "
            f"they span {', '.join(named[:-1])}"
            f"{' or ' if len(named) > 1 else ''}{named[-1]} would pass unseen (90 % "
            f"detection): {remedy}"
        )

    def reason(self, override_hint: bool = True) -> str:
        """One line: why the calibration is refused, the likely cause, how to override."""
        if self.passed:
            return "quality gate passed"
        found = "; ".join(i.message for i in self.refusals)
        text = f"calibration refused by the quality gate: {found}. Likely cause: {self.cause}"
        text += f" — {self.cause_text}" if self.cause_text else "."
        if override_hint:
            text += (
                " Nothing was written; fix the data, or pass --force (force=True) to write "
                "it anyway (the report records the override)"
            )
        return text

    def to_dict(self, overridden: bool = False) -> dict[str, Any]:
        """JSON-ready form (SI); ``overridden`` records a forced write."""

        def num(v: float) -> float | None:
            return float(v) if math.isfinite(v) else None

        lim = self.limits
        return {
            "passed": self.passed,
            "overridden": bool(overridden and not self.passed),
            "reason": None if self.passed else self.reason(override_hint=False),
            "cause": self.cause or None,
            "refusals": [{"kind": i.kind, "message": i.message} for i in self.refusals],
            "warnings": [{"kind": i.kind, "message": i.message} for i in self.warnings],
            "outlier_poses": list(self.outlier_poses),
            "outlier_limit": num(round(self.outlier_limit, 3)),
            "duplicate_rows": [list(p) for p in self.duplicate_rows],
            "scale_ratio": num(self.scale_ratio),
            "likely_unit": self.likely_unit,
            "singular_poses": list(self.singular_poses),
            "noise_source": self.noise_source or None,
            "chi2_blocks": [
                {"block": b, "chi2": num(c), "dof": num(n), "p_value": num(p)}
                for b, c, n, p in self.chi2_blocks
            ],
            "probes": [
                {"name": n, "explained": num(e), "p_value": num(p), "size": t}
                for n, e, p, t in self.probes
            ],
            "detection_floor": {
                "power": 0.9,
                "probes": [{"name": n, "floor": num(f), "text": t} for n, f, t in self.floors],
                "blind_spot": self.blind_spot() or None,
            },
            "instrument_profile": self.profile or None,
            "held_out": self.held_out,
            "limits": {
                "max_reduced_chi2": lim.max_reduced_chi2,
                "max_length_change_m": lim.max_length_change,
                "max_angle_change_rad": lim.max_angle_change,
                "outlier_risk": lim.outlier_risk,
                "max_downweighted": lim.max_downweighted,
                "chi2_significance": lim.chi2_significance,
                "min_chi2_ratio": lim.min_chi2_ratio,
                "probe_significance": lim.probe_significance,
                "probe_explained": lim.probe_explained,
                "noise_factor": lim.noise_factor,
                "max_registration_length_m": lim.max_registration_length,
                "max_registration_angle_rad": lim.max_registration_angle,
            },
        }

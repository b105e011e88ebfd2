"""How a marker table is calibrated: the settings ``pincal calibrate --link`` exposes.

Real measurements of unknown quality are the usual case of a marker table (motion
capture, a tracker without a declared σ), so the defaults are the ones that cannot run
away and that held-out prediction judges (docs/quality_gate.md, "Real data"):

- ``prior="auto"``: a weak Gaussian prior on the machine's parameters about nominal,
  its strength chosen by K-fold cross-validation among :data:`PRIOR_GRID` (the same
  number in mm for lengths and mrad for angles); ``"none"`` fits without one,
  ``"LEN_MM,ANG_MRAD"`` fixes it;
- ``loss="auto"``: least squares, then the Huber loss when the gate's outlier test
  names poses of the least-squares fit (the refit is said in the notes).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from pincal.errors import OptionValueError
from pincal.identification import LOSSES, GateLimits, Prior

__all__ = ["PRIOR_GRID", "MarkerSettings", "parse_prior"]

#: prior σ tried by ``prior="auto"`` (mm for lengths, mrad for angles). The weakest
#: (100 mm / 100 mrad) is "no prior" for any direction the poses determine; it still
#: bounds the directions they barely move, which a fit without a prior lets run away.
PRIOR_GRID = (0.3, 1.0, 3.0, 10.0, 30.0, 100.0)


def parse_prior(spec: str | None) -> str | Prior | None:
    """``"auto"``, a :class:`Prior` from ``"LEN_MM,ANG_MRAD"``, or None (``"none"``).

    ``None`` (not given) means ``"auto"``.

    Raises:
        OptionValueError: not ``auto``, ``none`` or two positive numbers.
    """
    if spec is None or spec == "auto":
        return "auto"
    if spec == "none":
        return None
    try:
        a, b = (float(v) for v in spec.split(","))
    except ValueError:
        a = b = math.nan
    if not (math.isfinite(a) and math.isfinite(b) and a > 0 and b > 0):
        raise OptionValueError(f"prior {spec!r} is not 'auto', 'none' or 'LEN_MM,ANG_MRAD' "
                               "(two numbers > 0, e.g. 10,10)")  # fmt: skip
    return Prior(a * 1e-3, b * 1e-3)


@dataclass(frozen=True)
class MarkerSettings:
    """The settings of a marker calibration.

    Attributes:
        preset: parameter preset (``chain``: every joint's geometry, the instrument
            frame and the marker(s)).
        method: ``gauss-newton`` (Levenberg–Marquardt takes over when it does not
            converge) or ``lm``; a robust loss runs ``lm``.
        prior: ``auto``, ``none`` or ``LEN_MM,ANG_MRAD`` (see :func:`parse_prior`).
        loss: ``auto`` or one of :data:`pincal.identification.LOSSES`.
        limits: the quality gate's thresholds.
        instrument: instrument profile judging the estimated noise, or None.
        folds: K of the cross-validation that chooses the prior and judges the fit.
        seed: the folds' seed.
    """

    preset: str = "chain"
    method: str = "gauss-newton"
    prior: str = "auto"
    loss: str = "auto"
    limits: GateLimits = field(default_factory=GateLimits)
    instrument: str | None = None
    folds: int = 5
    seed: int = 0

    def __post_init__(self) -> None:
        parse_prior(self.prior)
        if self.loss != "auto" and self.loss not in LOSSES:
            raise OptionValueError(f"loss {self.loss!r} is not 'auto' or one of {list(LOSSES)}")
        if self.folds < 2:
            raise OptionValueError(f"cross-validation needs ≥ 2 folds, got {self.folds}")

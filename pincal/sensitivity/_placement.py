"""The one rule for a parameter the poses do not place: 1σ beyond 20 mm / 0.1 rad.

A parameter (or a direction of parameters) whose 1σ at the declared noise exceeds
:data:`PLACEMENT_BOUND` — 20 mm for a length, 0.1 rad for an angle — is outside the
small-error range in which a calibration is linear: the fit holds it at nominal
(:class:`pincal.identification.WeakBound`, a direction of the whitened Jacobian) and
`pincal validate` withholds its Cramér–Rao prediction for a covariance in which a
parameter is that loose (:func:`pincal.validation.prediction_caveat`). Both read the
bound and its units from here, so what the fit keeps the prediction accepts.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = ["PLACEMENT_BOUND", "beyond_placement", "placement_limits", "placement_words"]

#: (length [m], angle [rad]): the largest 1σ of a parameter the poses place
PLACEMENT_BOUND: tuple[float, float] = (0.02, 0.1)


def placement_limits(
    units: Sequence[str], bounds: tuple[float, float] = PLACEMENT_BOUND
) -> np.ndarray:
    """The 1σ limit of each parameter: the angle bound for ``"rad"``, else the length one.

    Args:
        units: (p,) per parameter ``"m"``, ``"rad"`` (or a joint term's unit, held to
            the length bound's number).
        bounds: (length [m], angle [rad]).

    Returns:
        (p,) limits [m or rad].
    """
    return np.array([bounds[1] if u == "rad" else bounds[0] for u in units], dtype=float)


def beyond_placement(
    std: np.ndarray, units: Sequence[str], bounds: tuple[float, float] = PLACEMENT_BOUND
) -> np.ndarray:
    """True for each parameter whose 1σ exceeds its limit (NaN counts as beyond).

    Args:
        std: (p,) 1σ of each parameter [m or rad].
        units: (p,) their units (see :func:`placement_limits`).
        bounds: (length [m], angle [rad]).

    Returns:
        (p,) bool.
    """
    std = np.asarray(std, dtype=float)
    return ~(std <= placement_limits(units, bounds))


def placement_words(bounds: tuple[float, float] = PLACEMENT_BOUND) -> str:
    """The bound in words, e.g. ``"20 mm / 0.1 rad (1σ)"``."""
    return f"{bounds[0] * 1e3:g} mm / {bounds[1]:g} rad (1σ)"

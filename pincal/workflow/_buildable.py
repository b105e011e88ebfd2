"""Which geometric errors a built machine can have (the errors simulated machines get)."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from pincal.model import Mechanism, ParameterSet, degenerate_translations
from pincal.sensitivity import closure_breaking

__all__ = ["buildable_mask"]


def buildable_mask(
    mech: Mechanism,
    params: ParameterSet,
    rows: np.ndarray,
    say: Callable[[str], None] | None = None,
) -> np.ndarray:
    """Which parameters a built machine can have an error on: (n,) float, 1 or 0.

    0 for a translation that splits an emulated ball or universal joint (the physical
    joint has no such offset) and for a parameter that breaks a loop closure at the
    first (up to 10) actuator rows (m, n_act) [m, rad]: an over-constrained loop built
    with that error would not assemble. ``say``: given a note (one line) when any is
    left at 0. ``pincal simulate`` (:func:`simulate_campaign`) and the reach screen of
    ``pincal poses`` (:func:`compensation_test`) draw their errors times this mask.
    """
    split = set(degenerate_translations(mech))
    keep = np.array([n not in split for n in params.names])
    breaks = closure_breaking(mech, params, np.asarray(rows)[:10]) & keep
    keep &= ~breaks
    if say is not None and not keep.all():
        say(
            f"note: errors drawn on {int(keep.sum())} of {len(keep)} parameters; "
            f"{int(breaks.sum())} would break a loop closure and "
            f"{len(keep) - int(keep.sum()) - int(breaks.sum())} would split an emulated "
            "joint (a built machine has neither): they stay 0"
        )
    return keep.astype(float)

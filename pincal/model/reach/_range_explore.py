"""Ranges of actuators that declare none, found by continuation from home.

A URDF ``<limit>`` without ``lower``/``upper`` (read as 0 0) declares no range, and
many exported leg and ankle files write every joint that way. Random poses drawn over
±π then mostly fail to close the loops (or close them on another assembly mode), so
each draw costs a failed Newton solve and a pose design may never finish.

Without a declared range (URDF limits or the sidecar ``workspace: joints``), the
range of actuator k is *explored*: from home, actuator k alone is moved in steps of
``span / STEPS`` (the others held at home), each configuration solved from the last on
home's assembly branch (:meth:`Mechanism.configuration`), until the loops stop
closing, the branch changes or the closure turns singular, or the default span
:data:`DEFAULT_SPAN` (π/2 rad, 0.1 m) is reached — on each side. Where the loops
stopped closing, the range ends :data:`BACK_OFF` steps (π/24 rad, 8.3 mm) short of the
last value that closed: a margin to the edge of the workspace, where poses are
ill-conditioned and a slightly different machine (a calibration's trial) does not
close. A warning says the range was found, not declared, and how to declare one.
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING

import numpy as np

from pincal.errors import ConvergenceError, ModelFileError

if TYPE_CHECKING:
    from pincal.model._mechanism import Mechanism

__all__ = ["BACK_OFF", "DEFAULT_SPAN", "STEPS", "explored_ranges"]

log = logging.getLogger(__name__)

#: largest exploration from home on each side: π/2 rad (revolute), 0.1 m (prismatic)
DEFAULT_SPAN = {"rad": np.pi / 2, "m": 0.1}
#: continuation steps over the default span
STEPS = 24
#: steps given back where the loops stop closing (a margin to the workspace's edge)
BACK_OFF = 2


def _side(
    mech: Mechanism, k: int, q_home: np.ndarray, q_act0: np.ndarray, sign: float, span: float
) -> tuple[float, bool]:
    """Walk actuator k from home towards ``sign``·span.

    Returns the end of the range on that side and whether the walk stopped early
    (loops open, branch change, singularity): then the end is :data:`BACK_OFF` steps
    short of the last value that closed, so that poses (and the slightly different
    machines a calibration tries) stay clear of the edge of the workspace.
    """
    q_prev, closed = q_home, 0
    for i in range(1, STEPS + 1):
        trial = q_act0.copy()
        trial[k] = q_act0[k] + sign * span * i / STEPS
        try:
            q_prev = mech.configuration(trial, q_guess=q_prev)
        except ConvergenceError:  # includes SingularConfigurationError
            kept = max(closed - BACK_OFF, 0)
            return float(q_act0[k] + sign * span * kept / STEPS), True
        closed = i
    return float(q_act0[k] + sign * span), False


def explored_ranges(mech: Mechanism) -> dict[int, tuple[float, float]]:
    """{actuator index: (lower, upper)} for the actuators without a declared range.

    Computed once per mechanism (kept by :meth:`Mechanism.memo`). An actuator with one
    declared bound is explored on the other side only.

    Raises:
        ModelFileError: an actuator cannot move from home at all (its first step
            either way fails): no range can be found; declare one.
    """
    return mech.memo("explored_ranges", lambda: _explore(mech))


def _explore(mech: Mechanism) -> dict[int, tuple[float, float]]:
    """The explored ranges of :func:`explored_ranges` (computed, not cached)."""
    limits = np.array(mech.actuator_limits, dtype=float)
    q_home = mech.q_home
    q_act0 = mech.actuators_of(q_home)
    out: dict[int, tuple[float, float]] = {}
    for k, name in enumerate(mech.actuated):
        if name in mech.workspace.joints or np.all(np.isfinite(limits[k])):
            continue
        prismatic = mech.tree.joints[name].type == "prismatic"
        unit = "m" if prismatic else "rad"
        span = DEFAULT_SPAN[unit]
        lo, hi = limits[k]
        early = []
        if not np.isfinite(lo):
            lo, stopped = _side(mech, k, q_home, q_act0, -1.0, span)
            early.append(stopped)
        if not np.isfinite(hi):
            hi, stopped = _side(mech, k, q_home, q_act0, 1.0, span)
            early.append(stopped)
        if hi - lo <= 0.0:
            raise ModelFileError(
                f"actuator {name!r} of {mech.name!r} declares no range (URDF limits 0 0 or "
                f"none) and cannot move from home ({q_act0[k]:.6g} {unit}): the loops do not "
                "close one step away on home's branch; declare a range (sidecar 'workspace: "
                "joints') or move 'home'"
            )
        out[k] = (float(lo), float(hi))
        why = (
            "where the loops stop closing on home's assembly branch"
            if any(early)
            else f"at the default span ±{span:.4g} {unit} from home"
        )
        log.warning(
            "actuator %r of %r declares no range (URDF limits 0 0 or none, no sidecar "
            "workspace): range [%.6g, %.6g] %s found by continuation from home (stopped %s), "
            "not declared; declare it in the sidecar 'workspace: joints' to override",
            name,
            mech.name,
            lo,
            hi,
            unit,
            why,
        )
    return out

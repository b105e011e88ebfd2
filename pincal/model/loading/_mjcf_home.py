"""The home configuration of an MJCF model: keyframe, sidecar, or a regular one nearby.

MuJoCo's ``qpos0`` is often a straight or folded pose of a legged linkage, where the
loop closure Jacobian loses rank, and it may even put joints outside their own
ranges. :func:`build_with_home` assembles the mechanism from the home the file gives
(the keyframe ``home``, else the first keyframe, else ``qpos0``; a ``home:`` in the
sidecar beside the file overrides it) and, when that home is ``qpos0`` and singular
(or does not close), searches a regular configuration nearby: each actuator in turn
moved by ±0.02, 0.05, 0.1, 0.2, 0.4 (rad or m, nearest first, inside its range),
the passive joints solved from ``qpos0``; the first that assembles without a
singularity is home, and a note says which it is and why. A home outside a joint's
range is named (note, and in the error when nothing assembles). Joints with a spring
(MJCF ``stiffness`` > 0) are reported: a calibration treats them as passive joints.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING, Any

import numpy as np

from pincal.errors import ClosureError, ConvergenceError, MobilityError

if TYPE_CHECKING:
    from pincal.model._mechanism import Mechanism

__all__ = ["SEARCH_STEPS", "build_with_home"]

log = logging.getLogger(__name__)

#: actuator displacements tried from ``qpos0`` [rad or m], nearest first
SEARCH_STEPS = (0.02, 0.05, 0.1, 0.2, 0.4)
_FAILURES = (ConvergenceError, ClosureError, MobilityError)


def _outside(home: dict[str, Any], ranges: dict[str, tuple[float, float]]) -> list[str]:
    """"joint 'j' = v is outside its range [lo, hi]" for each such joint of ``home``."""
    out = []
    for j, (lo, hi) in ranges.items():
        v = home.get(j)
        if isinstance(v, int | float) and not lo - 1e-9 <= v <= hi + 1e-9:
            out.append(f"joint {j!r} = {v:.6g} is outside its range [{lo:.6g}, {hi:.6g}]")
    return out


def _home_values(mech: Mechanism, joints: Iterable[str]) -> dict[str, float]:
    """The assembled home value of each named 1-dof joint [rad, m]."""
    model = mech.model
    return {
        j: float(mech.q_home[model.idx_qs[model.getJointId(j)]])
        for j in joints
        if model.existJointName(j) and model.nqs[model.getJointId(j)] == 1
    }


def _regular(mech: Mechanism) -> bool:
    """Whether the passive closure Jacobian at home is well conditioned (the pose limit)."""
    s = np.linalg.svd(mech.closure_jacobian(mech.q_home)[:, mech.free_dofs], compute_uv=False)
    r = mech.closure_rank
    return bool(r == 0 or (s[r - 1] > 0 and s[0] / s[r - 1] <= mech.options.max_condition))


def build_with_home(
    build: Callable[[dict[str, Any]], Mechanism],
    sidecar: dict[str, Any],
    home_source: str,
    ranges: dict[str, tuple[float, float]],
    stiffness: dict[str, float],
) -> Mechanism:
    """The mechanism of an MJCF model with a usable home (see the module doc).

    Args:
        build: ``build(sidecar) -> Mechanism``.
        sidecar: the converted sidecar (with ``home`` and ``name_mot``), the file's
            own sidecar merged over it.
        home_source: ``"qpos0"``, ``"keyframe '<name>'"`` or ``"sidecar"``.
        ranges: hinge/slide joint → (lower, upper) [rad, m].
        stiffness: joints with a spring → MJCF stiffness [N·m/rad or N/m].

    Raises:
        ClosureError, ConvergenceError (SingularConfigurationError), MobilityError: no
            home assembles; the message names the home's source and the joints it puts
            outside their ranges.
    """
    home = dict(sidecar.get("home", {}))
    outside = _outside(home, ranges)
    notes: list[str] = []
    mech: Mechanism | None
    try:
        mech = build(sidecar)
    except _FAILURES as exc:
        found = _nearby(build, sidecar, home, ranges) if home_source == "qpos0" else None
        if found is None:
            extra = f"; at the home ({home_source}), " + "; ".join(outside) if outside else ""
            hint = (
                " Give a regular home: a <keyframe> in the MJCF, or 'home:' in a sidecar "
                "<stem>.yaml beside it."
            )
            springs = [j for j in getattr(exc, "free_joints", ()) if j in stiffness]
            if springs:  # a spring left free: locking it is the usual answer
                extra = ""
                hint = (
                    f" {', '.join(repr(j) for j in springs)}: a spring joint (MJCF stiffness); "
                    f"to hold it, 'lock: {{{springs[0]}: home}}' (or a value [rad, m]) in a "
                    "sidecar <stem>.yaml beside the MJCF."
                )
            raise type(exc)(f"{str(exc).rstrip('.')}{extra}.{hint}") from exc
        mech, nearby_note = found
        notes.append(nearby_note)
    outside = _outside(_home_values(mech, ranges), ranges)
    if outside:
        notes.append("at the home, " + "; ".join(outside))
    for j, k in stiffness.items():
        role = "an actuated" if j in mech.actuated else "a passive"
        notes.append(
            f"joint {j!r} has a spring (MJCF stiffness {k:g}): {role} joint here; "
            "calibration does not model the spring (to hold it, 'lock: {joint: value or "
            "home}' in a sidecar <stem>.yaml beside the MJCF)"
        )
    for n in notes:
        log.warning("MJCF import of %r: %s", mech.name, n)
    return mech.with_notes(after=notes)


def _nearby(
    build: Callable[[dict[str, Any]], Mechanism],
    sidecar: dict[str, Any],
    home: dict[str, Any],
    ranges: dict[str, tuple[float, float]],
) -> tuple[Mechanism, str] | None:
    """The first regular assembly with one actuator moved from ``qpos0`` and a note, or None."""
    actuated = [j for j in sidecar.get("name_mot") or [] if isinstance(home.get(j), float)]
    for step in SEARCH_STEPS:
        for j in actuated:
            lo, hi = ranges.get(j, (-float("inf"), float("inf")))
            for sign in (1.0, -1.0):
                value = home[j] + sign * step
                if not lo <= value <= hi:
                    continue
                trial = dict(sidecar, home=dict(home, **{j: value}))
                try:
                    mech = build(trial)
                except _FAILURES:
                    continue
                kept = abs(_home_values(mech, [j]).get(j, value) - value) <= 1e-9
                if not (kept and _regular(mech)):
                    continue  # the assembly moved the actuator (back to qpos0) or is singular
                note = (
                    f"qpos0 is singular or does not close; home is the nearest regular "
                    f"configuration found: {j!r} = {value:.6g} (qpos0 {sign * step:+g}), the "
                    "passive joints solved from qpos0. Give a <keyframe> or a sidecar "
                    "'home:' to choose another"
                )
                return mech, note
    return None

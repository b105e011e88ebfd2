"""A regular home for an open chain that has none (a robot by name without SRDF pose).

Measure of regularity: the smallest singular value σ_min of the measured-frame
Jacobian (measured rows, actuated columns), its orientation rows multiplied by the
chain length L, divided by L (dimensionless: 1 m of motion per rad over L). L is the
sum of the distances between consecutive joint origins up to the measured frame at
home, a configuration-independent reach bound. σ_min = 0 at a singular configuration.

Search (deterministic): home itself and 512 candidates home + k·15° (k an integer in
−6…6 per actuated joint, prismatic joints unchanged) drawn with
``numpy.random.default_rng(0)``; a candidate counts when it is inside the sampling
ranges and, with a floor (:mod:`pincal.model.reach._floor`), keeps the moving points above it.
The chosen home is the counting candidate nearest home (Euclidean norm of the joint
change) whose σ_min is at least half the best one found, then moved back toward home
one 15° step of one joint at a time while it still counts and keeps that σ_min:
well-conditioned, yet near where the URDF put the arm (joints that do not help stay).
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from pincal.model._mechanism import Mechanism
from pincal.model.files import COMPONENTS
from pincal.model.loops import six_by_nv
from pincal.model.reach._floor import moving_points, point_heights

__all__ = ["RegularHome", "by_name_defaults", "conditioning", "regular_home"]

#: candidates drawn around home, their step [rad] and largest step count per joint
CANDIDATES, STEP, STEPS = 512, np.pi / 12, 6
#: the chosen candidate's σ_min is at least this share of the best one's
SHARE = 0.5


@dataclass(frozen=True)
class RegularHome:
    """A searched home: actuator values (n_act,) [rad or m] and its σ_min (dimensionless)."""

    q_act: np.ndarray
    sigma: float  # σ_min at the chosen home
    sigma_start: float  # σ_min at the starting home (0 when below 1e-9)


def _chain_length(mech: Mechanism) -> float:
    """Sum of the distances between consecutive joint origins up to the measured frame [m]."""
    model, data = mech.model, mech.model.createData()
    pin.framesForwardKinematics(model, data, mech.q_home)
    fid = mech.frame_id(mech.measured_frame)
    j = model.frames[fid].parentJoint
    points = [data.oMf[fid].translation]
    while j > 0:
        points.append(data.oMi[j].translation)
        j = model.parents[j]
    length = sum(float(np.linalg.norm(a - b)) for a, b in itertools.pairwise(points))
    return max(length, 1e-3)


def conditioning(mech: Mechanism, q: np.ndarray, length: float | None = None) -> float:
    """σ_min of the length-scaled measured-frame Jacobian at q (nq,) (see module doc)."""
    L = _chain_length(mech) if length is None else length
    data = mech.model.createData()
    fid = mech.frame_id(mech.measured_frame)
    J = six_by_nv(pin.computeFrameJacobian(mech.model, data, q, fid, pin.LOCAL))
    rows = [COMPONENTS.index(c) for c in mech.measured_components]
    cols = [mech.model.idx_vs[mech.model.getJointId(n)] for n in mech.actuated]
    G = J[np.ix_(rows, cols)] * np.array([1.0 / L if r < 3 else 1.0 for r in rows])[:, None]
    return float(np.linalg.svd(G, compute_uv=False).min(initial=np.inf)) if G.size else 0.0


def regular_home(mech: Mechanism, ranges: np.ndarray, floor: float | None) -> RegularHome:
    """The regular home of an open chain (see module doc).

    Args:
        mech: the mechanism at its current home (the search starts there).
        ranges: actuator sampling ranges (n_act, 2) [rad or m].
        floor: floor height [m] the moving points keep, or None.
    """
    start = mech.actuators_of(mech.q_home)
    L = _chain_length(mech)
    kinds = [mech.model.joints[mech.model.getJointId(n)].shortname() for n in mech.actuated]
    revolute = np.array([not k.startswith("JointModelP") for k in kinds])
    rng = np.random.default_rng(0)
    steps = rng.integers(-STEPS, STEPS + 1, size=(CANDIDATES, start.size)) * revolute
    candidates = np.vstack([start, start + STEP * steps])
    points = moving_points(mech) if floor is not None else np.zeros(0, dtype=int)

    def score(row: np.ndarray) -> float:
        """σ_min at ``row``, −1 outside the ranges or below the floor."""
        if np.any(row < ranges[:, 0]) or np.any(row > ranges[:, 1]):
            return -1.0
        q = mech.with_actuators(mech.q_home, row)
        if floor is not None and points.size and point_heights(mech, q, points).min() < floor:
            return -1.0
        return conditioning(mech, q, L)

    scores = np.array([score(row) for row in candidates])
    at_start = conditioning(mech, mech.q_home, L)
    if scores.max() <= 0:
        return RegularHome(start, max(float(scores[0]), 0.0), at_start if at_start > 1e-9 else 0.0)
    good = np.flatnonzero(scores >= SHARE * scores.max())
    best = int(good[np.argmin(np.linalg.norm(candidates[good] - start, axis=1))])
    row, sigma = candidates[best].copy(), float(scores[best])
    moved = True
    while moved:  # back toward the start, one step of one joint at a time
        moved = False
        for j in np.flatnonzero(np.abs(row - start) > 1e-12):
            trial = row.copy()
            trial[j] -= STEP * np.sign(row[j] - start[j])
            if abs(trial[j] - start[j]) < 1e-9:
                trial[j] = start[j]
            trial_sigma = score(trial)
            if trial_sigma >= SHARE * scores.max():
                row, sigma, moved = trial, trial_sigma, True
    return RegularHome(row, sigma, at_start if at_start > 1e-9 else 0.0)


def by_name_defaults(
    mech: Mechanism, side: dict[str, Any], user_workspace: Any
) -> tuple[dict[str, Any], list[str]]:
    """Floor and home of an open chain by name (example-robot-data, no pincal sidecar).

    Args:
        mech: the mechanism loaded with ``side``.
        side: its sidecar mapping (not modified).
        user_workspace: the user sidecar's raw ``workspace`` (its ``floor`` key wins).

    Returns:
        (the sidecar mapping with ``workspace.floor`` and ``home`` added where they
        apply, the notes saying so).
    """
    from pincal.model.reach._floor import DEFAULT_FLOOR, stands_on_base
    from pincal.model.reach._workspace import joint_ranges

    if mech.closures:
        return side, []
    side, notes = dict(side), []
    own_floor = isinstance(user_workspace, Mapping) and "floor" in user_workspace
    floor = mech.workspace.floor
    if not own_floor and stands_on_base(mech):
        floor = DEFAULT_FLOOR
        side["workspace"] = {**(side.get("workspace") or {}), "floor": floor}
        notes.append(
            f"floor: drawn poses keep every moving joint origin and link frame >= "
            f"{floor * 1e3:.0f} mm above the base plane z = 0 (robot by name standing on its "
            f"base; a sidecar 'workspace: {{floor: false}}' turns it off)"
        )
    if "home" in side:
        return side, notes
    found = regular_home(mech, joint_ranges(mech), floor)
    start = mech.actuators_of(mech.q_home)
    if np.array_equal(found.q_act, start):
        return side, notes
    side["home"] = {n: float(v) for n, v in zip(mech.actuated, found.q_act, strict=True)}
    degrees = ", ".join(f"{n} = {np.degrees(v):.0f}°" for n, v in side["home"].items() if v)
    notes.append(
        f"home (searched): {degrees}, other joints 0 (no SRDF reference pose; near q = 0, a "
        f"regular configuration of {mech.measured_frame!r}: smallest singular value of the "
        f"length-scaled Jacobian {found.sigma_start:.2g} at q = 0, {found.sigma:.2g} there; "
        f"a sidecar 'home' wins)"
    )
    return side, notes

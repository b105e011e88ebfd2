"""The ISO 9283 test cube (or square) on the components a machine measures.

ISO 9283 places its test cube inside the working space and judges the machine at five
points of the cube's diagonal plane. pincal builds it on the machine's *measured* position
components: a cube in x, y, z for a machine measuring all three, a square in the plane of
the two it measures (x, y for a planar machine), and refuses with fewer than two. The
commanded orientation is home's, turned to the centre of the declared rotation ranges of
``workspace.pose``; only the measured components of a pose are commanded (the inverse
kinematics imposes nothing else), and unmeasured position axes are held at home's value.

The cube is the largest one, centred on its workspace box, whose 3^d lattice (corners,
edge and face centres, centre) is reached: inverse kinematics within the actuator limits
(and the sidecar's ``workspace.joints`` travel), then forward kinematics on home's
assembly branch returning the target on the measured components to 1 µm / 1 µrad. The
box is the sidecar's declared ``workspace.pose`` when it declares every measured position
axis ("declared", the cube centred in it), otherwise the bounding box of the forward
kinematics of random feasible actuator values ("sampled", the cube centred at their mean
or at home's position, whichever holds the larger one).

Test points: P1 at the centre; P2–P5 on the diagonals of the diagonal plane (a cube) or
of the square itself at ``inset`` (the standard's (10 ± 2) %) of the diagonal from the
corners: for a cube of half edge h about c the corners C7 = c + h(1,1,1),
C8 = c + h(−1,−1,1), C1 = c + h(−1,−1,−1), C2 = c + h(1,1,−1); for a square the corners
(+,+), (−,+), (−,−), (+,−) in its two axes.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pincal.errors import ConvergenceError, NoTestCubeError, PincalError
from pincal.model import COMPONENTS, Mechanism, sample_actuators

__all__ = ["TestCube", "iso_test_cube"]

#: a lattice point whose forward kinematics misses its target by more [m, rad] is unreached
_ROUND_TRIP_TOL = 1e-6

_CORNERS = {
    3: ((1, 1, 1), (-1, -1, 1), (-1, -1, -1), (1, 1, -1)),
    2: ((1, 1), (-1, 1), (-1, -1), (1, -1)),
}


@dataclass(frozen=True)
class TestCube:
    """The ISO 9283 test cube (or square) and its five test poses.

    Attributes:
        centre: (3,) centre [m] (unmeasured axes at home's value); edge: edge length [m].
        rotation: (3, 3) commanded orientation of every test pose.
        points: (5, 3) P1..P5 [m].
        inset: fraction of the diagonal between a corner and its test point.
        axes: the position axes spanned, e.g. ``("x", "y")`` for a square.
        components: the measured components the test commands and evaluates.
        workspace: ``"declared"`` (sidecar ``workspace.pose``) or ``"sampled"``.
        bounds: (len(axes), 2) the workspace box the cube lies in [m].
    """

    __test__ = False  # not a pytest class

    centre: np.ndarray
    edge: float
    rotation: np.ndarray
    points: np.ndarray
    inset: float
    axes: tuple[str, ...] = ("x", "y", "z")
    components: tuple[str, ...] = COMPONENTS
    workspace: str = "sampled"
    bounds: np.ndarray | None = None

    @property
    def poses(self) -> list[pin.SE3]:
        """The five commanded poses P1..P5."""
        return [pin.SE3(self.rotation, p) for p in self.points]

    @property
    def shape(self) -> str:
        """``"cube"`` or ``"square"``."""
        return "cube" if len(self.axes) == 3 else "square"

    def describe(self) -> str:
        """One line: shape, axes, centre and edge [mm], the workspace it lies in."""
        where = (
            "inside the declared workspace (sidecar workspace.pose)"
            if self.workspace == "declared"
            else "inside the sampled reachable workspace"
        )
        idx = [COMPONENTS.index(a) for a in self.axes]
        box = ", ".join(
            f"{a} [{lo * 1e3:.2f}, {hi * 1e3:.2f}]"
            for a, (lo, hi) in zip(self.axes, np.asarray(self.bounds), strict=True)
        )
        return (
            f"test {self.shape} in {' '.join(self.axes)} (measured components "
            f"{' '.join(self.components)}): centre {np.round(self.centre[idx] * 1e3, 3).tolist()}"
            f" mm, edge {self.edge * 1e3:.2f} mm, {where}: {box} mm; P2–P5 at "
            f"{self.inset:.0%} of the diagonal from the corners"
        )


def _test_points(c: np.ndarray, idx: list[int], edge: float, inset: float) -> np.ndarray:
    """P1..P5 (5, 3) of the cube/square of ``edge`` about ``c`` in axes ``idx``."""
    pts = [c.copy()]
    for s in _CORNERS[len(idx)]:
        corner = c.copy()
        corner[idx] += edge / 2 * np.array(s, dtype=float)
        opposite = 2 * c - corner
        pts.append(corner + inset * (opposite - corner))
    return np.array(pts)


def _reached(mech: Mechanism, target: pin.SE3, travel: np.ndarray) -> bool:
    """Whether ``target`` is reached on the measured components (see the module doc)."""
    try:
        q = mech.inverse(target)
        if np.any(q < travel[:, 0] - 1e-12) or np.any(q > travel[:, 1] + 1e-12):
            return False
        T = mech.forward(q)
    except ConvergenceError:
        return False
    err = np.concatenate(
        [T.translation - target.translation, pin.log3(target.rotation.T @ T.rotation)]
    )
    comps = [COMPONENTS.index(c) for c in mech.measured_components]
    return bool(np.max(np.abs(err[comps])) <= _ROUND_TRIP_TOL)


def _travel(mech: Mechanism) -> np.ndarray:
    """(n_act, 2) actuator limits narrowed to the sidecar's ``workspace.joints``."""
    travel = np.array(mech.actuator_limits, dtype=float)
    for k, name in enumerate(mech.actuated):
        if name in mech.workspace.joints:
            lo, hi = mech.workspace.joints[name]
            travel[k] = max(travel[k, 0], lo), min(travel[k, 1], hi)
    return travel


def _workspace_box(
    mech: Mechanism, idx: list[int], n_samples: int, gen: np.random.Generator
) -> tuple[str, np.ndarray, np.ndarray]:
    """(source, centre (d,), bounds (d, 2)) of the box the cube must lie in [m]."""
    declared = mech.workspace.pose
    axes = [COMPONENTS[i] for i in idx]
    if all(a in declared for a in axes):
        bounds = np.array([declared[a] for a in axes], dtype=float)
        return "declared", bounds.mean(axis=1), bounds
    q = sample_actuators(mech, n_samples, gen)
    P = np.array([mech.frame_placement(x).translation for x in mech.configurations(q)])[:, idx]
    return "sampled", P.mean(axis=0), np.stack([P.min(axis=0), P.max(axis=0)], axis=1)


def _advice(source: str, axes: list[str], flat: list[str]) -> str:
    if flat:
        return (
            f"the machine does not move its measured frame along {', '.join(flat)} in this "
            f"workspace: declare only the components it moves (sidecar 'measured', e.g. "
            f"x, y, rz for a planar machine)"
        )
    if source == "declared":
        return (
            f"widen the sidecar's workspace.pose ranges of {', '.join(axes)} to where the "
            "machine reaches (or remove them to use the sampled reachable workspace)"
        )
    return (
        f"give the sidecar a workspace.pose box of {', '.join(axes)} the machine reaches "
        "at home's orientation, or check the actuator limits"
    )


def _largest_edge(
    reached: Callable[[np.ndarray], bool],
    centre: np.ndarray,
    idx: list[int],
    bounds: np.ndarray,
    tol: float,
) -> float | None:
    """The largest reached cube edge [m] about ``centre`` inside ``bounds``, or None.

    Reached: every point of the 3^d lattice (bisection to ``tol``); None when the centre
    itself is not reached.
    """
    lattice = [np.array(d, dtype=float) for d in itertools.product((-1, 0, 1), repeat=len(idx))]
    mid = centre[idx]

    def reachable(edge: float) -> bool:
        for d in lattice:
            p = centre.copy()
            p[idx] += edge / 2 * d
            if not reached(p):
                return False
        return True

    if not reachable(0.0):
        return None
    hi = max(float(2 * np.min(np.minimum(mid - bounds[:, 0], bounds[:, 1] - mid))), 0.0)
    lo = hi if reachable(hi) else 0.0
    while hi - lo > tol:
        m = 0.5 * (lo + hi)
        lo, hi = (m, hi) if reachable(m) else (lo, m)
    return lo


def iso_test_cube(
    mech: Mechanism,
    n_samples: int = 300,
    rng: np.random.Generator | int = 0,
    inset: float = 0.1,
    tol: float = 1e-4,
    min_edge: float = 1e-3,
) -> TestCube:
    """The largest reached cube (square) of the measured position axes in the workspace.

    Centred on the declared box; in a sampled workspace on the samples' mean or on home's
    position, whichever holds the larger cube.

    Args:
        mech: the (nominal) machine.
        n_samples: random feasible poses sampled when no workspace box is declared.
        rng: random generator or seed.
        inset: (0.08..0.12) fraction of the diagonal by which P2..P5 are set in.
        tol: edge-length resolution of the bisection [m].
        min_edge: smallest edge accepted [m].

    Raises:
        PincalError: inset outside the standard's (10 ± 2) %.
        NoTestCubeError: fewer than two measured position components, the centre not
            reached, or no cube of at least ``min_edge`` inside the workspace.
    """
    if not 0.08 <= inset <= 0.12:
        raise PincalError(f"inset must be within the standard's 0.08..0.12, got {inset}")
    comps = tuple(mech.measured_components)
    idx = [i for i in range(3) if COMPONENTS[i] in comps]
    axes = [COMPONENTS[i] for i in idx]
    if len(idx) < 2:
        raise NoTestCubeError(
            f"{mech.name!r} measures {' '.join(comps)}: the ISO 9283 test needs at least two "
            "measured position components (a square in their plane, a cube with three); "
            "measure x, y (and z) of the measured frame (sidecar 'measured')"
        )
    gen = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    source, mid, bounds = _workspace_box(mech, idx, n_samples, gen)
    home = mech.frame_placement(mech.q_home)
    lim = mech.workspace.pose
    r = np.array([np.mean(lim[k]) if k in lim else 0.0 for k in ("rx", "ry", "rz")])
    R = home.rotation @ pin.exp3(r)
    travel = _travel(mech)
    candidates = [mid]
    h = home.translation[idx]
    if source == "sampled" and np.all((h >= bounds[:, 0]) & (h <= bounds[:, 1])):
        candidates.append(h)
    best: tuple[float, np.ndarray] | None = None
    for c in candidates:
        centre = home.translation.copy()
        centre[idx] = c
        edge = _largest_edge(lambda p: _reached(mech, pin.SE3(R, p), travel), centre, idx,
                             bounds, tol)  # fmt: skip
        if edge is not None and (best is None or edge > best[0]):
            best = edge, centre
    where = "declared workspace" if source == "declared" else "sampled reachable workspace"
    box = ", ".join(f"{a} [{lo * 1e3:.3g}, {hi * 1e3:.3g}] mm" for a, (lo, hi) in
                    zip(axes, bounds, strict=True))  # fmt: skip
    flat = [  # axes the sampled motion does not span (a declared box is the user's choice)
        a for a, (lo, hi) in zip(axes, bounds, strict=True)
        if source == "sampled" and hi - lo < min_edge
    ]  # fmt: skip
    if best is None:
        raise NoTestCubeError(
            f"the centre {np.round(mid * 1e3, 3).tolist()} mm ({' '.join(axes)}) of the {where} "
            f"of {mech.name!r} ({box}) is not reached at the commanded orientation; "
            + _advice(source, axes, flat)
        )
    edge, centre = best
    shape = "cube" if len(idx) == 3 else "square"
    if edge < min_edge:
        raise NoTestCubeError(
            f"no ISO 9283 test {shape} in {' '.join(axes)} with an edge of at least "
            f"{min_edge * 1e3:.3g} mm fits inside the {where} of {mech.name!r} ({box}; "
            f"largest reached edge {edge * 1e3:.3g} mm); " + _advice(source, axes, flat)
        )
    return TestCube(
        centre, edge, R, _test_points(centre, idx, edge, inset), inset, tuple(axes), comps,
        source, bounds,
    )  # fmt: skip

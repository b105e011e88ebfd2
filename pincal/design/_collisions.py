"""Collision checks of a mechanism's configurations with Pinocchio's GeometryModel.

The URDF's ``<collision>`` geometry (meshes through coal, primitives) is loaded with
``pin.buildGeomFromUrdfString`` onto the mechanism's own Pinocchio model, so closed
chains (whose tree is the URDF's) are checked like open ones. Checked pairs:

* **self**: every pair of geometries except those on the same joint body, on a joint
  and its parent (they touch at the joint by construction), and pairs already in
  contact at the home configuration (links that meet at a closure joint of a parallel
  machine, or shells that overlap by design); their number is reported;
* **surroundings**: every declared obstacle (an axis-aligned box in the world frame)
  against every geometry on a moving body; pairs in contact at home are dropped and
  reported the same way (a box that the machine stands in at home is not a rule).

A model without collision geometry (or whose meshes cannot be found) gives a
:class:`CollisionChecker` with ``available`` False and a ``note`` saying why; callers
skip the screen and print the note.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from pincal.errors import OptionValueError
from pincal.model import Mechanism

__all__ = ["Box", "CollisionChecker", "parse_box"]


@dataclass(frozen=True)
class Box:
    """An axis-aligned box obstacle in the world frame.

    Attributes:
        centre: (3,) centre [m].
        size: (3,) full edge lengths along x, y, z [m], all > 0.
    """

    centre: tuple[float, float, float]
    size: tuple[float, float, float]


def parse_box(text: str) -> Box:
    """A box from ``"X Y Z DX DY DZ"`` in mm (centre then edge lengths; commas allowed).

    Raises:
        OptionValueError: not six numbers, or an edge length ≤ 0.
    """
    parts = text.replace(",", " ").split()
    try:
        vals = [float(p) * 1e-3 for p in parts]
    except ValueError:
        vals = []
    if len(vals) != 6 or not all(np.isfinite(vals)) or min(vals[3:]) <= 0:
        raise OptionValueError(
            f"obstacle {text!r} must be six numbers 'X Y Z DX DY DZ' in mm: the box's centre "
            "in the world frame and its edge lengths (> 0), e.g. '0 0 -25 2000 2000 50' for "
            "a table top under the base"
        )
    return Box((vals[0], vals[1], vals[2]), (vals[3], vals[4], vals[5]))


def _package_dirs(source: Path | None) -> list[str]:
    """Every ancestor directory of the URDF file: where ``package://`` names resolve."""
    if source is None:
        return []
    return [str(p) for p in Path(source).resolve().parents]


class CollisionChecker:
    """Self- and obstacle-collision test of full configurations (nq,) of a mechanism.

    Attributes:
        available: whether any collision geometry was loaded.
        note: why there is none (``available`` False), else "".
        n_pairs: pairs checked.
        ignored_at_home: pairs dropped because they touch at home (self, obstacles).
    """

    def __init__(self, mech: Mechanism, obstacles: tuple[Box, ...] = ()) -> None:
        self.note = ""
        self.n_pairs = 0
        self.ignored_at_home = (0, 0)
        self._model = mech.model
        self._data = mech.model.createData()
        try:
            geom = pin.buildGeomFromUrdfString(
                mech.model, mech.urdf_xml, pin.COLLISION, package_dirs=_package_dirs(mech.source)
            )
        except (ValueError, RuntimeError) as exc:
            geom, self.note = None, f"its collision geometry could not be loaded ({exc})"
        if geom is not None and geom.ngeoms == 0:
            geom, self.note = None, "its URDF has no <collision> geometry"
        self.available = geom is not None
        if geom is None:
            return
        n_own = geom.ngeoms
        for k, box in enumerate(obstacles):
            shape = coal.Box(*box.size)
            placement = pin.SE3(np.eye(3), np.array(box.centre))
            geom.addGeometryObject(pin.GeometryObject(f"obstacle_{k}", 0, placement, shape))
        parents = list(mech.model.parents)
        objs = geom.geometryObjects
        own: list[tuple[int, int]] = []
        outer: list[tuple[int, int]] = []
        for a in range(n_own):
            ja = objs[a].parentJoint
            for b in range(a + 1, n_own):
                jb = objs[b].parentJoint
                if ja != jb and parents[ja] != jb and parents[jb] != ja:
                    own.append((a, b))
            if ja != 0:
                outer += [(a, n_own + k) for k in range(len(obstacles))]
        self._geom = geom
        touching = self._touching(own + outer, mech.q_home)
        t_own, t_outer = touching[: len(own)], touching[len(own) :]
        own = [p for p, t in zip(own, t_own, strict=True) if not t]
        outer = [p for p, t in zip(outer, t_outer, strict=True) if not t]
        self.ignored_at_home = (int(t_own.sum()), int(t_outer.sum()))
        self._set_pairs(own + outer)
        self._n_own_pairs = len(own)

    def _set_pairs(self, pairs: list[tuple[int, int]]) -> None:
        self._geom.removeAllCollisionPairs()
        for a, b in pairs:
            self._geom.addCollisionPair(pin.CollisionPair(a, b))
        self._gdata = pin.GeometryData(self._geom)
        self.n_pairs = len(pairs)

    def _touching(self, pairs: list[tuple[int, int]], q: NDArray[np.float64]) -> NDArray[np.bool_]:
        self._set_pairs(pairs)
        pin.computeCollisions(self._model, self._data, self._geom, self._gdata, q, False)
        return np.array([r.isCollision() for r in self._gdata.collisionResults], dtype=bool)

    def collisions(self, q: NDArray[np.float64]) -> tuple[bool, bool]:
        """(self-collision, obstacle collision) at the full configuration q (nq,)."""
        if not self.available or self.n_pairs == 0:
            return False, False
        hit = self._touching_current(q)
        return bool(hit[: self._n_own_pairs].any()), bool(hit[self._n_own_pairs :].any())

    def _touching_current(self, q: NDArray[np.float64]) -> NDArray[np.bool_]:
        pin.computeCollisions(self._model, self._data, self._geom, self._gdata, q, False)
        return np.array([r.isCollision() for r in self._gdata.collisionResults], dtype=bool)

    def names(self, q: NDArray[np.float64]) -> list[tuple[str, str]]:
        """The geometry name pairs in contact at q (for messages and tests)."""
        if not self.available:
            return []
        hit = self._touching_current(q)
        objs, pairs = self._geom.geometryObjects, self._geom.collisionPairs
        return [
            (objs[pairs[k].first].name, objs[pairs[k].second].name)
            for k in map(int, np.flatnonzero(hit))
        ]

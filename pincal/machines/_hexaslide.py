"""Seed-001 6-PUS geometry tables ↔ the ``pus54`` parameters of ``hexaslide_6pus``.

The paper describes leg i by the platform S-joint centre a_i (platform frame), the
guide point b_i (base frame), the guide direction angles θ_i, ψ_i with
``u_i = (sinθ cosψ, sinθ sinψ, cosθ)`` and the link length L_i. The model's
``pus54`` preset displaces joint origins instead (see models/hexaslide_6pus/README.md):
a_i and b_i and L_i map one-to-one onto translations; θ_i, ψ_i are the ``ry``, ``rz``
rotation of the slide origin, which equal δθ, δψ only to first order. This module
converts exactly in both directions, so a paper table can be the "true machine" of a
simulation and identified values can be printed in the paper's terms.

All values SI (m, rad); :func:`legs_from_table` reads the paper's mm tables.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pincal.errors import ParameterError
from pincal.model import Mechanism, ParameterSet

__all__ = ["LegGeometry", "leg_geometry", "legs_from_table", "pus54_values"]

N_LEGS = 6


@dataclass(frozen=True)
class LegGeometry:
    """One 6-PUS leg in the paper's terms.

    Attributes:
        a: (3,) S-joint centre in the platform frame [m].
        b: (3,) guide point (slider U-centre at q = 0) in the base frame [m].
        theta, psi: guide direction angles [rad].
        L: link length [m].
    """

    a: np.ndarray
    b: np.ndarray
    theta: float
    psi: float
    L: float

    @property
    def u(self) -> np.ndarray:
        """Unit guide direction (3,) in the base frame."""
        st = np.sin(self.theta)
        return np.array([st * np.cos(self.psi), st * np.sin(self.psi), np.cos(self.theta)])

    def as_row(self) -> np.ndarray:
        """(9,) [a (3) m, b (3) m, θ rad, ψ rad, L m] — the paper's column order."""
        return np.r_[self.a, self.b, self.theta, self.psi, self.L]


def legs_from_table(table: Sequence[Mapping]) -> list[LegGeometry]:
    """Legs from a paper table (``{a: [mm]*3, b: [mm]*3, theta, psi [rad], L [mm]}`` × 6)."""
    if len(table) != N_LEGS:
        raise ParameterError(f"a 6-PUS table has {N_LEGS} legs, got {len(table)}")
    return [
        LegGeometry(
            a=np.asarray(row["a"], dtype=float) * 1e-3,
            b=np.asarray(row["b"], dtype=float) * 1e-3,
            theta=float(row["theta"]),
            psi=float(row["psi"]),
            L=float(row["L"]) * 1e-3,
        )
        for row in table
    ]


def _origin(mech: Mechanism, joint: str) -> pin.SE3:
    try:
        return mech.tree.joints[joint].origin
    except KeyError as exc:
        raise ParameterError(
            f"joint {joint!r} not found: is {mech.name!r} the hexaslide_6pus model?"
        ) from exc


def leg_geometry(mech: Mechanism) -> list[LegGeometry]:
    """The paper's description of each leg of a (possibly calibrated) hexaslide model."""
    legs = []
    for i in range(1, N_LEGS + 1):
        guide = _origin(mech, f"leg{i}_guide_joint")
        slide = _origin(mech, f"leg{i}_slide")
        u = guide.rotation @ slide.rotation @ mech.tree.joints[f"leg{i}_slide"].axis
        u = u / np.linalg.norm(u)
        tip = _origin(mech, f"leg{i}_tip_joint")
        legs.append(
            LegGeometry(
                a=_origin(mech, f"platform_p{i}_joint").translation.copy(),
                b=(guide * slide).translation.copy(),
                theta=float(np.arccos(np.clip(u[2], -1.0, 1.0))),
                psi=float(np.arctan2(u[1], u[0])),
                L=float(np.linalg.norm(tip.translation)),
            )
        )
    return legs


def _slide_rotation(R0: np.ndarray, axis: np.ndarray, u_target: np.ndarray) -> np.ndarray:
    """(ry, rz) with ``R0 · exp3([0, ry, rz]) · axis = u_target`` (Gauss–Newton, exact)."""
    w = np.zeros(2)
    for _ in range(50):
        W = np.array([0.0, w[0], w[1]])
        R = pin.exp3(W)
        r = R0 @ R @ axis - u_target
        if np.linalg.norm(r) < 1e-15:
            break
        # d(R·axis)/dW = -R [axis]× Jr(W)
        J = -(R0 @ R @ pin.skew(axis) @ pin.Jexp3(W))[:, 1:]
        w = w - np.linalg.lstsq(J, r, rcond=None)[0]
    else:  # pragma: no cover - the map is smooth and well conditioned near 0
        raise ParameterError(f"guide direction {u_target} cannot be reached by ry, rz")
    return w


def pus54_values(mech: Mechanism, params: ParameterSet, legs: Sequence[LegGeometry]) -> np.ndarray:
    """Values of ``params`` (a ``pus54``-like set) that give ``mech`` the geometry ``legs``.

    Args:
        mech: the nominal hexaslide mechanism ``params`` was built for.
        params: must contain every parameter the conversion needs (the 54 of ``pus54``).
        legs: the target geometry (six legs).

    Returns:
        (n,) values [m, rad] with ``leg_geometry(params.apply(mech, values)) == legs``.
    """
    if len(legs) != N_LEGS:
        raise ParameterError(f"expected {N_LEGS} legs, got {len(legs)}")
    values = np.zeros(len(params))
    nominal = leg_geometry(mech)
    for i, (leg, nom) in enumerate(zip(legs, nominal, strict=True), start=1):
        for k, axis in enumerate("xyz"):
            values[params.index(f"platform_p{i}_joint.t{axis}")] = leg.a[k] - nom.a[k]
            values[params.index(f"leg{i}_guide_joint.t{axis}")] = leg.b[k] - nom.b[k]
        slide = mech.tree.joints[f"leg{i}_slide"]
        R0 = _origin(mech, f"leg{i}_guide_joint").rotation @ slide.origin.rotation
        ry, rz = _slide_rotation(R0, slide.axis, leg.u)
        values[params.index(f"leg{i}_slide.ry")] = ry
        values[params.index(f"leg{i}_slide.rz")] = rz
        values[params.index(f"leg{i}_tip_joint.tz")] = leg.L - nom.L
    return values

"""LinuxCNC ``genhexkins``: a hexapod as six strut-end point pairs.

genhexkins (LinuxCNC man page ``genhexkins(9)``) describes a Stewart platform by the
base end ``b_i`` of each strut in the base (world) frame and the platform end ``p_i``
in the platform frame, i = 0..5, set as HAL pins ``genhexkins.base.N.x|y|z`` and
``genhexkins.platform.N.x|y|z`` [machine length unit; here m]. Its joints are the strut
lengths; with the platform pose ``(R, t)`` in the base frame (world position XYZ,
``R = Rz(C)·Ry(B)·Rx(A)``), the inverse kinematics is closed-form::

    L_i = | R·p_i + t − b_i |                                   (1)

and the forward kinematics solves (1) for ``(R, t)`` by Newton's method from the
previous pose. pincal's strut joints are read as ``q_i``; the exported per-joint zero
offset ``c_i`` makes ``L_i = q_i + c_i`` (2): add ``c_i`` to the joint's HOME_OFFSET
(and HOME) in the INI file so that LinuxCNC's joint position is the strut length.

What (1)–(2) cannot hold: a strut whose base end is not one fixed point (the U joint's
axes do not intersect, or the prismatic axis misses the joint centres), a platform
joint that is not a point (a non-``3d`` closure: refused), an actuator scale
(``L = (1 + g) q + c``: set it in the joint's position scale instead) and any other
joint term. The exported points are least-squares fits over workspace poses (means of
the point positions, ``c_i = mean(L_i − q_i)``); what they miss is in the projection.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np
import pinocchio as pin

from pincal.errors import ExportError
from pincal.export._format import Built, ControllerFormat, fmt_number
from pincal.export._machine import CalibratedMachine

__all__ = ["GenHexKins"]

#: a point or length that varies over the workspace by more is reported [m]
_SPREAD_TOL = 1e-9


def _legs(machine: CalibratedMachine) -> list[tuple[str, str, str]]:
    """Per actuated strut (in joint order): (joint, base-end frame, platform-end frame).

    Raises:
        ExportError: not six prismatic struts, each closed on the platform by a point.
    """
    mech = machine.calibrated
    joints = mech.tree.joints
    if len(mech.actuated) != 6 or any(joints[j].type != "prismatic" for j in mech.actuated):
        raise ExportError(
            f"genhexkins describes a hexapod of 6 prismatic struts; {mech.name!r} actuates "
            f"{[f'{j} ({joints[j].type})' for j in mech.actuated]} (use --format generic-table)"
        )
    by_child = {uj.child: uj for uj in joints.values()}
    legs = []
    for joint in mech.actuated:
        below = {joints[joint].child}
        grew = True
        while grew:
            new = {uj.child for uj in joints.values() if uj.parent in below} - below
            below |= new
            grew = bool(new)
        match = [c for c in mech.closures if (c.frame_a in below) != (c.frame_b in below)]
        if len(match) != 1 or not match[0].is_point:
            raise ExportError(
                f"genhexkins needs strut {joint!r} closed on the platform by one point joint "
                f"(a 3d closure); it has {[m.label for m in match] or 'none'}"
            )
        platform = match[0].frame_b if match[0].frame_a in below else match[0].frame_a
        parent = by_child.get(joints[joint].parent)
        if parent is None:
            raise ExportError(f"strut {joint!r} hangs from the base with no joint before it")
        legs.append((joint, parent.name, platform))
    return legs


class GenHexKins(ControllerFormat):
    """``linuxcnc-genhexkins``: HAL ``setp`` lines of the strut ends, joint offsets."""

    name: ClassVar[str] = "linuxcnc-genhexkins"
    suffix: ClassVar[str] = ".hal"
    summary: ClassVar[str] = "LinuxCNC genhexkins base/platform strut ends (HAL) + offsets"

    def build(self, machine: CalibratedMachine, q_fit: np.ndarray) -> Built:
        legs = _legs(machine)
        mech = machine.calibrated
        frame = mech.measured_frame
        m, n = len(q_fit), len(legs)
        base = np.empty((m, n, 3))
        plat = np.empty((m, n, 3))
        length = np.empty((m, n))
        for s, q in enumerate(q_fit):
            qf = machine.configuration(q)
            M = mech.frame_placement(qf, frame)
            for i, (_, base_frame, plat_frame) in enumerate(legs):
                b = mech.frame_placement(qf, base_frame).translation
                w = mech.frame_placement(qf, plat_frame).translation
                base[s, i], plat[s, i] = b, M.actInv(w)
                length[s, i] = np.linalg.norm(w - b)
        b_fit, p_fit = base.mean(axis=0), plat.mean(axis=0)
        c_fit = (length - q_fit).mean(axis=0)
        # the numbers as written are the numbers the controller uses
        b_w = np.vectorize(lambda v: float(fmt_number(v)))(b_fit)
        p_w = np.vectorize(lambda v: float(fmt_number(v)))(p_fit)
        c_w = np.vectorize(lambda v: float(fmt_number(v)))(c_fit)

        missing = []
        for i, (joint, base_frame, _) in enumerate(legs):
            moved = np.linalg.norm(base[:, i] - b_fit[i], axis=1).max()
            if moved > _SPREAD_TOL:
                missing.append(
                    f"strut {joint}: its base end {base_frame!r} is not a fixed point "
                    f"(moves {moved * 1e3:.3g} mm over the workspace)"
                )
            spread = np.abs(length[:, i] - q_fit[:, i] - c_fit[i]).max()
            if spread > _SPREAD_TOL:
                missing.append(
                    f"strut {joint}: length - reading is not a constant offset "
                    f"(varies by {spread * 1e3:.3g} mm: actuator scale or off-centre joints)"
                )
        gains = machine.gains()
        missing += [
            f"actuator scale {j}.gain = {g:.6g} (genhexkins has none: multiply the joint's "
            f"position scale by {1 + g:.9g})"
            for j, g in gains.items()
        ]
        missing += [f"joint term {t}" for t in machine.terms_not_held(("gain", "offset"))]

        def inverse(poses: np.ndarray) -> np.ndarray:
            world = np.einsum("mij,nj->mni", poses[:, :3, :3], p_w) + poses[:, None, :3, 3]
            return np.linalg.norm(world - b_w, axis=2) - c_w

        def forward(q_act: np.ndarray) -> np.ndarray:
            out = np.empty((len(q_act), 4, 4))
            for s, q in enumerate(q_act):
                out[s] = _newton(b_w, p_w, q + c_w, machine.reference(q[None])[0])
            return out

        lines = [
            "# genhexkins: leg length L_i = |R p_i + t - b_i| (R = Rz(C) Ry(B) Rx(A), t = XYZ)",
            f"# base frame: world of {mech.name!r}; platform frame: {frame!r}; unit: m",
        ]
        for key, pts in (("base", b_w), ("platform", p_w)):
            for i, pt in enumerate(pts):
                lines += [
                    f"setp genhexkins.{key}.{i}.{axis} {fmt_number(v)}"
                    for axis, v in zip("xyz", pt, strict=True)
                ]
        lines.append("# per-joint zero offsets c_i [m]: L_i = reading_i + c_i;")
        lines.append("# add c_i to [JOINT_i]HOME_OFFSET and HOME in the INI file")
        lines += [
            f"# joint.{i}.offset = {fmt_number(c)}  ({joint})"
            for i, (c, (joint, _, _)) in enumerate(zip(c_w, legs, strict=True))
        ]
        conventions = [
            "joint N = the model's actuated joint N: "
            + ", ".join(f"{i}={j}" for i, (j, _, _) in enumerate(legs)),
            "points and offsets are means over workspace poses (exact when they are constant)",
        ]
        return Built("\n".join(lines) + "\n", forward, missing, conventions, inverse)


def _newton(
    base: np.ndarray, plat: np.ndarray, lengths: np.ndarray, start: np.ndarray
) -> np.ndarray:
    """The pose (4, 4) whose leg lengths (1) are ``lengths``, by Newton from ``start``.

    Rotation updates ``R ← exp3(ω) R``; Jacobian rows ``[u_iᵀ, ((R p_i) × u_i)ᵀ]`` with
    the unit leg direction ``u_i``. Stops at a step below 1e-14 m or after 50 steps.
    """
    R, t = start[:3, :3].copy(), start[:3, 3].copy()
    for _ in range(50):
        rp = plat @ R.T
        leg = rp + t - base
        L = np.linalg.norm(leg, axis=1)
        u = leg / L[:, None]
        J = np.hstack([u, np.cross(rp, u)])
        step = np.linalg.solve(J, lengths - L)
        t += step[:3]
        R = pin.exp3(step[3:]) @ R
        if np.abs(step).max() < 1e-14:
            break
    out = np.eye(4)
    out[:3, :3], out[:3, 3] = R, t
    return out

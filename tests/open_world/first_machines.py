"""Machines a new user writes first (issue 36), as URDF text + sidecar dict.

* :func:`delta_elbows`: a Delta robot whose six rods hang from their arms by one joint
  each (``elbow<i>a``, ``elbow<i>b``) and meet a floating platform in six ``3D``
  closures. The rod ends must be spherical; a new user writes them as plain revolutes
  about the arm's hinge axis (``kind="revolute"``), a careful one declares them spherical
  in the sidecar (``joint_name``/``joint_type``, the robot.yaml habit).
* :func:`spherical_3rrr`: a spherical parallel manipulator (3-RRR wrist): three legs of
  three revolutes whose axes all meet at one point, the moving platform hanging from
  leg 1 and closed to legs 2 and 3 by ``6d`` welds; measured: the platform orientation.

The file pose (q = 0) is the assembled home. Lengths in m, angles in rad.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from tests.open_world.machines import (
    HALF_W,
    L_ARM,
    L_ROD,
    R_BASE,
    R_PLAT,
    THETA,
    _joint,
    _link,
    _ry,
    _rz,
    _se3,
)

__all__ = ["delta_elbows", "spherical_3rrr"]


def _frame_z(direction: np.ndarray) -> np.ndarray:
    """A rotation whose z axis is ``direction`` (3,) and whose y axis stays horizontal-ish."""
    z = direction / np.linalg.norm(direction)
    y = np.cross(z, [1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.cross(z, [0.0, 1.0, 0.0])
    y /= np.linalg.norm(y)
    return np.column_stack([np.cross(y, z), y, z])


def delta_elbows(kind: str = "revolute", rod_tilt: float = 0.0) -> tuple[str, dict]:
    """Delta robot with rods on ``elbow<i>a``/``elbow<i>b`` joints and a floating platform.

    Leg i (φ = 120°·(i−1)): ``hinge<i>`` (actuated, axis y of the leg, ±0.3 rad), arm
    0.25 m; two rods of 0.5 m from the arm end at ±0.03 m along the hinge axis, each on an
    elbow joint (URDF revolute about the hinge axis); the rod tips ``tip<i>a``/``tip<i>b``
    are closed (``3D``) to the platform anchors ``anchor<i>a``/``anchor<i>b``. ``kind``:
    ``"revolute"`` leaves the elbows plain revolutes (the mistake), ``"spherical"`` adds
    the sidecar ``joint_name``/``joint_type: SPHERICAL`` for them. Measured: the position
    of ``tcp`` 0.02 m below the platform centre. ``rod_tilt`` [rad] turns rod ``1a`` out
    of its arm's plane (about the leg's radial axis) in the file, as a CAD export drawn
    with the rod off its anchor: a revolute elbow cannot turn it back, a ball end can.
    """
    h = L_ARM * np.sin(THETA) + np.sqrt(L_ROD**2 - (R_BASE + L_ARM * np.cos(THETA) - R_PLAT) ** 2)
    platform = _se3(p=(0, 0, -h))
    links = [_link("base_link"), _link("platform"), _link("tcp")]
    joints = [
        '  <joint name="platform_free" type="floating"><parent link="base_link"/>'
        f'<child link="platform"/><origin xyz="0 0 {-h:.17g}" rpy="0 0 0"/></joint>\n',
        _joint("tcp_joint", "fixed", "platform", "tcp", _se3(p=(0, 0, -0.02))),
    ]
    closures, elbows = [], []
    for i in (1, 2, 3):
        leg = _rz(np.radians(120.0 * (i - 1)))
        arm_w = _se3(leg @ _ry(THETA), leg @ np.array([R_BASE, 0.0, 0.0]))
        links.append(_link(f"arm{i}"))
        joints.append(
            _joint(f"hinge{i}", "revolute", "base_link", f"arm{i}", arm_w, "0 1 0", (-0.3, 0.3))
        )
        for side, dy in (("a", HALF_W), ("b", -HALF_W)):
            elbow_w = arm_w.act(np.array([L_ARM, dy, 0.0]))
            anchor_w = platform.translation + leg @ np.array([R_PLAT, dy, 0.0])
            rod_w = pin.SE3(_frame_z(anchor_w - elbow_w), elbow_w)
            if (i, side) == (1, "a") and rod_tilt:
                rod_w.rotation = pin.exp3(rod_tilt * (leg @ np.array([1.0, 0.0, 0.0]))) @ (
                    rod_w.rotation
                )
            in_arm = arm_w.inverse() * rod_w
            axis = _fmt3(in_arm.rotation.T @ np.array([0.0, 1.0, 0.0]))  # the hinge axis
            rod, tip, anchor = f"rod{i}{side}", f"tip{i}{side}", f"anchor{i}{side}"
            links += [_link(rod), _link(tip), _link(anchor)]
            elbows.append(f"elbow{i}{side}")
            joints += [
                _joint(f"elbow{i}{side}", "revolute", f"arm{i}", rod, in_arm, axis, None),
                _joint(f"{tip}_joint", "fixed", rod, tip, _se3(p=(0, 0, L_ROD))),
                _joint(
                    f"{anchor}_joint",
                    "fixed",
                    "platform",
                    anchor,
                    _se3(p=anchor_w - platform.translation),
                ),
            ]
            closures.append([tip, anchor])
    urdf = '<?xml version="1.0"?>\n<robot name="delta">\n' + "".join(links + joints) + "</robot>\n"
    sidecar: dict = {
        "closed_loop": closures,
        "type": ["3D"] * len(closures),
        "name_mot": ["hinge1", "hinge2", "hinge3"],
        "measured_frame": "tcp",
        "measured": "position",
        "workspace": {"joints": {f"hinge{i}": [-0.25, 0.25] for i in (1, 2, 3)}},
    }
    if kind == "spherical":
        sidecar["joint_name"] = elbows
        sidecar["joint_type"] = ["SPHERICAL"] * len(elbows)
    elif kind != "revolute":
        raise ValueError(f"kind must be 'revolute' or 'spherical', not {kind!r}")
    return urdf, sidecar


def _fmt3(v: np.ndarray) -> str:
    return " ".join(f"{0.0 if abs(x) < 1e-15 else x:.17g}" for x in v)


SPM_CENTRE = (0.0, 0.0, 0.3)
"""Centre [m] of the spherical 3-RRR: every joint axis passes through it."""

SPM_RANGE = (-0.3, 0.3)
"""Actuator range [rad] of the spherical 3-RRR around its home (q = 0)."""


def _spm_axes(phi: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit axes (base u, elbow w, platform v) of the leg at azimuth ``phi`` [rad], home."""

    def spread(azimuth: float, polar: float) -> np.ndarray:
        return np.array(
            [np.sin(polar) * np.cos(azimuth), np.sin(polar) * np.sin(azimuth), np.cos(polar)]
        )

    u = spread(phi, np.radians(125.0))  # down and out, under the centre
    w = spread(phi + np.radians(55.0), np.radians(85.0))  # about horizontal, turned
    v = spread(phi + np.radians(20.0), np.radians(40.0))  # up and out, the platform's
    return u, w, v


def spherical_3rrr() -> tuple[str, dict]:
    """A spherical parallel manipulator (3-RRR wrist), every axis through ``SPM_CENTRE``.

    Leg i (azimuth 120°·(i−1)): ``base<i>`` (actuated, ±0.3 rad), ``elbow<i>``,
    ``wrist<i>``, their joint origins 0.15 m from the centre along their axes (URDF axis
    z of each joint frame). The platform (frame at the centre, world axes at home) hangs
    from leg 1's ``wrist1``; legs 2 and 3 end in ``end2``/``end3`` at the same place,
    welded (``6d``) to it: closures whose translation rows are redundant. Measured: the
    pose of ``tool`` 0.1 m above the centre on the platform.
    """
    centre = np.array(SPM_CENTRE)
    links, joints, closures = [_link("base_link")], [], []
    for i in (1, 2, 3):
        axes = _spm_axes(np.radians(120.0 * (i - 1)))
        parent, parent_w = "base_link", pin.SE3.Identity()
        for name, axis in zip((f"base{i}", f"elbow{i}", f"wrist{i}"), axes, strict=True):
            frame_w = pin.SE3(_frame_z(axis), centre + 0.15 * axis)
            link = f"{name}_link"
            limit = SPM_RANGE if name.startswith("base") else None
            links.append(_link(link))
            joints.append(
                _joint(name, "revolute", parent, link, parent_w.inverse() * frame_w, limit=limit)
            )
            parent, parent_w = link, frame_w
        at_centre = parent_w.inverse() * pin.SE3(np.eye(3), centre)
        if i == 1:
            links += [_link("platform"), _link("tool")]
            joints.append(_joint("platform_mount", "fixed", parent, "platform", at_centre))
            joints.append(_joint("tool_mount", "fixed", "platform", "tool", _se3(p=(0, 0, 0.1))))
        else:
            links.append(_link(f"end{i}"))
            joints.append(_joint(f"end{i}_mount", "fixed", parent, f"end{i}", at_centre))
            closures.append([f"end{i}", "platform"])
    urdf = (
        '<?xml version="1.0"?>\n<robot name="spm3rrr">\n' + "".join(links + joints) + "</robot>\n"
    )
    sidecar = {
        "closed_loop": closures,
        "type": ["6d"] * len(closures),
        "name_mot": ["base1", "base2", "base3"],
        "measured_frame": "tool",
        "workspace": {"joints": {f"base{i}": list(SPM_RANGE) for i in (1, 2, 3)}},
    }
    return urdf, sidecar

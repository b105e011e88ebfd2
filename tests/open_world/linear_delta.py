"""A linear delta (Kossel-style 3D printer) as URDF text + sidecar dict.

Three vertical towers at 210°, 330° and 90° (Klipper's default stepper_a, _b, _c
angles) at radius ``TOWER_R``; each carriage (``carriage<i>``, prismatic along z, its
reading = its height [m]) holds two rods ``ROD`` long, ``HALF_W`` either side of the
tower, on spherical joints (URDF revolute placeholders declared ``SPHERICAL`` in the
sidecar); the rod tips close (``3D``) on anchors of a floating effector at
``EFFECTOR_R`` from its centre. Measured: the position of ``nozzle``, ``NOZZLE`` below
the effector centre. The effective radius of the delta equations is
``TOWER_R − EFFECTOR_R``.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from tests.open_world.first_machines import _frame_z
from tests.open_world.machines import _joint, _link, _rz, _se3

__all__ = ["ANGLES", "EFFECTOR_R", "HOME_H", "ROD", "TOWER_R", "linear_delta"]

ANGLES = np.radians([210.0, 330.0, 90.0])
TOWER_R, EFFECTOR_R, ROD, HALF_W, NOZZLE = 0.2, 0.04, 0.3, 0.025, 0.03
HOME_H = 0.35  # carriage height at home [m]
RANGE = (0.26, 0.45)  # carriage range [m]


def _prismatic(name: str, parent: str, child: str, M: pin.SE3) -> str:
    rpy = " ".join(f"{v:.17g}" for v in pin.rpy.matrixToRpy(M.rotation))
    xyz = " ".join(f"{v:.17g}" for v in M.translation)
    return (
        f'  <joint name="{name}" type="prismatic"><parent link="{parent}"/>'
        f'<child link="{child}"/><origin xyz="{xyz}" rpy="{rpy}"/><axis xyz="0 0 1"/>'
        f'<limit lower="{RANGE[0]}" upper="{RANGE[1]}" effort="1" velocity="1"/></joint>\n'
    )


def linear_delta() -> tuple[str, dict]:
    """The linear delta at home (carriages at ``HOME_H``): URDF text and sidecar."""
    drop = np.sqrt(ROD**2 - (TOWER_R - EFFECTOR_R) ** 2)
    z_eff = HOME_H - drop
    links = [_link("base_link"), _link("effector"), _link("nozzle")]
    joints = [
        '  <joint name="effector_free" type="floating"><parent link="base_link"/>'
        f'<child link="effector"/><origin xyz="0 0 {z_eff:.17g}" rpy="0 0 0"/></joint>\n',
        _joint("nozzle_joint", "fixed", "effector", "nozzle", _se3(p=(0, 0, -NOZZLE))),
    ]
    closures, pivots, home = [], [], {}
    for i, a in enumerate(ANGLES, start=1):
        R = _rz(a)
        links.append(_link(f"carriage{i}"))
        joints.append(
            _prismatic(f"carriage{i}", "base_link", f"carriage{i}", _se3(R, R @ [TOWER_R, 0, 0]))
        )
        home[f"carriage{i}"] = HOME_H
        for side, dy in (("a", HALF_W), ("b", -HALF_W)):
            pivot_w = R @ np.array([TOWER_R, dy, HOME_H])
            anchor_e = R @ np.array([EFFECTOR_R, dy, 0.0])
            anchor_w = anchor_e + np.array([0.0, 0.0, z_eff])
            rod_w = pin.SE3(_frame_z(anchor_w - pivot_w), pivot_w)
            carriage_w = _se3(R, R @ [TOWER_R, 0, 0] + np.array([0, 0, HOME_H]))
            rod, tip, anchor = f"rod{i}{side}", f"tip{i}{side}", f"anchor{i}{side}"
            links += [_link(rod), _link(tip), _link(anchor)]
            pivots.append(f"pivot{i}{side}")
            joints += [
                _joint(f"pivot{i}{side}", "revolute", f"carriage{i}", rod,
                       carriage_w.inverse() * rod_w, "0 1 0", None),
                _joint(f"{tip}_joint", "fixed", rod, tip, _se3(p=(0, 0, ROD))),
                _joint(f"{anchor}_joint", "fixed", "effector", anchor, _se3(p=anchor_e)),
            ]  # fmt: skip
            closures.append([tip, anchor])
    urdf = (
        '<?xml version="1.0"?>\n<robot name="linear_delta">\n'
        + "".join(links + joints)
        + "</robot>\n"
    )
    sidecar: dict = {
        "closed_loop": closures,
        "type": ["3D"] * len(closures),
        "name_mot": ["carriage1", "carriage2", "carriage3"],
        "measured_frame": "nozzle",
        "measured": "position",
        "joint_name": pivots,
        "joint_type": ["SPHERICAL"] * len(pivots),
        "home": home,
        "workspace": {"joints": {f"carriage{i}": [0.30, 0.40] for i in (1, 2, 3)}},
    }
    return urdf, sidecar

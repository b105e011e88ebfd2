"""Machines exported the way CAD plug-ins write them (URDF text + sidecar dict).

* :func:`fivebar_cad`: a planar five-bar in a tilted plane, every link frame aligned with
  the world and every number rounded to 7 significant digits (the exporter's habit),
  its loop closed by a ``6d`` weld at the distal joint. The joint axes stay exactly
  parallel (one rounded normal for all), but the rounded origins no longer put the two
  chain ends in one plane: the weld's out-of-plane rows are redundant (zero Jacobian)
  and miss closing by ~1e-8 m, as MuJoCo closes such exports to 1e-8..1e-7 m.

Lengths in m, angles in rad.
"""

from __future__ import annotations

import numpy as np

_INERTIAL = (
    '<inertial><mass value="0.1"/><origin xyz="0 0 0"/>'
    '<inertia ixx="1e-5" ixy="0" ixz="0" iyy="1e-5" iyz="0" izz="1e-5"/></inertial>'
)


def _r7(v: np.ndarray) -> str:
    """Numbers as a CAD exporter writes them: 7 significant digits."""
    return " ".join(f"{x:.7g}" for x in np.atleast_1d(v))


def _link(name: str) -> str:
    return f'  <link name="{name}">{_INERTIAL}</link>\n'


def _revolute(name: str, parent: str, child: str, xyz: np.ndarray, axis: np.ndarray) -> str:
    return (
        f'  <joint name="{name}" type="revolute"><parent link="{parent}"/>'
        f'<child link="{child}"/><origin xyz="{_r7(xyz)}" rpy="0 0 0"/>'
        f'<axis xyz="{_r7(axis)}"/><limit lower="-3" upper="3" effort="1" velocity="1"/>'
        "</joint>\n"
    )


def _fixed(name: str, parent: str, child: str, xyz: np.ndarray) -> str:
    return (
        f'  <joint name="{name}" type="fixed"><parent link="{parent}"/>'
        f'<child link="{child}"/><origin xyz="{_r7(xyz)}" rpy="0 0 0"/></joint>\n'
    )


#: base half-spacing, proximal and distal link lengths [m]
FIVEBAR_CAD = (0.0713, 0.1427, 0.2183)


def fivebar_cad(tilt: float = 0.4137) -> tuple[str, dict]:
    """The five-bar of the module doc; ``tilt`` [rad] turns its plane about x then y."""
    d, l1, l2 = FIVEBAR_CAD
    c, s = np.cos(tilt), np.sin(tilt)
    R = np.array([[1, 0, 0], [0, c, -s], [0, s, c]]) @ np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    origin = np.array([0.0312, -0.0457, 0.1034])

    def world(x: float, y: float) -> np.ndarray:
        return origin + R @ np.array([x, y, 0.0])

    a_l, a_r = np.radians(118.0), np.radians(62.0)  # home motor angles
    A, B = np.array([-d, 0.0]), np.array([d, 0.0])
    E_l = A + l1 * np.array([np.cos(a_l), np.sin(a_l)])
    E_r = B + l1 * np.array([np.cos(a_r), np.sin(a_r)])
    mid, half = 0.5 * (E_l + E_r), 0.5 * np.linalg.norm(E_r - E_l)
    normal = np.array([-(E_r - E_l)[1], (E_r - E_l)[0]]) / (2 * half)
    P = mid + np.sqrt(l2**2 - half**2) * normal  # the distal joint, elbows out
    n = R[:, 2]
    pts = {k: world(*v) for k, v in {"A": A, "B": B, "El": E_l, "Er": E_r, "P": P}.items()}
    links = ["base", "prox_l", "dist_l", "tip_l", "prox_r", "dist_r", "tip_r", "tool"]
    joints = [
        _revolute("mot_l", "base", "prox_l", pts["A"], n),
        _revolute("elbow_l", "prox_l", "dist_l", pts["El"] - pts["A"], n),
        _revolute("tip_joint", "dist_l", "tip_l", pts["P"] - pts["El"], n),
        _revolute("mot_r", "base", "prox_r", pts["B"], n),
        _revolute("elbow_r", "prox_r", "dist_r", pts["Er"] - pts["B"], n),
        _fixed("tip_r_joint", "dist_r", "tip_r", pts["P"] - pts["Er"]),
        _fixed("tool_joint", "dist_l", "tool", pts["P"] - pts["El"] + 0.02 * n),
    ]
    urdf = (
        '<?xml version="1.0"?>\n<robot name="fivebar_cad">\n'
        + "".join(_link(k) for k in links)
        + "".join(joints)
        + "</robot>\n"
    )
    sidecar = {
        "closed_loop": [["tip_l", "tip_r"]],
        "type": ["6d"],
        "name_mot": ["mot_l", "mot_r"],
        "measured_frame": "tool",
        "measured": "position",
        "workspace": {"joints": {"mot_l": [-0.15, 0.15], "mot_r": [-0.15, 0.15]}},
    }
    return urdf, sidecar

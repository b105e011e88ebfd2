"""Generate models/stewart_6ups/ (URDF + sidecar) from the nominal geometry.

Run: python scripts/models/build_stewart.py   (rewrites the two files; they are committed)

Geometry (SI): base joint centres on radius 0.300 m at −15, 15, 105, 135, 225, 255 deg
(z = 0); platform joint centres on radius 0.150 m at −45, 45, 75, 165, 195, 285 deg in
the platform frame; leg i joins base i to platform i; home platform height 0.450 m.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml
from urdf_snippets import INERTIAL, sphere_visual

OUT = Path(__file__).resolve().parents[2] / "models" / "stewart_6ups"
R_BASE, R_PLATFORM, HOME_Z = 0.300, 0.150, 0.450
BASE_DEG = (-15, 15, 105, 135, 225, 255)
PLATFORM_DEG = (-45, 45, 75, 165, 195, 285)
LEG_LIMITS = (0.30, 0.70)  # [m]


def circle(radius: float, degrees: tuple[int, ...], z: float = 0.0) -> np.ndarray:
    a = np.radians(degrees)
    return np.stack([radius * np.cos(a), radius * np.sin(a), np.full(a.size, z)], axis=1)


def vec(v: np.ndarray) -> str:
    return " ".join(f"{x:.12g}" for x in v)


def cylinder_visual(length: float, radius: float, direction: np.ndarray, colour: str) -> str:
    """A cylinder from the link origin along ``direction`` (unit) of the given length."""
    d = direction / np.linalg.norm(direction)
    pitch = np.arccos(np.clip(d[2], -1, 1))
    yaw = np.arctan2(d[1], d[0])
    centre = d * length / 2
    return (
        f'<visual><origin xyz="{vec(centre)}" rpy="0 {pitch:.12g} {yaw:.12g}"/>'
        f'<geometry><cylinder radius="{radius}" length="{length:.6g}"/></geometry>'
        f'<material name="{colour}"/></visual>'
    )


def build() -> tuple[str, dict]:
    b = circle(R_BASE, BASE_DEG)
    a = circle(R_PLATFORM, PLATFORM_DEG)
    p_home = a + np.array([0, 0, HOME_Z])
    parts = [
        '<?xml version="1.0"?>',
        '<robot name="stewart_6ups">',
        '<material name="grey"><color rgba="0.6 0.6 0.65 1"/></material>',
        '<material name="blue"><color rgba="0.2 0.4 0.8 1"/></material>',
        '<material name="orange"><color rgba="0.95 0.55 0.1 1"/></material>',
        '<material name="red"><color rgba="0.85 0.15 0.15 1"/></material>',
        '<link name="world"><visual><origin xyz="0 0 -0.01"/><geometry>'
        f'<cylinder radius="{R_BASE + 0.04:.6g}" length="0.02"/></geometry>'
        '<material name="grey"/></visual></link>',
    ]
    home = {}
    for i in range(6):
        n = i + 1
        d = p_home[i] - b[i]
        length = float(np.linalg.norm(d))
        d /= length
        axis1 = np.cross([0.0, 0.0, 1.0], d)
        axis1 /= np.linalg.norm(axis1)
        axis2 = np.cross(d, axis1)
        home[f"leg{n}_slide"] = round(length, 9)
        parts += [
            f'<link name="leg{n}_u1_link">{INERTIAL}</link>',
            f'<link name="leg{n}_u2_link">{INERTIAL}'
            f"{cylinder_visual(0.25, 0.018, d, 'blue')}{sphere_visual(0.022, 'grey')}</link>",
            f'<link name="leg{n}_rod">{INERTIAL}'
            f"{cylinder_visual(0.22, 0.011, -d, 'orange')}</link>",
            f'<link name="leg{n}_tip">{sphere_visual(0.014, "grey")}</link>',
            f'<joint name="leg{n}_u1" type="revolute"><parent link="world"/>'
            f'<child link="leg{n}_u1_link"/><origin xyz="{vec(b[i])}" rpy="0 0 0"/>'
            f'<axis xyz="{vec(axis1)}"/><limit lower="-1.2" upper="1.2" effort="1" velocity="1"/>'
            "</joint>",
            f'<joint name="leg{n}_u2" type="revolute"><parent link="leg{n}_u1_link"/>'
            f'<child link="leg{n}_u2_link"/><origin xyz="0 0 0" rpy="0 0 0"/>'
            f'<axis xyz="{vec(axis2)}"/><limit lower="-1.2" upper="1.2" effort="1" velocity="1"/>'
            "</joint>",
            f'<joint name="leg{n}_slide" type="prismatic"><parent link="leg{n}_u2_link"/>'
            f'<child link="leg{n}_rod"/><origin xyz="0 0 0" rpy="0 0 0"/>'
            f'<axis xyz="{vec(d)}"/>'
            f'<limit lower="{LEG_LIMITS[0]}" upper="{LEG_LIMITS[1]}" effort="1" velocity="1"/>'
            "</joint>",
            f'<joint name="leg{n}_tip_joint" type="fixed"><parent link="leg{n}_rod"/>'
            f'<child link="leg{n}_tip"/><origin xyz="0 0 0" rpy="0 0 0"/></joint>',
        ]
    parts += [
        '<link name="platform"><inertial><mass value="2"/><inertia ixx="0.01" iyy="0.01" '
        'izz="0.02" ixy="0" ixz="0" iyz="0"/></inertial><visual><geometry>'
        f'<cylinder radius="{R_PLATFORM + 0.03:.6g}" length="0.015"/></geometry>'
        '<material name="grey"/></visual></link>',
        '<joint name="platform_joint" type="floating"><parent link="world"/>'
        '<child link="platform"/><origin xyz="0 0 0" rpy="0 0 0"/></joint>',
        '<link name="effector"><visual><origin xyz="0 0 0.03"/><geometry>'
        '<box size="0.03 0.03 0.06"/></geometry><material name="red"/></visual></link>',
        '<joint name="effector_joint" type="fixed"><parent link="platform"/>'
        '<child link="effector"/><origin xyz="0 0 0" rpy="0 0 0"/></joint>',
    ]
    for i in range(6):
        n = i + 1
        parts += [
            f'<link name="platform_p{n}"/>',
            f'<joint name="platform_p{n}_joint" type="fixed"><parent link="platform"/>'
            f'<child link="platform_p{n}"/><origin xyz="{vec(a[i])}" rpy="0 0 0"/></joint>',
        ]
    parts.append("</robot>")
    home["platform_joint"] = [0.0, 0.0, HOME_Z, 0.0, 0.0, 0.0]
    sidecar = {
        "closed_loop": [[f"leg{n}_tip", f"platform_p{n}"] for n in range(1, 7)],
        "type": ["3d"] * 6,
        "name_mot": [f"leg{n}_slide" for n in range(1, 7)],
        "measured_frame": "effector",
        "measured": "pose",
        "home": home,
        "workspace": {
            "pose": {
                "x": [-0.06, 0.06],
                "y": [-0.06, 0.06],
                "z": [0.41, 0.49],
                "rx": [-0.15, 0.15],
                "ry": [-0.15, 0.15],
                "rz": [-0.15, 0.15],
            }
        },
        "presets": {
            "stewart42": [
                entry
                for n in range(1, 7)
                for entry in (
                    {"joints": f"leg{n}_u1", "dofs": ["tx", "ty", "tz"]},
                    {"joints": f"platform_p{n}_joint", "dofs": ["tx", "ty", "tz"]},
                    {"joints": f"leg{n}_slide", "dofs": ["offset"]},
                )
            ],
        },
    }
    return "\n".join(parts) + "\n", sidecar


def main() -> None:
    urdf, sidecar = build()
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "stewart_6ups.urdf").write_text(urdf, encoding="utf-8")
    header = (
        "# Sidecar of the 6-UPS Stewart platform (generated by scripts/models/build_stewart.py)\n"
    )
    text = yaml.safe_dump(sidecar, sort_keys=False, default_flow_style=None, width=100)
    (OUT / "stewart_6ups.yaml").write_text(header + text, encoding="utf-8")
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()

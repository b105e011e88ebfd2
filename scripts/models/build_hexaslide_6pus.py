"""Generate models/hexaslide_6pus/ (URDF + sidecar) from the nominal table of seed 001.

Run: python scripts/models/build_hexaslide_6pus.py   (rewrites the two files; they are committed)

Source: scripts/data/seed001.yaml (paper units mm, rad); the model is in metres.
Tree per leg i (see models/hexaslide_6pus/README.md):

    base ─leg{i}_guide_joint (fixed, xyz = b_i, rpy = 0)─► leg{i}_guide
         ─leg{i}_slide (prismatic, rpy = (0, 0, ψ_i), axis (sinθ_i, 0, cosθ_i))─► leg{i}_slider
         ─leg{i}_u1 (revolute, axis x)─► leg{i}_cross ─leg{i}_u2 (revolute, axis y)─► leg{i}_link
         ─leg{i}_tip_joint (fixed, xyz = (0, 0, L_i))─► leg{i}_tip
    base ─platform_float (floating, origin = home pose)─► platform
         ─platform_p{i}_joint (fixed, xyz = a_i)─► platform_p{i}
    closures: leg{i}_tip ≡ platform_p{i} (3d)
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import yaml
from urdf_snippets import INERTIAL, sphere_visual

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "scripts" / "data" / "seed001.yaml"
OUT = ROOT / "models" / "hexaslide_6pus"
NAME = "hexaslide_6pus"
MM = 1e-3
HOME_POSE = (0.0, 0.0, 460.0, 0.0, 0.0, 0.0)  # [mm, rad], simulation pose 3 of the paper
SLIDE_LIMITS = (-0.10, 0.30)  # [m]
U_LIMIT = 1.2  # [rad] passive U-joint range (home = 0)


def vec(v) -> str:
    return " ".join(f"{float(x):.15g}" for x in v)


def leg_geometry(table: list[dict]) -> dict[str, np.ndarray]:
    """Arrays in SI units from a paper table: a, b (6, 3) [m]; theta, psi (6,); L (6,) [m]."""
    a = np.array([leg["a"] for leg in table]) * MM
    b = np.array([leg["b"] for leg in table]) * MM
    theta = np.array([leg["theta"] for leg in table], dtype=float)
    psi = np.array([leg["psi"] for leg in table], dtype=float)
    L = np.array([leg["L"] for leg in table]) * MM
    u = np.column_stack([np.sin(theta) * np.cos(psi), np.sin(theta) * np.sin(psi), np.cos(theta)])
    return {"a": a, "b": b, "theta": theta, "psi": psi, "L": L, "u": u}


def pose_se3(pose) -> pin.SE3:
    """Paper pose (x, y, z [mm], α, β, γ [rad]) → SE3, R = Rz(γ) Ry(β) Rx(α)."""
    x, y, z, al, be, ga = pose
    return pin.SE3(pin.rpy.rpyToMatrix(al, be, ga), np.array([x, y, z]) * MM)


def inverse_kinematics(g: dict[str, np.ndarray], T_base_platform: pin.SE3) -> np.ndarray:
    """Closed-form slider positions q (6,) [m]: |A - (b + q u)| = L, the smaller root."""
    A = g["a"] @ T_base_platform.rotation.T + T_base_platform.translation
    d = A - g["b"]
    du = np.sum(d * g["u"], axis=1)
    disc = du**2 - np.sum(d * d, axis=1) + g["L"] ** 2
    return du - np.sqrt(disc)


def cylinder(length: float, radius: float, rpy, xyz, colour: str) -> str:
    return (
        f'<visual><origin xyz="{vec(xyz)}" rpy="{vec(rpy)}"/>'
        f'<geometry><cylinder radius="{radius}" length="{length:.6g}"/></geometry>'
        f'<material name="{colour}"/></visual>'
    )


def box(size, colour: str, xyz=(0, 0, 0)) -> str:
    return (
        f'<visual><origin xyz="{vec(xyz)}" rpy="0 0 0"/><geometry><box size="{vec(size)}"/>'
        f'</geometry><material name="{colour}"/></visual>'
    )


def build() -> tuple[str, dict]:
    data = yaml.safe_load(DATA.read_text())
    g = leg_geometry(data["nominal"])
    T_home = pose_se3(HOME_POSE)
    q_home = inverse_kinematics(g, T_home)
    parts = [
        f'<?xml version="1.0"?>\n<robot name="{NAME}">',
        '<material name="grey"><color rgba="0.6 0.6 0.6 1"/></material>',
        '<material name="steel"><color rgba="0.8 0.8 0.85 1"/></material>',
        '<material name="blue"><color rgba="0.2 0.4 0.8 1"/></material>',
        '<material name="orange"><color rgba="0.95 0.55 0.1 1"/></material>',
        f'<link name="base">{cylinder(0.02, 0.45, (0, 0, 0), (0, 0, -0.01), "grey")}</link>',
    ]
    for i in range(6):
        n = i + 1
        b, u, th, ps, L = g["b"][i], g["u"][i], g["theta"][i], g["psi"][i], g["L"][i]
        slider = b + q_home[i] * u
        A_home = T_home.act(g["a"][i])
        d = (A_home - slider) / L  # home link direction (base frame)
        x = np.cross(u, d)
        x /= np.linalg.norm(x)
        R_base_u = np.column_stack([x, np.cross(d, x), d])  # z along the link at home
        R_base_slider = pin.rpy.rpyToMatrix(0.0, 0.0, ps)
        rpy_u = pin.rpy.matrixToRpy(R_base_slider.T @ R_base_u)
        rail = 0.40
        parts += [
            f'<joint name="leg{n}_guide_joint" type="fixed"><parent link="base"/>'
            f'<child link="leg{n}_guide"/><origin xyz="{vec(b)}" rpy="0 0 0"/></joint>',
            f'<link name="leg{n}_guide">'
            f"{cylinder(rail, 0.008, (0, th, ps), u * (rail / 2 - 0.1), 'grey')}</link>",
            f'<joint name="leg{n}_slide" type="prismatic"><parent link="leg{n}_guide"/>'
            f'<child link="leg{n}_slider"/><origin xyz="0 0 0" rpy="0 0 {ps:.17g}"/>'
            f'<axis xyz="{vec([np.sin(th), 0.0, np.cos(th)])}"/>'
            f'<limit lower="{SLIDE_LIMITS[0]}" upper="{SLIDE_LIMITS[1]}" effort="1000" '
            f'velocity="0.5"/></joint>',
            f'<link name="leg{n}_slider">{INERTIAL}{box((0.04, 0.03, 0.03), "blue")}</link>',
            f'<joint name="leg{n}_u1" type="revolute"><parent link="leg{n}_slider"/>'
            f'<child link="leg{n}_cross"/><origin xyz="0 0 0" rpy="{vec(rpy_u)}"/>'
            f'<axis xyz="1 0 0"/><limit lower="{-U_LIMIT}" upper="{U_LIMIT}" effort="0" '
            f'velocity="10"/></joint>',
            f'<link name="leg{n}_cross">{INERTIAL}{sphere_visual(0.012, "steel")}</link>',
            f'<joint name="leg{n}_u2" type="revolute"><parent link="leg{n}_cross"/>'
            f'<child link="leg{n}_link"/><origin xyz="0 0 0" rpy="0 0 0"/>'
            f'<axis xyz="0 1 0"/><limit lower="{-U_LIMIT}" upper="{U_LIMIT}" effort="0" '
            f'velocity="10"/></joint>',
            f'<link name="leg{n}_link">{INERTIAL}'
            f"{cylinder(L, 0.007, (0, 0, 0), (0, 0, L / 2), 'steel')}</link>",
            f'<joint name="leg{n}_tip_joint" type="fixed"><parent link="leg{n}_link"/>'
            f'<child link="leg{n}_tip"/><origin xyz="0 0 {L:.15g}" rpy="0 0 0"/></joint>',
            f'<link name="leg{n}_tip">{sphere_visual(0.01, "orange")}</link>',
        ]
    parts += [
        '<joint name="platform_float" type="floating"><parent link="base"/>'
        f'<child link="platform"/><origin xyz="{vec(T_home.translation)}" '
        f'rpy="{vec(pin.rpy.matrixToRpy(T_home.rotation))}"/></joint>',
        f'<link name="platform">{INERTIAL}'
        f"{cylinder(0.015, 0.115, (0, 0, 0), (0, 0, g['a'][0, 2]), 'blue')}"
        f"{cylinder(0.05, 0.004, (0, 0, 0), (0, 0, 0.025), 'orange')}</link>",
    ]
    for i in range(6):
        n = i + 1
        parts += [
            f'<joint name="platform_p{n}_joint" type="fixed"><parent link="platform"/>'
            f'<child link="platform_p{n}"/><origin xyz="{vec(g["a"][i])}" rpy="0 0 0"/></joint>',
            f'<link name="platform_p{n}">{sphere_visual(0.01, "orange")}</link>',
        ]
    parts.append("</robot>\n")
    urdf = "\n".join(parts)

    preset = []
    for n in range(1, 7):  # paper order per leg: a_i, b_i, θ_i, ψ_i, L_i
        preset += [
            {"joints": f"platform_p{n}_joint", "dofs": ["tx", "ty", "tz"]},
            {"joints": f"leg{n}_guide_joint", "dofs": ["tx", "ty", "tz"]},
            {"joints": f"leg{n}_slide", "dofs": ["ry", "rz"]},
            {"joints": f"leg{n}_tip_joint", "dofs": ["tz"]},
        ]
    sidecar = {
        "closed_loop": [[f"leg{n}_tip", f"platform_p{n}"] for n in range(1, 7)],
        "type": ["3d"],
        "name_mot": [f"leg{n}_slide" for n in range(1, 7)],
        "measured_frame": "platform",
        "measured": "pose",
        "home": {f"leg{n}_slide": round(float(q_home[n - 1]), 12) for n in range(1, 7)},
        "workspace": {
            "pose": {
                "x": [-0.05, 0.05],
                "y": [-0.05, 0.05],
                "z": [0.42, 0.50],
                "rx": [-0.12, 0.12],
                "ry": [-0.15, 0.15],
                "rz": [-0.15, 0.15],
            },
            "joints": {f"leg{n}_slide": [-0.02, 0.20] for n in range(1, 7)},
        },
        "presets": {"pus54": preset},
    }
    return urdf, sidecar


HEADER = """\
# hexaslide_6pus: 6-PUS parallel mechanism of seed 001 (FAN, LI, WANG, JBUAA 2016).
# Generated by scripts/models/build_hexaslide_6pus.py from scripts/data/seed001.yaml; see README.md.
# Units: m, rad. Home = paper pose (0, 0, 460 mm, 0, 0, 0); the platform_float origin is
# that home pose, so the neutral configuration with these slider values is assembled.
"""


def main() -> None:
    urdf, sidecar = build()
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / f"{NAME}.urdf").write_text(urdf)
    (OUT / f"{NAME}.yaml").write_text(
        HEADER + yaml.safe_dump(sidecar, sort_keys=False, width=100, default_flow_style=None)
    )


if __name__ == "__main__":
    main()

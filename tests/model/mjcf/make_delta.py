"""Write delta.xml: a Delta robot in MJCF (run once; the XML is committed).

Three actuated arms (top-level bodies, hinge with ref = the file angle), each carrying a
parallelogram of two rods (ball joint at the elbow, connect to the free platform at the
far end). Lengths in m; angles in degrees in the file (eulerseq zyx).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

R, LA, LB, RP, W, THETA = 0.2, 0.25, 0.5, 0.05, 0.03, 30.0  # base, arm, rod, platform, half-width


def rz(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def ry(a: float) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def fmt(v) -> str:
    return " ".join(f"{0.0 if abs(x) < 1e-14 else x:.15g}" for x in np.atleast_1d(v))


def main() -> None:
    th = np.radians(THETA)
    h = LA * np.sin(th) + np.sqrt(LB**2 - (R + LA * np.cos(th) - RP) ** 2)
    arms, eqs, acts = [], [], []
    for i in range(3):
        phi = np.radians(120.0 * i)
        Rarm = rz(phi) @ ry(th)
        base = R * np.array([np.cos(phi), np.sin(phi), 0.0])
        elbow = base + Rarm @ np.array([LA, 0.0, 0.0])
        attach = np.array([0.0, 0.0, -h]) + RP * np.array([np.cos(phi), np.sin(phi), 0.0])
        z_rod = Rarm.T @ (attach - elbow)  # rod direction in the arm frame (both rods)
        rods = []
        for side, y in (("a", W), ("b", -W)):
            rod = f"arm{i + 1}_rod{side}"
            rods.append(
                f'      <body name="{rod}" pos="{fmt([LA, y, 0])}" zaxis="{fmt(z_rod)}">\n'
                f'        <joint name="{rod}_ball" type="ball"/>\n'
                f'        <geom type="capsule" fromto="0 0 0 0 0 {LB}" size="0.004"/>\n'
                f"      </body>\n"
            )
            eqs.append(
                f'    <connect name="{rod}_tip" body1="{rod}" body2="platform" '
                f'anchor="0 0 {LB}"/>\n'
            )
        arms.append(
            f'    <body name="arm{i + 1}" pos="{fmt(base)}" euler="{120 * i} {THETA} 0">\n'
            f'      <joint name="arm{i + 1}_hinge" axis="0 1 0" ref="{THETA}" range="-10 70"/>\n'
            + "".join(rods)
            + "    </body>\n"
        )
        acts.append(f'    <motor name="motor{i + 1}" joint="arm{i + 1}_hinge" gear="50"/>\n')
    xml = (
        "<!-- Delta robot for pincal's MJCF import tests; written by make_delta.py. -->\n"
        '<mujoco model="delta">\n  <compiler angle="degree" eulerseq="zyx"/>\n'
        "  <worldbody>\n"
        + "".join(arms)
        + f'    <body name="platform" pos="0 0 {-h:.15g}">\n'
        + '      <freejoint name="platform_free"/>\n'
        '      <site name="tcp" pos="0 0 -0.02"/>\n    </body>\n  </worldbody>\n'
        "  <equality>\n" + "".join(eqs) + "  </equality>\n"
        "  <actuator>\n" + "".join(acts) + "  </actuator>\n</mujoco>\n"
    )
    Path(__file__).with_name("delta.xml").write_text(xml, encoding="utf-8")


if __name__ == "__main__":
    main()

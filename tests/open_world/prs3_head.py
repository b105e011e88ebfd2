"""A 3-PRS spindle head written as MJCF in its own habits: three vertical ``slide``
actuators at 120°, a ``hinge`` on each carriage about the column's tangent, rods of
0.25 m, the platform hung from rod 1 by an MJCF ``ball`` joint and held by the other
two rods through ``connect`` equalities (anchors in the rods' frames); the sidecar
measures the spindle tip's height and two tilts, ``[z, rx, ry]``, and the platform
tilts by up to ≈ 0.8 rad across the slides' ±80 mm."""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: base and platform radii, rod length, carriage height at slide 0 [m]
BASE, PLATFORM, ROD, HEIGHT = 0.2, 0.08, 0.25, 0.3


def _f(v: np.ndarray) -> str:
    return " ".join(f"{x:.9g}" for x in v)


def prs3_head_mjcf() -> str:
    """The MJCF text (assembled at qpos 0: every slide at 0, the platform level)."""
    d = BASE - PLATFORM
    rise = np.array([0.0, 0.0, np.sqrt(ROD**2 - d**2)])
    lines = ['<mujoco model="prs3_head">', '  <compiler angle="radian"/>', "  <worldbody>"]
    ends = []
    for i, a in enumerate(np.radians([90.0, 210.0, 330.0]), start=1):
        u = np.array([np.cos(a), np.sin(a), 0.0])
        t = np.array([-np.sin(a), np.cos(a), 0.0])
        end = rise - d * u
        ends.append(end)
        lines += [
            f'    <body name="carriage{i}" pos="{_f(BASE * u + [0, 0, HEIGHT])}">',
            f'      <joint name="slide{i}" type="slide" axis="0 0 1" range="-0.08 0.08" '
            'limited="true"/>',
            '      <geom type="box" size="0.02 0.02 0.02"/>',
            f'      <body name="rod{i}">',
            f'        <joint name="knee{i}" type="hinge" axis="{_f(t)}" range="-1 1" '
            'limited="true"/>',
            f'        <geom type="capsule" fromto="0 0 0 {_f(end)}" size="0.008"/>',
        ]
        if i == 1:
            lines += [
                f'        <body name="platform" pos="{_f(rise - BASE * u)}">',
                f'          <joint name="ball1" type="ball" pos="{_f(PLATFORM * u)}"/>',
                f'          <geom type="cylinder" size="{PLATFORM} 0.01"/>',
                '          <site name="spindle_tip" pos="0 0 -0.12"/>',
                "        </body>",
            ]
        lines += ["      </body>", "    </body>"]
    lines += ["  </worldbody>", "  <equality>"]
    lines += [f'    <connect body1="rod{i}" body2="platform" anchor="{_f(ends[i - 1])}"/>'
              for i in (2, 3)]  # fmt: skip
    lines += ["  </equality>", "  <actuator>"]
    lines += [f'    <position joint="slide{i}" kp="1000"/>' for i in (1, 2, 3)]
    lines += ["  </actuator>", "</mujoco>"]
    return "\n".join(lines) + "\n"


def write_prs3_head(folder: Path) -> Path:
    """Write ``prs3.xml`` and its sidecar ``prs3.yaml`` into ``folder``; the model's path."""
    path = folder / "prs3.xml"
    path.write_text(prs3_head_mjcf())
    (folder / "prs3.yaml").write_text("measured_frame: spindle_tip\nmeasured: [z, rx, ry]\n")
    return path

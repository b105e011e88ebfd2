"""Linkage machines written in other people's habits (issue 36): a robot neck, an
excavator-style arm and a gripper finger, each new to pincal.

* :func:`mjcf_neck`: MJCF, two linear actuators (``<position>`` on slides) between the
  torso and a head on a U joint; each leg a U joint at the torso and a slide, its rod end
  tied to the head by a ``connect``; the head's orientation measured ([rx, ry]).
* :func:`urdf_excavator`: URDF from a CAD exporter's habits (every link with an empty
  ``<inertial>``, joint limits everywhere, ``continuous`` passive pins), three hydraulic
  cylinders (prismatic joints) and four planar loops closed by ``[x, z]`` cuts: boom and
  stick cylinders, and the bucket's cylinder on a side-link / bucket-link linkage; the
  bucket tip measured in the plane ([x, z, ry]).
* :func:`mjcf_finger`: MJCF with ``<compiler angle="degree">`` (ranges and ``ref`` in
  degrees), a drive crank pushing the proximal phalanx through a rod, and a coupler from
  the palm bending the distal phalanx: two ``connect`` loops, one motor.
* :func:`mjcf_finger_polycoef`: the same finger with its distal joint tied to the
  proximal one by ``<equality><joint polycoef=…>`` instead of the coupler (refused).

Dimensions are made up (no published model is copied); each loop closes at the file's
pose by construction (``connect`` anchors are taken at ``qpos0``; the URDF cuts are
computed from the same numbers).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import yaml

# ------------------------------------------------------------------------------ neck
NECK_PIVOT = np.array([0.0, 0.0, 0.22])  # the head's U joint in the torso frame [m]
NECK_BASE = {"l": np.array([0.065, -0.07, 0.0]), "r": np.array([-0.065, -0.07, 0.0])}
NECK_HEAD = {"l": np.array([0.045, -0.055, -0.04]), "r": np.array([-0.045, -0.055, -0.04])}
"""Leg anchors: on the torso (world) and on the head (head frame, origin at the pivot)."""


def _f(v: np.ndarray) -> str:
    return " ".join(f"{x:.9g}" for x in v)


def mjcf_neck() -> str:
    """MJCF text of the neck (see the module docstring); site ``face`` on the head."""
    legs = []
    for s in ("l", "r"):
        a = NECK_BASE[s]
        d = NECK_PIVOT + NECK_HEAD[s] - a
        length = float(np.linalg.norm(d))
        legs.append(
            f'    <body name="cyl_{s}" pos="{_f(a)}">\n'
            f'      <joint name="cyl_{s}_a" type="hinge" axis="1 0 0" range="-35 35"/>\n'
            f'      <joint name="cyl_{s}_b" type="hinge" axis="0 1 0" range="-35 35"/>\n'
            f'      <geom type="cylinder" size="0.012" fromto="0 0 0 {_f(0.6 * d)}"/>\n'
            f'      <body name="rod_{s}" zaxis="{_f(d / length)}">\n'
            f'        <joint name="push_{s}" type="slide" axis="0 0 1" range="-0.03 0.03"/>\n'
            f'        <geom type="capsule" size="0.006" fromto="0 0 {0.3 * length:.9g} '
            f'0 0 {length:.9g}"/>\n'
            f'        <site name="rod_{s}_end" pos="0 0 {length:.9g}"/>\n'
            "      </body>\n"
            "    </body>\n"
        )
    return (
        '<mujoco model="neck">\n'
        '  <compiler angle="degree" autolimits="true"/>\n'
        '  <option timestep="0.002"/>\n'
        '  <default><geom rgba="0.7 0.7 0.75 1"/></default>\n'
        "  <worldbody>\n"
        '    <geom name="torso" type="box" size="0.1 0.1 0.01" pos="0 0 -0.01"/>\n'
        f'    <body name="head" pos="{_f(NECK_PIVOT)}">\n'
        '      <joint name="neck_pitch" type="hinge" axis="0 1 0" range="-40 40"/>\n'
        '      <joint name="neck_roll" type="hinge" axis="1 0 0" range="-40 40"/>\n'
        '      <geom type="sphere" size="0.06" pos="0 0.02 0.06"/>\n'
        '      <site name="face" pos="0 0.08 0.06"/>\n'
        f'      <site name="head_l" pos="{_f(NECK_HEAD["l"])}"/>\n'
        f'      <site name="head_r" pos="{_f(NECK_HEAD["r"])}"/>\n'
        "    </body>\n" + "".join(legs) + "  </worldbody>\n"
        "  <equality>\n"
        '    <connect name="tie_l" site1="rod_l_end" site2="head_l"/>\n'
        '    <connect name="tie_r" site1="rod_r_end" site2="head_r"/>\n'
        "  </equality>\n"
        "  <actuator>\n"
        '    <position name="act_l" joint="push_l" kp="2000" ctrlrange="-0.03 0.03"/>\n'
        '    <position name="act_r" joint="push_r" kp="2000" ctrlrange="-0.03 0.03"/>\n'
        "  </actuator>\n"
        "</mujoco>\n"
    )


NECK_SIDECAR = {"measured_frame": "face", "measured": ["rx", "ry"]}


def write_mjcf(folder: Path, name: str, text: str, sidecar: dict | None) -> Path:
    """Write ``folder/name.xml`` (and ``name.yaml`` when a sidecar is given)."""
    path = Path(folder) / f"{name}.xml"
    path.write_text(text, encoding="utf-8")
    if sidecar is not None:
        path.with_suffix(".yaml").write_text(yaml.safe_dump(sidecar), encoding="utf-8")
    return path

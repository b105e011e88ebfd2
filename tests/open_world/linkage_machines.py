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
* :func:`mjcf_finger`: MJCF with ``<compiler angle="degree">`` (ranges, ``euler`` and
  ``ctrlrange`` in degrees), a drive crank pushing the proximal phalanx through a rod,
  and a coupler from the palm bending the distal phalanx: two ``connect`` loops, one
  motor; the fingertip measured in the plane ([x, z, ry]).
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


# ------------------------------------------------------------------------ excavator
# every point in the link frame of its parent at the file's pose (all joints 0); the
# links keep the world's orientation there, so link and world axes agree at home [m]
EXC_PINS = {
    "boom_pin": ("base_link", "boom", (0.1, 0.0, 0.3)),
    "stick_pin": ("boom", "stick", (1.2, 0.0, 0.5)),
    "bucket_pin": ("stick", "bucket", (0.3, 0.0, -0.9)),
    "side_pin": ("stick", "side_link", (0.2, 0.0, -0.7)),
    "link_pin": ("side_link", "bucket_link", (0.1, 0.0, 0.2)),
}
EXC_CYLINDERS = {
    # name: (barrel's link, barrel pin, rod's link, rod pin, ± stroke [m])
    "boom_cyl": ("base_link", (0.3, 0.0, 0.15), "boom", (0.6, 0.0, 0.1), 0.08),
    "stick_cyl": ("boom", (0.5, 0.0, 0.35), "stick", (-0.15, 0.0, 0.25), 0.08),
    "bucket_cyl": ("stick", (0.0, 0.0, 0.15), "side_link", (0.1, 0.0, 0.2), 0.05),
}
EXC_LUG = ("bucket", (0.12, 0.0, 0.12))  # where the bucket link's far end is pinned
EXC_LINK_END = (0.12, 0.0, -0.28)  # that end in the bucket link's frame
EXC_TIP = (0.25, 0.0, -0.15)  # the bucket's teeth in its frame


def _exc_world() -> dict[str, np.ndarray]:
    """World origin of each link at the file's pose."""
    out = {"base_link": np.zeros(3)}
    for parent, child, xyz in EXC_PINS.values():
        out[child] = out[parent] + np.array(xyz)
    return out


def _inertial(mass: float) -> str:
    i = 0.01 * mass
    return (
        f'    <inertial>\n      <origin xyz="0 0 0" rpy="0 0 0"/>\n      <mass value="{mass:g}"/>'
        f'\n      <inertia ixx="{i:g}" ixy="0" ixz="0" iyy="{i:g}" iyz="0" izz="{i:g}"/>\n'
        "    </inertial>\n"
    )


def _exc_link(name: str, mass: float = 1.0) -> str:
    return f'  <link name="{name}">\n{_inertial(mass)}  </link>\n'


def _exc_joint(
    name: str,
    kind: str,
    parent: str,
    child: str,
    xyz: tuple[float, ...] | np.ndarray,
    pitch: float = 0.0,
    limit: tuple[float, float] | None = None,
) -> str:
    axis = '\n    <axis xyz="1 0 0"/>' if kind == "prismatic" else ""
    axis = '\n    <axis xyz="0 1 0"/>' if kind == "revolute" else axis
    lim = (
        f'\n    <limit lower="{limit[0]:.9g}" upper="{limit[1]:.9g}" effort="5000" velocity="0.5"/>'
        if limit
        else ""
    )
    return (
        f'  <joint name="{name}" type="{kind}">\n'
        f'    <origin xyz="{_f(np.asarray(xyz))}" rpy="0 {pitch:.12g} 0"/>\n'
        f'    <parent link="{parent}"/>\n    <child link="{child}"/>{axis}{lim}\n  </joint>\n'
    )


def urdf_excavator() -> tuple[str, dict]:
    """URDF text and sidecar of the excavator-style arm (module docstring).

    Boom, stick and bucket pinned in series (axes along y); each cylinder a barrel
    pinned on one link and a rod sliding along it (``<name>`` prismatic, 0 at the file's
    pose), its end ``<name>_end`` cut ``[x, z]`` from a lug ``<name>_lug`` on the other
    link; the bucket cylinder pushes the pin between the side link (on the stick) and
    the bucket link, whose end is cut from the bucket's lug. Measured: ``bucket_tip``.
    """
    world = _exc_world()
    links = ["base_link", "boom", "stick", "bucket", "side_link", "bucket_link"]
    text = ['<?xml version="1.0" encoding="utf-8"?>\n', '<robot name="excavator_arm">\n']
    text += [_exc_link(n, 50.0 if n in ("boom", "stick") else 5.0) for n in links]
    for name, (parent, child, xyz) in EXC_PINS.items():
        text.append(_exc_joint(name, "revolute", parent, child, xyz, limit=(-1.2, 1.2)))
    closures = []
    for name, (a_link, a_xyz, b_link, b_xyz, stroke) in EXC_CYLINDERS.items():
        a = world[a_link] + np.array(a_xyz)
        b = world[b_link] + np.array(b_xyz)
        d = b - a
        length = float(np.linalg.norm(d))
        pitch = -float(np.arctan2(d[2], d[0]))  # the barrel's x along the cylinder
        text += [_exc_link(f"{name}_barrel", 8.0), _exc_link(f"{name}_rod", 4.0)]
        text += [_exc_link(f"{name}_end", 0.1), _exc_link(f"{name}_lug", 0.1)]
        text.append(
            _exc_joint(
                f"{name}_pin", "revolute", a_link, f"{name}_barrel", a_xyz, pitch, (-1.2, 1.2)
            )
        )
        text.append(
            _exc_joint(
                name,
                "prismatic",
                f"{name}_barrel",
                f"{name}_rod",
                (0, 0, 0),
                0.0,
                (-stroke, stroke),
            )
        )
        text.append(
            _exc_joint(f"{name}_rod_eye", "fixed", f"{name}_rod", f"{name}_end", (length, 0, 0))
        )
        text.append(_exc_joint(f"{name}_lug_fix", "fixed", b_link, f"{name}_lug", b_xyz))
        closures.append([f"{name}_lug", f"{name}_end"])
    text += [_exc_link("bucket_lug", 0.1), _exc_link("bucket_link_end", 0.1)]
    text += [_exc_link("bucket_tip", 0.1)]
    text.append(_exc_joint("bucket_lug_fix", "fixed", EXC_LUG[0], "bucket_lug", EXC_LUG[1]))
    text.append(
        _exc_joint("bucket_link_eye", "fixed", "bucket_link", "bucket_link_end", EXC_LINK_END)
    )
    text.append(_exc_joint("teeth", "fixed", "bucket", "bucket_tip", EXC_TIP))
    text.append("</robot>\n")
    closures.append(["bucket_lug", "bucket_link_end"])
    sidecar = {
        "closed_loop": closures,
        "type": [["x", "z"]] * len(closures),
        "name_mot": list(EXC_CYLINDERS),
        "measured_frame": "bucket_tip",
        "measured": ["x", "z", "ry"],
    }
    return "".join(text), sidecar


# --------------------------------------------------------------------------- finger
def mjcf_finger(coupler: bool = True) -> str:
    """MJCF text of the finger (module docstring), in degrees; site ``fingertip``.

    The palm is tilted 20° about y (``euler`` in degrees); every hinge turns about y
    (a ``<default>`` class), so both loops are planar, each closed by a ``connect``
    (three rows, two independent). ``coupler=False``: the distal joint follows the
    proximal one through ``<equality><joint polycoef="0 0.8 0 0 0">`` instead.
    """
    link = (
        '      <body name="coupler" pos="0.03 0 -0.01">\n'
        '        <joint name="coupler_base" class="pin"/>\n'
        '        <geom type="capsule" size="0.002" fromto="0 0 0 0.05 0 0.002"/>\n'
        '        <site name="coupler_end" pos="0.05 0 0.002"/>\n'
        "      </body>\n"
        if coupler
        else ""
    )
    tie = (
        '    <connect name="coupler_tie" site1="coupler_end" site2="distal_lug"/>\n'
        if coupler
        else '    <joint name="pip_follows_mcp" joint1="pip" joint2="mcp" '
        'polycoef="0 0.8 0 0 0"/>\n'
    )
    return (
        '<mujoco model="finger">\n'
        '  <compiler angle="degree" autolimits="true"/>\n'
        "  <default>\n"
        '    <default class="pin"><joint type="hinge" axis="0 1 0" damping="0.01"/></default>\n'
        '    <geom contype="0" conaffinity="0" rgba="0.8 0.6 0.5 1"/>\n'
        "  </default>\n"
        "  <worldbody>\n"
        '    <body name="palm" pos="0 0 0.1" euler="0 -20 0">\n'
        '      <geom type="box" size="0.02 0.01 0.02" pos="0 0 0"/>\n'
        '      <body name="crank" pos="0 0 0.015">\n'
        '        <joint name="drive" class="pin" range="-45 45"/>\n'
        '        <geom type="capsule" size="0.002" fromto="0 0 0 0 0 0.012"/>\n'
        '        <body name="pushrod" pos="0 0 0.012">\n'
        '          <joint name="rod_base" class="pin"/>\n'
        '          <geom type="capsule" size="0.002" fromto="0 0 0 0.04 0 -0.013"/>\n'
        '          <site name="rod_end" pos="0.04 0 -0.013"/>\n'
        "        </body>\n"
        "      </body>\n"
        f"{link}"
        '      <body name="proximal" pos="0.04 0 0">\n'
        '        <joint name="mcp" class="pin" range="-30 60"/>\n'
        '        <geom type="capsule" size="0.007" fromto="0 0 0 0.045 0 0"/>\n'
        '        <site name="proximal_lug" pos="0 0 0.014"/>\n'
        '        <body name="distal" pos="0.045 0 0">\n'
        '          <joint name="pip" class="pin" range="-20 80"/>\n'
        '          <geom type="capsule" size="0.006" fromto="0 0 0 0.03 0 0"/>\n'
        '          <site name="distal_lug" pos="-0.005 0 -0.008"/>\n'
        '          <site name="fingertip" pos="0.03 0 0"/>\n'
        "        </body>\n"
        "      </body>\n"
        "    </body>\n"
        "  </worldbody>\n"
        "  <equality>\n"
        '    <connect name="pushrod_tie" site1="rod_end" site2="proximal_lug"/>\n'
        f"{tie}"
        "  </equality>\n"
        '  <actuator><position name="finger_drive" joint="drive" kp="5" ctrlrange="-45 45"/>'
        "</actuator>\n"
        "</mujoco>\n"
    )


FINGER_SIDECAR = {"measured_frame": "fingertip", "measured": ["x", "z", "ry"]}

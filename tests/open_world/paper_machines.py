"""Three closed-loop machines written from published geometry (issue 36), each in a habit
the rest of the roster does not have. Lengths in m, angles in rad.

* :func:`agile_eye`: the Agile Eye spherical 3-RRR wrist (Gosselin & Hamel, 1994: every
  link angle 90°, the motor axes mutually orthogonal at home), as an example-parallel-robots
  folder: ``robot.urdf`` + ``robot.yaml`` whose closures name URDF joints (``wrist2`` on
  leg 2's copy of the platform, ``seat2`` a fixed joint on the platform), ``6d``;
  measured: the platform orientation only (``[rx, ry, rz]``).
* :func:`stewart_6rss`: a rotary Stewart head (6-RSS: six motors with horizontal radial
  shafts, cranks, rods with ball ends) in MJCF: ``angle="radian"``, joint ``<default>``
  classes, a ``<freejoint>`` platform, ``<equality><connect site1 site2>`` cuts and a
  ``<keyframe name="home">`` holding the assembled ``qpos``; measured: the tool pose.
* :func:`clavel_delta`: Clavel's Delta with the dimensions of the ABB FlexPicker IRB 360
  given by Williams ("The Delta Parallel Robot: Its Kinematics Solutions", 2016):
  s_B = 0.567, s_P = 0.076, L = 0.524, l = 1.244, rod spacing h = 0.131; every ball
  end written as three revolutes (z, y, x) meeting at a point, the platform hanging from
  rod ``1a`` through its lower emulated ball and closed (``3D``) to the five other rods.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import yaml

from tests.open_world.first_machines import _frame_z
from tests.open_world.machines import _fmt, _joint, _link, _se3

__all__ = [
    "AGILE_EYE_RANGE",
    "CLAVEL_RANGE",
    "STEWART_RANGE",
    "agile_eye",
    "clavel_delta",
    "stewart_6rss",
    "write_agile_eye",
    "write_stewart",
]

AGILE_EYE_RANGE = (-0.5, 0.5)
"""Motor range [rad] of the Agile Eye around its home (q = 0)."""


def agile_eye() -> tuple[str, dict]:
    """The Agile Eye: leg i has motor ``base<i>`` (axis u_i), ``elbow<i>`` (w_i) and
    ``wrist<i>`` (v_i), all through the centre (0, 0, 0.25); at home u = (x, y, z),
    w = (y, z, x), v = (z, x, y) (all link angles 90°: the isotropic reference pose).
    Joint origins 0.1 m from the centre along their axes. The platform hangs from
    ``wrist1``; legs 2 and 3 end in ``plat<i>`` on ``wrist<i>`` and are closed (``6d``) by
    the joint frames ``[wrist<i>, seat<i>]``. Measured: the orientation of ``tool``."""
    c = np.array([0.0, 0.0, 0.25])
    e = np.eye(3)
    legs = [(e[0], e[1], e[2]), (e[1], e[2], e[0]), (e[2], e[0], e[1])]
    links, joints, closures = [_link("base_link")], [], []
    for i, axes in enumerate(legs, start=1):
        parent, parent_w = "base_link", pin.SE3.Identity()
        for name, axis in zip((f"base{i}", f"elbow{i}", f"wrist{i}"), axes, strict=True):
            frame_w = pin.SE3(_frame_z(axis), c + 0.1 * axis)
            child = (
                "platform"
                if name == "wrist1"
                else (f"plat{i}" if name.startswith("wrist") else f"{name}_link")
            )
            links.append(_link(child))
            limit = AGILE_EYE_RANGE if name.startswith("base") else None
            joints.append(
                _joint(name, "revolute", parent, child, parent_w.inverse() * frame_w, limit=limit)
            )
            parent, parent_w = child, frame_w
            if name == "wrist1":
                platform_w = frame_w
            elif name.startswith("wrist"):
                seat_w = frame_w
        if i > 1:  # the seat: where leg i's wrist frame sits on the platform
            links.append(_link(f"seat{i}_link"))
            joints.append(
                _joint(
                    f"seat{i}", "fixed", "platform", f"seat{i}_link", platform_w.inverse() * seat_w
                )
            )
            closures.append([f"wrist{i}", f"seat{i}"])
    links.append(_link("tool"))
    tool_w = pin.SE3(np.eye(3), c + np.array([0.0, 0.0, 0.08]))
    joints.append(_joint("tool_mount", "fixed", "platform", "tool", platform_w.inverse() * tool_w))
    urdf = '<?xml version="1.0"?>\n<robot name="agile_eye">\n' + "".join(links + joints)
    sidecar = {
        "name_mot": ["base1", "base2", "base3"],
        "closed_loop": closures,
        "type": ["6D", "6D"],
        "measured_frame": "tool",
        "measured": ["rx", "ry", "rz"],
    }
    return urdf + "</robot>\n", sidecar


def write_agile_eye(folder: Path) -> Path:
    """Write ``folder/agile_eye/robot.urdf`` + ``robot.yaml``; returns the directory."""
    d = Path(folder) / "agile_eye"
    d.mkdir(parents=True, exist_ok=True)
    urdf, sidecar = agile_eye()
    (d / "robot.urdf").write_text(urdf, encoding="utf-8")
    (d / "robot.yaml").write_text(yaml.safe_dump(sidecar), encoding="utf-8")
    return d


STEWART_RANGE = (-0.6, 0.6)
"""Crank range [rad] of the 6-RSS head (0: cranks horizontal)."""

_RB, _RP, _CRANK, _H = 0.10, 0.07, 0.03, 0.13  # base, platform radii; crank; home height


def _stewart_points() -> list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    """Per leg: motor position B, shaft axis (radial), crank tip C at home, anchor P."""
    out = []
    for k in range(3):
        for s in (-1.0, 1.0):
            a = np.radians(120.0 * k + s * 12.0)
            radial = np.array([np.cos(a), np.sin(a), 0.0])
            tangent = np.array([-np.sin(a), np.cos(a), 0.0])
            B = _RB * radial
            C = B + s * _CRANK * tangent  # cranks point away from the pair's partner
            ap = np.radians(120.0 * k + s * 45.0)
            P = np.array([_RP * np.cos(ap), _RP * np.sin(ap), _H])
            out.append((B, radial, C, P))
    return out


def stewart_6rss() -> tuple[str, dict]:
    """MJCF text and sidecar of the 6-RSS head: motors ``m1``…``m6`` (hinges about
    their radial shafts), rods ``rod<i>`` on ball joints at the crank tips, a free
    platform at height 0.13 m closed by ``connect`` between the sites ``rod<i>_end``
    and ``anchor<i>``. Measured: the pose of site ``tool`` 0.02 m above the platform."""
    bodies, cuts, qpos = [], [], []
    for i, (B, radial, C, P) in enumerate(_stewart_points(), start=1):
        rod = P - C
        length = float(np.linalg.norm(rod))
        R = _frame_z(radial)  # motor body: z along the shaft
        c_local = R.T @ (C - B)
        q_motor = pin.Quaternion(R)
        q_local = pin.Quaternion(R.T @ _frame_z(rod))  # rod body: z along the rod
        bodies.append(
            f'    <body name="motor{i}" pos="{_fmt(B)}" '
            f'quat="{_fmt([q_motor.w, q_motor.x, q_motor.y, q_motor.z])}">\n'
            f'      <joint name="m{i}" class="motor"/>\n'
            f'      <geom type="capsule" fromto="0 0 0 {_fmt(c_local)}" size="0.004"/>\n'
            f'      <body name="rod{i}" pos="{_fmt(c_local)}" '
            f'quat="{_fmt([q_local.w, q_local.x, q_local.y, q_local.z])}">\n'
            f'        <joint name="ball{i}" class="rod_end"/>\n'
            f'        <geom type="capsule" fromto="0 0 0 0 0 {length:.17g}" size="0.003"/>\n'
            f'        <site name="rod{i}_end" pos="0 0 {length:.17g}"/>\n'
            "      </body>\n    </body>\n"
        )
        cuts.append(f'    <connect name="cut{i}" site1="rod{i}_end" site2="anchor{i}"/>\n')
        qpos += [0.0, 1.0, 0.0, 0.0, 0.0]
    anchors = "".join(
        f'      <site name="anchor{i}" pos="{_fmt(P - [0, 0, _H])}"/>\n'
        for i, (_, _, _, P) in enumerate(_stewart_points(), start=1)
    )
    qpos += [0.0, 0.0, _H, 1.0, 0.0, 0.0, 0.0]
    text = (
        '<mujoco model="stewart_6rss">\n  <compiler angle="radian"/>\n'
        "  <default>\n"
        f'    <default class="motor"><joint type="hinge" axis="0 0 1" limited="true" '
        f'range="{STEWART_RANGE[0]} {STEWART_RANGE[1]}" damping="0.1"/></default>\n'
        '    <default class="rod_end"><joint type="ball" damping="0.01"/></default>\n'
        "  </default>\n  <worldbody>\n"
        + "".join(bodies)
        + f'    <body name="platform" pos="0 0 {_H}">\n      <freejoint name="float"/>\n'
        '      <geom type="cylinder" size="0.075 0.004"/>\n'
        + anchors
        + '      <site name="tool" pos="0 0 0.02"/>\n    </body>\n  </worldbody>\n'
        "  <equality>\n"
        + "".join(cuts)
        + "  </equality>\n  <actuator>\n"
        + "".join(f'    <position name="act{i}" joint="m{i}" kp="20"/>\n' for i in range(1, 7))
        + "  </actuator>\n  <keyframe>\n"
        f'    <key name="home" qpos="{_fmt(qpos)}"/>\n  </keyframe>\n</mujoco>\n'
    )
    return text, {"measured_frame": "tool", "measured": "pose"}


def write_stewart(folder: Path) -> Path:
    """Write ``folder/stewart_6rss.xml`` + ``.yaml``; returns the MJCF path."""
    text, sidecar = stewart_6rss()
    path = Path(folder) / "stewart_6rss.xml"
    path.write_text(text, encoding="utf-8")
    path.with_suffix(".yaml").write_text(yaml.safe_dump(sidecar), encoding="utf-8")
    return path


CLAVEL_RANGE = (-0.35, 0.7)
"""Motor range [rad] of the Clavel delta (0: arms horizontal; positive: arm down)."""

_SB, _SP, _L, _LR, _HW = 0.567, 0.076, 0.524, 1.244, 0.131


def _ball(prefix: str, parent: str, placement: pin.SE3) -> tuple[list[str], list[str], str]:
    """An emulated ball: revolutes ``<prefix>_z``, ``_y``, ``_x`` at one point; returns
    links, joints and the last link's name."""
    links, joints, prev = [], [], parent
    for k, axis in zip("zyx", ("0 0 1", "0 1 0", "1 0 0"), strict=True):
        link = f"{prefix}_{k}_link"
        links.append(_link(link))
        joints.append(
            _joint(
                f"{prefix}_{k}",
                "revolute",
                prev,
                link,
                placement if k == "z" else None,
                axis=axis,
                limit=None,
            )
        )
        prev = link
    return links, joints, prev


def clavel_delta() -> tuple[str, dict]:
    """The Delta (ABB IRB 360 dimensions after Williams 2016): motors ``motor<i>`` on
    the base triangle's sides (w_B = s_B/(2√3) from the centre, axis along the side),
    arms L; rods ``<i>a``/``<i>b`` of l at ±h/2 along the motor axis, each hanging from
    the elbow by an emulated ball ``ball<i><a|b>_top``; the platform (anchors at
    w_P = s_P/(2√3), ±h/2) hangs from rod 1a by ``ball1a_bot`` and is closed (``3D``)
    to the other five rod ends. Measured: position of ``tcp`` 0.05 m below the platform."""
    wb, wp = _SB / (2 * np.sqrt(3)), _SP / (2 * np.sqrt(3))
    depth = np.sqrt(_LR**2 - (wb + _L - wp) ** 2)
    links = [_link("base_link"), _link("tcp")]
    joints, closures = [], []
    platform_w = pin.SE3(np.eye(3), np.array([0.0, 0.0, -depth]))
    for i in (1, 2, 3):
        a = np.radians(-90.0 + 120.0 * (i - 1))
        radial = np.array([np.cos(a), np.sin(a), 0.0])
        side = np.array([-np.sin(a), np.cos(a), 0.0])
        # motor frame: x radial, y along the side (minus: positive angle turns the arm down)
        Rm = np.column_stack([radial, -side, np.cross(radial, -side)])
        motor_w = pin.SE3(Rm, wb * radial)
        links.append(_link(f"arm{i}"))
        joints.append(
            _joint(
                f"motor{i}",
                "revolute",
                "base_link",
                f"arm{i}",
                motor_w,
                axis="0 1 0",
                limit=CLAVEL_RANGE,
            )
        )
        for s, tag in ((1.0, "a"), (-1.0, "b")):
            top = (wb + _L) * radial + s * _HW / 2 * side
            bottom = platform_w.translation + wp * radial + s * _HW / 2 * side
            Rrod = _frame_z(bottom - top)
            top_w = pin.SE3(Rrod, top)
            ls, js, last = _ball(f"ball{i}{tag}_top", f"arm{i}", motor_w.inverse() * top_w)
            links += [*ls, _link(f"rod{i}{tag}")]
            joints += [*js, _joint(f"rod{i}{tag}_mount", "fixed", last, f"rod{i}{tag}")]
            end_w = pin.SE3(Rrod, bottom)
            if i == 1 and tag == "a":
                ls, js, last = _ball("ball1a_bot", f"rod{i}{tag}", top_w.inverse() * end_w)
                links += [*ls, _link("platform")]
                joints += [
                    *js,
                    _joint(
                        "platform_mount", "fixed", last, "platform", end_w.inverse() * platform_w
                    ),
                ]
            else:
                links.append(_link(f"tip{i}{tag}"))
                joints.append(
                    _joint(
                        f"tip{i}{tag}_mount",
                        "fixed",
                        f"rod{i}{tag}",
                        f"tip{i}{tag}",
                        top_w.inverse() * end_w,
                    )
                )
                links.append(_link(f"anchor{i}{tag}"))
                joints.append(
                    _joint(
                        f"anchor{i}{tag}_mount",
                        "fixed",
                        "platform",
                        f"anchor{i}{tag}",
                        platform_w.inverse() * end_w,
                    )
                )
                closures.append([f"tip{i}{tag}", f"anchor{i}{tag}"])
    joints.append(_joint("tcp_mount", "fixed", "platform", "tcp", _se3(p=(0, 0, -0.05))))
    urdf = '<?xml version="1.0"?>\n<robot name="clavel_delta">\n' + "".join(links + joints)
    sidecar = {
        "closed_loop": closures,
        "type": ["3D"] * len(closures),
        "name_mot": ["motor1", "motor2", "motor3"],
        "measured_frame": "tcp",
        "measured": "position",
    }
    return urdf + "</robot>\n", sidecar

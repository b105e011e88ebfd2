"""Machines written for the open-world acceptance tests (URDF text + sidecar dict).

* :func:`rssr_emulated_ball`: the RSSR four-bar of tests/model/machines/rssr with its
  ball joint emulated by three revolutes whose axes intersect (z, y, x; zero-length
  links between them), as many public URDFs write a spherical joint.
* :func:`delta_4r`: a Delta robot whose parallelograms are four-revolute planar loops,
  each closed by a ``6d`` weld (three over-constrained closures: 18 rows of rank 9),
  with the platform hanging from leg 1 and welded (``6d``) to the wrists of legs 2 and
  3. The file pose (q = 0) is the assembled home. Lengths in m, angles in rad.

:func:`write_machine` writes ``<dir>/<name>/<name>.urdf`` + ``.yaml`` for the CLI.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import yaml

_INERTIAL = (
    '<inertial><mass value="0.1"/><origin xyz="0 0 0"/>'
    '<inertia ixx="1e-5" ixy="0" ixz="0" iyy="1e-5" iyz="0" izz="1e-5"/></inertial>'
)


def _fmt(v) -> str:
    return " ".join(f"{0.0 if abs(x) < 1e-15 else x:.17g}" for x in np.atleast_1d(v))


def _link(name: str) -> str:
    return f'  <link name="{name}">{_INERTIAL}</link>\n'


def _joint(
    name: str,
    kind: str,
    parent: str,
    child: str,
    placement: pin.SE3 | None = None,
    axis: str = "0 0 1",
    limit: tuple[float, float] | None = (-3.1, 3.1),
) -> str:
    M = placement if placement is not None else pin.SE3.Identity()
    body = (
        f'  <joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
        f'<origin xyz="{_fmt(M.translation)}" rpy="{_fmt(pin.rpy.matrixToRpy(M.rotation))}"/>'
    )
    if kind == "revolute":
        body += f'<axis xyz="{axis}"/>'
        if limit is not None:
            body += f'<limit lower="{limit[0]}" upper="{limit[1]}" effort="1" velocity="1"/>'
        else:
            body += '<limit effort="0" velocity="1"/>'
    return body + "</joint>\n"


def _se3(R: np.ndarray | None = None, p=(0.0, 0.0, 0.0)) -> pin.SE3:
    return pin.SE3(np.eye(3) if R is None else R, np.asarray(p, dtype=float))


# ------------------------------------------------------------------ RSSR, ball = 3 revolutes
RSSR_CRANK_RANGE = (0.1, 1.0)
"""Crank range [rad] of the RSSR machines: on one side of the output dead point at 0."""


def rssr_emulated_ball() -> tuple[str, dict]:
    """RSSR four-bar (crank 0.05, coupler 0.17, rocker 0.08, pivots 0.2 apart) whose crank
    ball joint is three revolutes ``ball_x`` (z), ``ball_y`` (y), ``ball_z`` (x) meeting at
    one point; the rocker-end ball is the cut (3D closure). Measured: rocker tip position.

    The machine is mirror-symmetric about the plane y = 0: crank angles a and −a put the
    rocker tip at the same position, and crank = 0 is a dead point of the output (the
    tip does not move at first order). Inverse kinematics is therefore posed only on one
    side of it: home is at crank 0.5 rad and the workspace is [0.1, 1.0] rad.
    """
    urdf = (
        '<?xml version="1.0"?>\n<robot name="rssr3r">\n'
        + "".join(
            _link(n) for n in ("base_link", "crank", "gimbal1", "gimbal2", "coupler", "coupler_tip")
        )
        + _link("rocker")
        + _link("rocker_tip")
        + _joint("crank_mot", "revolute", "base_link", "crank")
        + _joint("ball_x", "revolute", "crank", "gimbal1", _se3(p=(0.05, 0, 0)), limit=None)
        + _joint("ball_y", "revolute", "gimbal1", "gimbal2", axis="0 1 0", limit=None)
        + _joint("ball_z", "revolute", "gimbal2", "coupler", axis="1 0 0", limit=None)
        + _joint("coupler_end", "fixed", "coupler", "coupler_tip", _se3(p=(0.17, 0, 0)))
        + _joint("rocker_pivot", "revolute", "base_link", "rocker", _se3(p=(0.2, 0, 0)), "0 1 0")
        + _joint("rocker_end", "fixed", "rocker", "rocker_tip", _se3(p=(0, 0, 0.08)))
        + "</robot>\n"
    )
    sidecar = {
        "closed_loop": [["coupler_end", "rocker_end"]],
        "type": ["3D"],
        "name_mot": ["crank_mot"],
        "measured_frame": "rocker_tip",
        "measured": "position",
        "home": {"crank_mot": 0.5, "ball_y": -float(np.arctan2(0.08, 0.15))},
        "workspace": {"joints": {"crank_mot": list(RSSR_CRANK_RANGE)}},
    }
    return urdf, sidecar


# ------------------------------------------------------------------ RUSR with a universal joint
RUSR_CRANK_RANGE = (0.2, 0.8)
"""Crank range [rad] of :func:`rusr_universal` (home at 0.5)."""


def rusr_universal() -> tuple[str, dict]:
    """Spatial RUSR four-bar whose crank-end joint is a universal joint given in the
    sidecar (``joint_type: universal`` on the revolute placeholder ``u_joint``).

    Crank ``crank_mot`` (actuated, axis z, length 0.05); ``u_joint`` at the crank tip:
    first axis z (the placeholder's ``<axis>``), second axis x (pincal's rule for a z
    first axis); the coupler runs 0.17 along its own y (perpendicular to both U axes, so
    the U joint points it anywhere and the coupler has no idle spin); its end meets the
    rocker tip in a ball joint (3D closure); the rocker ``rocker_pivot`` turns about x
    (length 0.08). The pivot is placed so that the loop closes at crank 0.5 rad with the
    coupler along (0.1, 1, 0.15) — not mirror-symmetric. Measured: the position of the
    point ``coupler_mark`` (0.02, 0.085, 0.01) on the coupler (a coupler curve).
    """
    crank_home = 0.5
    c = np.array([0.05 * np.cos(crank_home), 0.05 * np.sin(crank_home), 0.0])
    u = np.array([0.1, 1.0, 0.15]) / np.linalg.norm([0.1, 1.0, 0.15])
    pivot = c + 0.17 * u - np.array([0.0, 0.0, 0.08])
    urdf = (
        '<?xml version="1.0"?>\n<robot name="rusr">\n'
        + "".join(
            _link(n)
            for n in ("base_link", "crank", "coupler", "coupler_tip", "coupler_mark", "rocker")
        )
        + _link("rocker_tip")
        + _joint("crank_mot", "revolute", "base_link", "crank")
        + _joint("u_joint", "revolute", "crank", "coupler", _se3(p=(0.05, 0, 0)), "0 0 1")
        + _joint("coupler_end", "fixed", "coupler", "coupler_tip", _se3(p=(0, 0.17, 0)))
        + _joint("mark", "fixed", "coupler", "coupler_mark", _se3(p=(0.02, 0.085, 0.01)))
        + _joint("rocker_pivot", "revolute", "base_link", "rocker", _se3(p=pivot), "1 0 0")
        + _joint("rocker_end", "fixed", "rocker", "rocker_tip", _se3(p=(0, 0, 0.08)))
        + "</robot>\n"
    )
    sidecar = {
        "closed_loop": [["coupler_end", "rocker_end"]],
        "type": ["3D"],
        "name_mot": ["crank_mot"],
        "joint_name": ["u_joint"],
        "joint_type": ["universal"],
        "measured_frame": "coupler_mark",
        "measured": "position",
        "home": {"crank_mot": crank_home},
        "workspace": {"joints": {"crank_mot": list(RUSR_CRANK_RANGE)}},
    }
    return urdf, sidecar


# ------------------------------------------------------------------ RUSR, U joint named UJOINT_ab
def _frame_for(kind: str) -> np.ndarray:
    """Rotation of a ``UJOINT_ab`` joint frame in the crank frame: axis a along crank z,
    the third axis c (normal to a and b) along crank y; b is then along ±x."""
    a, b = ("xyz".index(ch) for ch in kind[-2:].lower())
    c = 3 - a - b
    R = np.zeros((3, 3))
    R[2, a], R[1, c] = 1.0, 1.0
    R[:, b] = np.cross(R[:, (b + 1) % 3], R[:, (b + 2) % 3])
    return R


def rusr_ujoint(kind: str = "UJOINT_ZY") -> tuple[str, dict]:
    """The RUSR four-bar of :func:`rusr_universal` written as the robot.yaml collection
    writes a U joint: ``joint_type: [<kind>, FIXED]`` with ``kind`` one of UJOINT_XY,
    UJOINT_YZ, UJOINT_ZY — two revolutes about the joint frame's first then second named
    axis. The joint ``<origin>`` is rotated so that the first named axis is the crank's
    z and the coupler runs 0.17 along the joint frame's third axis (the crank's y): the
    same machine as :func:`rusr_universal` (its second U axis is ±x). The placeholder's
    ``<axis>`` (1 1 0) is deliberately not one of the named axes: it is not used.

    ``mark`` is a revolute joint (axis 0 1 1, range ±1 rad) that the sidecar locks
    (``FIXED``): the mark hangs at its origin, as in :func:`rusr_universal`.
    Measured: position of ``coupler_mark``.
    """
    crank_home = 0.5
    c = np.array([0.05 * np.cos(crank_home), 0.05 * np.sin(crank_home), 0.0])
    u = np.array([0.1, 1.0, 0.15]) / np.linalg.norm([0.1, 1.0, 0.15])
    pivot = c + 0.17 * u - np.array([0.0, 0.0, 0.08])
    R = _frame_for(kind)
    third = np.zeros(3)
    third[3 - sum("xyz".index(ch) for ch in kind[-2:].lower())] = 0.17
    mark = R.T @ np.array([0.02, 0.085, 0.01])
    urdf = (
        '<?xml version="1.0"?>\n<robot name="rusr_ujoint">\n'
        + "".join(
            _link(n)
            for n in ("base_link", "crank", "coupler", "coupler_tip", "coupler_mark", "rocker")
        )
        + _link("rocker_tip")
        + _joint("crank_mot", "revolute", "base_link", "crank")
        + _joint("u_joint", "revolute", "crank", "coupler", _se3(R, (0.05, 0, 0)), "1 1 0")
        + _joint("coupler_end", "fixed", "coupler", "coupler_tip", _se3(p=third))
        + _joint("mark", "revolute", "coupler", "coupler_mark", _se3(p=mark), "0 1 1", (-1, 1))
        + _joint("rocker_pivot", "revolute", "base_link", "rocker", _se3(p=pivot), "1 0 0")
        + _joint("rocker_end", "fixed", "rocker", "rocker_tip", _se3(p=(0, 0, 0.08)))
        + "</robot>\n"
    )
    sidecar = {
        "closed_loop": [["coupler_end", "rocker_end"]],
        "type": ["3D"],
        "name_mot": ["crank_mot"],
        "joint_name": ["u_joint", "mark"],
        "joint_type": [kind, "FIXED"],
        "measured_frame": "coupler_mark",
        "measured": "position",
        "home": {"crank_mot": crank_home},
        "workspace": {"joints": {"crank_mot": list(RUSR_CRANK_RANGE)}},
    }
    return urdf, sidecar


# ------------------------------------------------------------------ 2-RSU ankle of a leg
ANKLE_MOTOR_RANGE = (-0.3, 0.3)
"""Motor range [rad] of :func:`ankle_2rsu` when its limits are given."""


def ankle_2rsu(zero_limits: bool = False) -> tuple[str, dict]:
    """A legged robot's parallel ankle, two loops, written as a leg URDF often is.

    The shin (``base_link``) carries the foot on an emulated U joint (``ankle_pitch``
    about y, then ``ankle_roll`` about x, 0.30 m below the knee-side origin, zero-length
    link between them) and two motors ``mot_l`` / ``mot_r`` (axis y, at z = −0.05 m,
    y = ±0.035 m) whose 0.05 m cranks point backwards (−x). Each crank ends in an
    emulated ball joint (``ball_a_*`` z, ``ball_b_*`` y, ``ball_c_*`` x, zero-length
    links) carrying a rod whose end (0.015, 0, −0.25) in the rod frame meets the foot
    point (−0.035, ±0.035, 0) in a ball (``3D`` closure). Both motors turning together
    pitch the foot, opposite ways roll it; the foot lever (0.035 m) is shorter than the
    crank, so the motors cannot turn all the way round: turned together, the loops stop
    closing near +1.24 rad. The rods' spins are idle. The file pose (q = 0) is assembled. Measured:
    the pose of ``sole`` (0.03, 0, −0.05) on the foot.

    With ``zero_limits`` every revolute has ``<limit lower="0" upper="0">`` (no range,
    as many exported leg URDFs write it) and the sidecar gives no workspace.
    """
    lim = (0.0, 0.0) if zero_limits else None
    mot = (0.0, 0.0) if zero_limits else ANKLE_MOTOR_RANGE
    links = ["base_link", "ankle_cross", "foot", "sole"]
    joints = [
        _joint(
            "ankle_pitch",
            "revolute",
            "base_link",
            "ankle_cross",
            _se3(p=(0, 0, -0.3)),
            "0 1 0",
            lim,
        ),
        _joint("ankle_roll", "revolute", "ankle_cross", "foot", axis="1 0 0", limit=lim),
        _joint("sole_joint", "fixed", "foot", "sole", _se3(p=(0.03, 0, -0.05))),
    ]
    closures = []
    for side, y in (("l", 0.035), ("r", -0.035)):
        links += [f"crank_{side}", f"gimbal1_{side}", f"gimbal2_{side}", f"rod_{side}"]
        links += [f"rod_end_{side}", f"foot_att_{side}"]
        joints += [
            _joint(
                f"mot_{side}",
                "revolute",
                "base_link",
                f"crank_{side}",
                _se3(p=(0, y, -0.05)),
                "0 1 0",
                mot,
            ),
            _joint(
                f"ball_a_{side}",
                "revolute",
                f"crank_{side}",
                f"gimbal1_{side}",
                _se3(p=(-0.05, 0, 0)),
                "0 0 1",
                lim,
            ),
            _joint(
                f"ball_b_{side}",
                "revolute",
                f"gimbal1_{side}",
                f"gimbal2_{side}",
                axis="0 1 0",
                limit=lim,
            ),
            _joint(
                f"ball_c_{side}",
                "revolute",
                f"gimbal2_{side}",
                f"rod_{side}",
                axis="1 0 0",
                limit=lim,
            ),
            _joint(
                f"rod_end_{side}",
                "fixed",
                f"rod_{side}",
                f"rod_end_{side}",
                _se3(p=(0.015, 0, -0.25)),
            ),
            _joint(f"foot_att_{side}", "fixed", "foot", f"foot_att_{side}", _se3(p=(-0.035, y, 0))),
        ]
        closures.append([f"rod_end_{side}", f"foot_att_{side}"])
    urdf = (
        '<?xml version="1.0"?>\n<robot name="ankle_2rsu">\n'
        + "".join(_link(n) for n in links)
        + "".join(joints)
        + "</robot>\n"
    )
    sidecar: dict = {
        "closed_loop": closures,
        "type": ["3D", "3D"],
        "name_mot": ["mot_l", "mot_r"],
        "measured_frame": "sole",
        "measured": "pose",
    }
    return urdf, sidecar


# ------------------------------------------------------------------ Delta with 4R parallelograms
R_BASE, L_ARM, L_ROD, R_PLAT, HALF_W, THETA = 0.2, 0.25, 0.5, 0.05, 0.03, np.radians(30.0)


def _ry(a: float) -> np.ndarray:
    return pin.utils.rotate("y", a)


def _rz(a: float) -> np.ndarray:
    return pin.utils.rotate("z", a)


def delta_4r() -> tuple[str, dict]:
    """Delta robot with revolute-only parallelograms (see the module doc).

    Leg i (φ = 120°·(i−1)): ``hinge_i`` (actuated, axis y of the leg), ``elbow_i`` (∥ y),
    the parallelogram ``rod_a_i``/``rod_b_i``/``wbar_i``/``rod_b_end_i`` (four revolutes
    normal to its plane; the weld of link ``rod_b_end_i`` to frame ``wbar_b_i`` closes
    it), ``wrist_i`` (∥ y). Measured: the
    position of ``tcp`` 0.02 m below the platform centre.
    """
    h = L_ARM * np.sin(THETA) + np.sqrt(L_ROD**2 - (R_BASE + L_ARM * np.cos(THETA) - R_PLAT) ** 2)
    platform = _se3(p=(0, 0, -h))
    links, joints, closures = [_link("base_link")], [], []
    for i in (1, 2, 3):
        phi = np.radians(120.0 * (i - 1))
        leg = _rz(phi)
        arm_w = _se3(leg @ _ry(THETA), leg @ np.array([R_BASE, 0.0, 0.0]))
        elbow_p = arm_w.act(np.array([L_ARM, 0.0, 0.0]))
        attach = platform.translation + leg @ np.array([R_PLAT, 0.0, 0.0])
        d_arm = arm_w.rotation.T @ (attach - elbow_p) / L_ROD
        beta = float(np.arctan2(d_arm[0], d_arm[2]))
        wrist_w = _se3(arm_w.rotation @ _ry(beta), attach)
        names = [f"{n}{i}" for n in ("arm", "ebar", "rod_a", "rod_b", "wbar", "wrist")]
        names += [f"rod_b_end{i}", f"wbar_b{i}"]
        links += [_link(n) for n in names]
        joints += [
            _joint(f"hinge{i}", "revolute", "base_link", f"arm{i}", arm_w, "0 1 0", (-0.3, 0.3)),
            _joint(
                f"elbow{i}",
                "revolute",
                f"arm{i}",
                f"ebar{i}",
                _se3(_ry(beta), (L_ARM, 0, 0)),
                "0 1 0",
            ),
            _joint(
                f"rod_a{i}", "revolute", f"ebar{i}", f"rod_a{i}", _se3(p=(0, HALF_W, 0)), "1 0 0"
            ),
            _joint(
                f"rod_b{i}", "revolute", f"ebar{i}", f"rod_b{i}", _se3(p=(0, -HALF_W, 0)), "1 0 0"
            ),
            _joint(f"wbar{i}", "revolute", f"rod_a{i}", f"wbar{i}", _se3(p=(0, 0, L_ROD)), "1 0 0"),
            _joint(
                f"rod_b_end{i}",
                "revolute",
                f"rod_b{i}",
                f"rod_b_end{i}",
                _se3(p=(0, 0, L_ROD)),
                "1 0 0",
                None,
            ),
            _joint(f"wbar_b{i}", "fixed", f"wbar{i}", f"wbar_b{i}", _se3(p=(0, -2 * HALF_W, 0))),
            _joint(
                f"wrist{i}", "revolute", f"wbar{i}", f"wrist{i}", _se3(p=(0, -HALF_W, 0)), "0 1 0"
            ),
        ]
        closures.append([f"rod_b_end{i}", f"wbar_b{i}"])
        to_platform = wrist_w.inverse() * platform
        if i == 1:
            links += [_link("platform"), _link("tcp")]
            joints.append(_joint("platform_mount", "fixed", "wrist1", "platform", to_platform))
            joints.append(_joint("tcp_joint", "fixed", "platform", "tcp", _se3(p=(0, 0, -0.02))))
        else:
            links.append(_link(f"wrist_end{i}"))
            joints.append(
                _joint(f"wrist_end{i}", "fixed", f"wrist{i}", f"wrist_end{i}", to_platform)
            )
            closures.append([f"wrist_end{i}", "platform"])
    urdf = (
        '<?xml version="1.0"?>\n<robot name="delta4r">\n' + "".join(links + joints) + "</robot>\n"
    )
    sidecar = {
        "closed_loop": closures,
        "type": ["6d"] * len(closures),
        "name_mot": ["hinge1", "hinge2", "hinge3"],
        "measured_frame": "tcp",
        "measured": "position",
        "workspace": {"joints": {f"hinge{i}": [-0.25, 0.25] for i in (1, 2, 3)}},
    }
    return urdf, sidecar


def write_machine(folder: Path, name: str, urdf: str, sidecar: dict) -> Path:
    """Write ``folder/name/name.urdf`` and ``.yaml``; returns the model directory."""
    d = Path(folder) / name
    d.mkdir(parents=True, exist_ok=True)
    (d / f"{name}.urdf").write_text(urdf, encoding="utf-8")
    (d / f"{name}.yaml").write_text(yaml.safe_dump(sidecar), encoding="utf-8")
    return d


MODEL_MACHINES = Path(__file__).parents[1] / "model" / "machines"


def copy_machine(folder: Path, name: str, **sidecar_changes) -> Path:
    """Copy tests/model/machines/<name> to ``folder`` with sidecar keys replaced; returns
    the model directory. Used to give a workspace to machines whose actuators have no
    range (a URDF ``<limit>`` without lower/upper is unlimited: random poses over ±π cross
    working modes, where inverse kinematics from home answers another mode)."""
    src = MODEL_MACHINES / name
    sidecar = yaml.safe_load((src / f"{name}.yaml").read_text(encoding="utf-8"))
    sidecar.update(sidecar_changes)
    return write_machine(folder, name, (src / f"{name}.urdf").read_text(encoding="utf-8"), sidecar)


FIVEBAR_WORKSPACE = {"joints": {"mot_l": [1.8, 2.2], "mot_r": [0.9, 1.3]}}

MJCF = Path(__file__).parents[1] / "model" / "mjcf"

FOURBAR_KEYFRAME = (-0.4, 1.059932, -0.390232)
"""(crank, coupler, rocker) [rad] of :func:`mjcf_fourbar_straight`'s keyframe ``home``."""


def mjcf_fourbar_straight(
    keyframe: bool = True, crank_range: str = "-60 -10", coupler_range: str = "-180 180"
) -> str:
    """MJCF text of a planar four-bar whose file pose (``qpos0``) is its extended dead
    point: crank AB = 0.1 m along +y from A = (0, 0), rocker DC = 0.2 m from
    D = (0.3, 0), coupler BC = |BD| − 0.2 ≈ 0.1162 m, so that B, C and D are collinear at
    qpos0 and the loop's passive Jacobian loses rank there (the crank cannot turn
    positive). Written the way MJCF legs are: ``<equality><connect>`` closing the loop,
    a position actuator on the crank, degrees, a spring (``stiffness="2"``) on the
    rocker, and — with ``keyframe`` — a ``<keyframe><key name="home">`` at crank −0.4 rad
    (:data:`FOURBAR_KEYFRAME`). Measured: the coupler site ``tool``.
    """
    key = (
        '  <keyframe><key name="home" qpos="' + " ".join(map(str, FOURBAR_KEYFRAME)) + '"/>'
        "</keyframe>\n"
        if keyframe
        else ""
    )
    return f"""<mujoco model="fourbar_straight">
  <compiler angle="degree"/>
  <default><joint type="hinge" axis="0 0 1"/></default>
  <worldbody>
    <body name="ground" pos="0 0 0.1">
      <body name="crank" euler="0 0 90">
        <joint name="crank_joint" range="{crank_range}"/>
        <body name="coupler" pos="0.1 0 0" euler="0 0 -108.43494882292201">
          <joint name="coupler_joint" range="{coupler_range}"/>
          <site name="tool" pos="0.06 0.03 0"/>
        </body>
      </body>
      <body name="rocker" pos="0.3 0 0" euler="0 0 161.565051177078">
        <joint name="rocker_joint" range="-180 180" stiffness="2"/>
      </body>
    </body>
  </worldbody>
  <equality>
    <connect name="pin_C" body1="coupler" body2="rocker" anchor="0.11622776601683793 0 0"/>
  </equality>
  <actuator><position name="crank_motor" joint="crank_joint" kp="10"/></actuator>
{key}</mujoco>
"""

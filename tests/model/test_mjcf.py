"""MJCF import: machines written in MuJoCo XML behave as their URDF twins.

Test machines live in tests/model/mjcf/: a planar four-bar (one connect), a Delta robot
(three top-level arms, six rods with ball joints, six connects to a free platform) and a
five-bar with two top-level bodies closed by a weld; zoo.xml is an open tree of frame
conventions cross-checked against Pinocchio's own MJCF parser.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pincal
from pincal.errors import ModelFileError, UnknownNameError
from pincal.identification import identify
from pincal.measure import simulate_measurements
from pincal.model import (
    Mechanism,
    load_mechanism,
    load_mjcf,
    mjcf_to_urdf,
    parameters,
    sample_actuators,
)
from pincal.sensitivity import identifiability, identification_jacobian

HERE = Path(__file__).with_name("mjcf")
ALL = ("x", "y", "z", "rx", "ry", "rz")


@pytest.fixture(scope="module")
def fourbar() -> Mechanism:
    return load_mjcf(HERE / "fourbar.xml", measured_frame="tool")


@pytest.fixture(scope="module")
def delta() -> Mechanism:
    return load_mjcf(HERE / "delta.xml")  # delta.yaml adds measured_frame, measured, workspace


@pytest.fixture(scope="module")
def fivebar() -> Mechanism:
    return load_mjcf(HERE / "fivebar.xml")  # fivebar.yaml: measured_frame pen, workspace


MACHINES = ("fourbar", "delta", "fivebar")
# parameters whose effect stays in the plane of a planar machine (out-of-plane errors
# would open its loops), or any for the spatial Delta
CANDIDATES = {
    "fourbar": [
        {"joints": "*", "dofs": ["tx", "ty", "rz"]},
        {"joints": "crank_joint", "dofs": ["offset"]},
    ],
    "delta": [
        {"joints": "arm?_hinge", "dofs": ["tx", "ty", "tz", "rx", "ry", "rz", "offset"]},
        {"joints": "arm?_rod?_tip_?_frame", "dofs": ["tx", "ty", "tz"]},
        {"joints": "tcp_frame", "dofs": ["tx", "ty", "tz"]},
    ],
    "fivebar": [
        {"joints": "*", "dofs": ["tx", "ty", "rz"]},
        {"joints": "*_motor", "dofs": ["offset"]},
    ],
}


def test_structure_and_names(fourbar, delta, fivebar):
    """MJCF names survive: bodies and sites as links, joints, equalities, actuators."""
    assert fourbar.actuated == ("crank_joint",)
    assert [(c.frame_a, c.frame_b, c.label) for c in fourbar.closures] == [
        ("pin_C_1", "pin_C_2", "3d")
    ]
    assert fourbar.sidecar.closure_names == ("pin_C",)
    assert fourbar.sidecar.actuator_names == {"crank_motor": "crank_joint"}
    assert {"ground", "crank", "coupler", "rocker", "tool"} <= set(fourbar.tree.links)
    assert delta.model.nq == 3 + 6 * 3 + 7 and delta.model.nv == 27
    assert delta.mobility == 3 and delta.actuated == ("arm1_hinge", "arm2_hinge", "arm3_hinge")
    assert len(delta.closures) == 6 and {c.label for c in delta.closures} == {"3d"}
    assert delta.tree.joints["platform_free"].type == "floating"
    assert delta.tree.joints["arm1_roda_ball_y"].type == "revolute"
    assert delta.measured_frame == "tcp" and delta.measured_components == ("x", "y", "z")
    # five-bar: two top-level bodies on the world link; a weld is a 6d closure
    assert fivebar.tree.joints["left_motor"].parent == "world"
    assert fivebar.tree.joints["right_motor"].parent == "world"
    assert [c.label for c in fivebar.closures] == ["6d"] and fivebar.mobility == 2
    # two actuators on one joint declare it once; actuator names are kept
    assert fivebar.actuated == ("left_motor", "right_motor")
    assert fivebar.sidecar.actuator_names == {
        "motor0": "left_motor",
        "position1": "right_motor",
        "velocity2": "right_motor",
    }


@pytest.mark.parametrize("name", MACHINES)
def test_loops_close_at_home(name, request):
    mech = request.getfixturevalue(name)
    assert np.max(np.abs(mech.closure_residual(mech.q_home))) <= 1e-12


def test_file_pose_is_qpos0(fourbar, delta):
    """Joint values equal MuJoCo qpos: ref is folded into the origins, loops close at qpos0."""
    q0 = fourbar.with_actuators(fourbar.q_home, [np.pi / 2])  # crank ref = 90 deg
    assert fourbar.sidecar.home["crank_joint"][0] == pytest.approx(np.pi / 2)
    assert np.allclose(
        fourbar.frame_placement(q0, "tool").translation, [0.15, 0.15, 0.1], atol=1e-15
    )
    assert np.allclose(fourbar.configuration([np.pi / 2]), fourbar.q_home, atol=1e-12)
    assert delta.sidecar.home["arm1_hinge"][0] == pytest.approx(np.radians(30))


def test_fourbar_same_as_urdf_route(fourbar):
    """The four-bar written by hand as URDF + sidecar gives the same forward kinematics."""
    twin = load_mechanism(HERE / "fourbar_urdf.urdf")
    assert twin.model.nq == fourbar.model.nq and twin.mobility == fourbar.mobility
    worst = 0.0
    for angle in np.linspace(np.radians(50), np.radians(130), 20):
        a, b = fourbar.forward(np.array([angle])), twin.forward(np.array([angle]))
        worst = max(worst, np.max(np.abs(a.homogeneous - b.homogeneous)))
    assert worst <= 1e-12


@pytest.mark.parametrize("name", MACHINES)
def test_forward_inverse_round_trip(name, request):
    mech = request.getfixturevalue(name)
    comps = [ALL.index(c) for c in mech.measured_components]
    for row in sample_actuators(mech, 4, np.random.default_rng(3)):
        T = mech.forward(row)
        q_act = mech.inverse(T, q_guess=mech.q_home)
        T2 = mech.forward(q_act)
        err = np.concatenate([T2.translation - T.translation, pin.log3(T.rotation.T @ T2.rotation)])
        assert np.max(np.abs(err[comps])) <= 1e-9
        assert np.max(np.abs(q_act - row)) <= 1e-9


def _measured(mech, rows, R_ref):
    out = []
    for row, R0 in zip(rows, R_ref, strict=True):
        T = mech.forward(row)
        out.append(np.concatenate([T.translation, pin.log3(R0.T @ T.rotation)]))
    return np.concatenate(out)


@pytest.mark.parametrize("name", MACHINES)
def test_identification_jacobian_matches_central_differences(name, request):
    mech = request.getfixturevalue(name)
    params = parameters(mech, CANDIDATES[name])
    rng = np.random.default_rng(7)
    pick = np.sort(rng.choice(len(params), size=min(len(params), 14), replace=False))
    params = parameters(mech, [params.names[i] for i in pick])
    rows = sample_actuators(mech, 2, np.random.default_rng(4))
    values = rng.normal(0, 2e-4, len(params))
    J = identification_jacobian(mech, params, rows, values, components=ALL)
    at = params.apply(mech, values)
    R_ref = [at.forward(r).rotation for r in rows]
    h, cols = 1e-6, []
    for k in range(len(params)):
        e = np.zeros(len(params))
        e[k] = h
        plus = _measured(params.apply(mech, values + e), rows, R_ref)
        minus = _measured(params.apply(mech, values - e), rows, R_ref)
        cols.append((plus - minus) / (2 * h))
    J_fd = np.stack(cols, axis=1)
    assert np.max(np.abs(J - J_fd)) <= 1e-6 * np.max(np.abs(J))


@pytest.mark.parametrize("name", MACHINES)
def test_noise_free_identification_recovers_base_parameters(name, request):
    mech = request.getfixturevalue(name)
    candidates = parameters(mech, CANDIDATES[name])
    rows = sample_actuators(mech, 30, np.random.default_rng(11))
    ident = identifiability(mech, candidates, rows)
    params = parameters(mech, [candidates.names[i] for i in ident.base])
    assert 0 < len(params) < len(candidates)
    true = np.random.default_rng(1).normal(0, 2e-4, len(params))
    meas = simulate_measurements(params.apply(mech, true), rows)
    res = identify(mech, params, meas)
    assert res.success, res.message
    assert np.max(np.abs(res.values - true)) <= 1e-9
    assert res.before.max_position > 1e-5


def _pin_q(ref: pin.Model, values: dict[str, float], ball: dict[str, np.ndarray]) -> np.ndarray:
    """Pinocchio-MJCF configuration: MuJoCo qpos order (hinge/slide values, ball quats)."""
    q = []
    for j in range(1, ref.njoints):
        name = ref.names[j]
        if ref.joints[j].shortname() == "JointModelComposite":
            q += [values[n] for n in ("j_slide", "j_tilt")]
        elif name in ball:
            q += list(pin.Quaternion(ball[name]).coeffs())
        else:
            q.append(values[name])
    return np.array(q)


def test_zoo_matches_pinocchio_mjcf_parser():
    """Frame conventions (euler/axisangle/xyaxes/zaxis/quat/fromto, degrees, eulerseq,
    default classes, childclass, ref, joint pos, multi-joint bodies, ball) agree with
    ``pin.buildModelAndConstraintsFromMJCF`` on a tree with one top-level body."""
    from pincal.model.files._mjcf_tree import euler_xyz

    urdf, _ = mjcf_to_urdf(HERE / "zoo.xml")
    mine = pin.buildModelFromXML(urdf)
    ref, points, frames = pin.buildModelAndConstraintsFromMJCF(str(HERE / "zoo.xml"))
    assert len(points) == len(frames) == 0
    assert mine.nv == ref.nv and mine.nq == ref.nq - 1  # the ball: 3 revolutes vs a quaternion
    checked = [f.name for f in ref.frames if f.type in (pin.BODY, pin.OP_FRAME)]
    assert {"base", "wrist", "s_tip", "s_side"} <= set(checked)
    rng = np.random.default_rng(0)
    dm, dr = mine.createData(), ref.createData()
    for _ in range(5):
        values = {
            n: rng.uniform(-0.6, 0.6) for n in ("j_base", "j_upper", "j_slide", "j_tilt", "j_side")
        }
        R = pin.exp3(rng.normal(0, 0.5, 3))
        qm = pin.neutral(mine)
        for n, v in {
            **values,
            **dict(zip(("j_ball_x", "j_ball_y", "j_ball_z"), euler_xyz(R), strict=True)),
        }.items():
            qm[mine.idx_qs[mine.getJointId(n)]] = v
        pin.framesForwardKinematics(mine, dm, qm)
        pin.framesForwardKinematics(ref, dr, _pin_q(ref, values, {"j_ball": R}))
        for name in checked:
            a, b = dm.oMf[mine.getFrameId(name)], dr.oMf[ref.getFrameId(name)]
            assert np.max(np.abs(a.homogeneous - b.homogeneous)) <= 1e-12, name


def test_fourbar_matches_pinocchio_relative_to_its_top_body(fourbar):
    """Same nq/nv and placements as Pinocchio's parser, relative to the top-level body:
    Pinocchio drops the position of a jointless top-level body (ground at z = 0.1 m)."""
    ref, points, frames = pin.buildModelAndConstraintsFromMJCF(str(HERE / "fourbar.xml"))
    assert (ref.nq, ref.nv) == (fourbar.model.nq, fourbar.model.nv)
    assert len(points) == 1 and len(frames) == 0
    dr = ref.createData()
    for q_act in np.radians([60.0, 90.0, 120.0]):
        q = fourbar.configuration(np.array([q_act]))
        kin = fourbar.kinematics(q, frames=["ground", "crank", "coupler", "rocker", "tool"])
        pin.framesForwardKinematics(ref, dr, q)  # same joint order: crank, coupler, rocker
        g_ref = dr.oMf[ref.getFrameId("ground")]
        assert kin.placements["ground"].translation[2] == pytest.approx(0.1)
        assert g_ref.translation[2] == 0.0  # the Pinocchio trap
        for name in ("crank", "coupler", "rocker", "tool"):
            a = kin.placements["ground"].actInv(kin.placements[name])
            b = g_ref.actInv(dr.oMf[ref.getFrameId(name)])
            assert np.max(np.abs(a.homogeneous - b.homogeneous)) <= 1e-12, name


ROT = {
    "x": lambda t: pin.exp3(np.array([t, 0, 0])),
    "y": lambda t: pin.exp3(np.array([0, t, 0])),
    "z": lambda t: pin.exp3(np.array([0, 0, t])),
}


def _one_body(attrs: str, compiler: str = "", extra: str = "") -> tuple[str, dict]:
    return mjcf_to_urdf(
        f'<mujoco><compiler {compiler}/><worldbody><body name="b" {attrs}>'
        f'<joint name="j"/>{extra}</body></worldbody></mujoco>'
    )


def _origin(urdf: str, joint: str) -> pin.SE3:
    return pincal.model.UrdfTree(urdf).joints[joint].origin


def test_orientation_conventions_where_pinocchio_differs():
    """MuJoCo semantics where Pinocchio's parser deviates: upper-case eulerseq letters are
    extrinsic (fixed axes); axisangle axes are normalised; site defaults apply."""
    d = np.radians
    urdf, _ = _one_body('euler="10 20 30"', 'angle="degree" eulerseq="ZYX"')
    R = ROT["x"](d(30)) @ ROT["y"](d(20)) @ ROT["z"](d(10))
    assert np.allclose(_origin(urdf, "j").rotation, R, atol=1e-15)
    urdf, _ = _one_body('euler="10 20 30"', 'angle="degree" eulerseq="zYx"')
    R = ROT["y"](d(20)) @ ROT["z"](d(10)) @ ROT["x"](d(30))
    assert np.allclose(_origin(urdf, "j").rotation, R, atol=1e-15)
    urdf, _ = _one_body('axisangle="2 0 0 0.5"', 'angle="radian"')
    assert np.allclose(_origin(urdf, "j").rotation, ROT["x"](0.5), atol=1e-15)
    urdf, _ = _one_body('zaxis="0 0 -1"')
    assert np.allclose(_origin(urdf, "j").rotation, ROT["x"](np.pi), atol=1e-15)
    urdf, _ = mjcf_to_urdf(
        '<mujoco><default><site pos="0 0 0.01"/></default><worldbody><body name="b">'
        '<site name="s"/><site name="t" pos="1 0 0"/></body></worldbody></mujoco>'
    )
    assert np.allclose(_origin(urdf, "s_frame").translation, [0, 0, 0.01])
    assert np.allclose(_origin(urdf, "t_frame").translation, [1, 0, 0])


def test_multi_joint_ref_at_qpos0():
    """ref inside a multi-joint body (Pinocchio's parser ignores it): bodies sit at their
    file pose at qpos0."""
    text = (
        '<mujoco><worldbody><body name="a"><joint name="ja"/><body name="c" pos="0.3 0 0">'
        '<joint name="j1" type="slide" axis="0 0 1" ref="0.05"/><joint name="j2" '
        'pos="0.01 0.02 0" ref="20"/><site name="s" pos="0.1 0 0"/></body></body>'
        '</worldbody><actuator><motor joint="j1"/><motor joint="j2"/><motor joint="ja"/>'
        "</actuator></mujoco>"
    )
    urdf, sidecar = mjcf_to_urdf(text)
    mech = Mechanism(urdf, sidecar, measured_frame="s")
    assert sidecar["home"] == pytest.approx({"ja": 0.0, "j1": 0.05, "j2": np.radians(20)})
    T = mech.frame_placement(mech.q_home)
    assert np.allclose(T.translation, [0.4, 0, 0], atol=1e-15)
    assert np.allclose(T.rotation, np.eye(3), atol=1e-15)


def test_weld_relpose_and_sites():
    """weld with an explicit relpose, and connect/weld between sites."""
    body = (
        '<body name="a"><joint name="ja" axis="0 0 1"/><site name="sa" pos="1 0 0"/>'
        '<body name="b" pos="1 0 0"><joint name="jb" axis="0 0 1"/>'
        '<site name="sb" pos="0 0 0"/></body></body>'
    )
    urdf, sc = mjcf_to_urdf(
        f"<mujoco><worldbody>{body}</worldbody><equality>"
        '<weld name="w" body1="a" body2="b" relpose="0.5 0 0 0 0 0 1" anchor="0.1 0 0"/>'
        '<connect site1="sa" site2="sb"/></equality></mujoco>'
    )
    assert sc["closed_loop"] == [["w_1", "w_2"], ["sa", "sb"]] and sc["type"] == ["6d", "3d"]
    assert sc["closure_names"] == ["w", "connect1"]
    T = _origin(urdf, "w_1_frame")
    assert np.allclose(T.translation, [0.5, 0, 0]) and np.allclose(T.rotation, ROT["z"](np.pi))
    assert np.allclose(_origin(urdf, "w_2_frame").translation, [0.1, 0, 0])


def test_free_joint_and_keyframe_home():
    text = (
        '<mujoco><worldbody><body name="p" pos="1 2 3" quat="0 1 0 0"><freejoint name="f"/>'
        '<body name="r"><joint name="jb" type="ball"/></body></body></worldbody><keyframe>'
        '<key name="other" qpos="0 0 0 1 0 0 0 1 0 0 0"/>'
        '<key name="home" qpos="4 5 6 1 0 0 0 0.9 0.1 0.2 0.3"/></keyframe></mujoco>'
    )
    _, sc = mjcf_to_urdf(text)
    assert sc["home"]["f"] == [4.0, 5.0, 6.0, 0.0, 0.0, 0.0, 1.0]
    R = pin.Quaternion(*(np.array([0.9, 0.1, 0.2, 0.3]) / np.linalg.norm([0.9, 0.1, 0.2, 0.3])))
    a, b, c = (sc["home"][f"jb_{k}"] for k in "xyz")
    assert np.allclose(ROT["x"](a) @ ROT["y"](b) @ ROT["z"](c), R.toRotationMatrix())
    _, sc0 = mjcf_to_urdf(text.replace('name="home"', 'name="late"'))  # first keyframe
    assert sc0["home"]["f"] == [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]
    _, sc1 = mjcf_to_urdf(text.replace("<keyframe>", "<!--").replace("</keyframe>", "-->"))
    assert sc1["home"]["f"] == [1.0, 2.0, 3.0, 1.0, 0.0, 0.0, 0.0]  # qpos0: the file pose
    with pytest.raises(UnknownNameError, match="keyframe 'nope' not found"):
        mjcf_to_urdf(text, keyframe="nope")


@pytest.mark.parametrize(
    ("snippet", "error", "match"),
    [
        (
            '<equality><joint joint1="ja" joint2="jb"/></equality>',
            ModelFileError,
            r"<equality><joint> 'joint0' is not supported: it couples joint 'ja' to joint 'jb'"
            r" by a polynomial \(polycoef '0 1 0 0 0'\).*model the linkage .*<connect>.*"
            r"drive both joints \(load_mjcf\(actuated=\[\.\.\., 'ja', 'jb'\]\)",
        ),
        (
            '<equality><joint name="hold" joint1="ja" polycoef="0.3 0 0 0 0"/></equality>',
            ModelFileError,
            r"<equality><joint> 'hold' is not supported: it holds joint 'ja' at a value "
            r"\(polycoef '0.3 0 0 0 0'\).*'lock: \{ja: VALUE\}' \[rad or m\] in a sidecar",
        ),
        (
            '<equality><tendon tendon1="t"/></equality>',
            ModelFileError,
            r"<equality><tendon> 'tendon0' is not supported: it couples tendon lengths "
            r"\('t'\).*path as a linkage closed by <connect>, or remove the equality",
        ),
        (
            '<equality><flex flex="f"/></equality>',
            ModelFileError,
            r"<equality><flex> 'flex0' is not supported: only connect \(3d\) and weld",
        ),
        (
            '<equality><connect body1="a" body2="nope" anchor="0 0 0"/></equality>',
            UnknownNameError,
            "MJCF body 'nope' not found",
        ),
        (
            '<equality><connect site1="nope" site2="sa"/></equality>',
            UnknownNameError,
            "MJCF site 'nope' not found",
        ),
        ('<include file="other.xml"/>', ModelFileError, "<include> is not supported"),
        (
            '<actuator><motor joint="nope"/></actuator>',
            UnknownNameError,
            "MJCF joint 'nope' not found",
        ),
        ('<actuator><motor joint="jf"/></actuator>', ModelFileError, "drives the ball joint 'jf'"),
    ],
)
def test_unsupported_or_wrong_input_is_refused(snippet, error, match):
    body = (
        '<worldbody><body name="a"><joint name="ja"/><site name="sa"/><body name="b">'
        '<joint name="jb"/><joint name="jf" type="ball"/></body></body></worldbody>'
    )
    with pytest.raises(error, match=match) as info:
        mjcf_to_urdf(f"<mujoco>{body}{snippet}</mujoco>")
    assert "\n" not in str(info.value)  # one line


def test_inactive_joint_equality_is_skipped(caplog):
    body = '<worldbody><body name="a"><joint name="ja"/></body></worldbody>'
    eq = '<equality><joint name="off" joint1="ja" active="false"/></equality>'
    with caplog.at_level(logging.WARNING, logger="pincal.model.loading._mjcf"):
        _, sc = mjcf_to_urdf(f"<mujoco>{body}{eq}</mujoco>")
    assert "closed_loop" not in sc and "inactive equality 'off' skipped" in caplog.text


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("<robot/>", "root element is <robot>"),
        ("<mujoco><worldbody/></mujoco>", "no <worldbody> with a <body>"),
        (
            '<mujoco><worldbody><body name="a" pos="1 2"/></worldbody></mujoco>',
            "body 'a' pos: expected 3 finite numbers",
        ),
        (
            '<mujoco><worldbody><body name="a" euler="1 2 3" quat="1 0 0 0"/></worldbody></mujoco>',
            "give one orientation",
        ),
        (
            '<mujoco><worldbody><body name="a"><joint type="screw"/></body></worldbody></mujoco>',
            "unknown type 'screw'",
        ),
        (
            '<mujoco><worldbody><body name="a"><site name="a"/></body></worldbody></mujoco>',
            r"names \['a'\] are used twice",
        ),
        (
            '<mujoco><worldbody><body name="a"><body name="b"><freejoint/></body></body>'
            "</worldbody></mujoco>",
            "only alone in a top-level body",
        ),
        ("<mujoco><worldbody><body", "not well-formed XML"),
    ],
)
def test_malformed_mjcf(text, match):
    with pytest.raises(ModelFileError, match=match):
        mjcf_to_urdf(text)


def test_non_joint_actuator_is_skipped_with_warning(caplog):
    text = (
        '<mujoco><worldbody><body name="a"><joint name="ja"/><site name="s"/></body>'
        '</worldbody><actuator><motor name="m" site="s"/><motor joint="ja"/></actuator>'
        "</mujoco>"
    )
    with caplog.at_level(logging.WARNING, logger="pincal.model.loading._mjcf"):
        _, sc = mjcf_to_urdf(text)
    assert sc["name_mot"] == ["ja"] and "actuator 'm'" in caplog.text


def test_load_mjcf_errors_and_overrides(tmp_path):
    with pytest.raises(ModelFileError, match="MJCF file .*missing.xml does not exist"):
        load_mjcf(tmp_path / "missing.xml")
    mech = load_mjcf(HERE / "fivebar.xml", actuated=["left_motor", "right_motor"], keyframe="home")
    assert mech.actuated == ("left_motor", "right_motor") and mech.measured_frame == "pen"
    assert mjcf_to_urdf(HERE / "fivebar.xml")[1]["measured_frame"] == "right_distal"  # last leaf
    out = pincal.save_urdf(mech, tmp_path / "fivebar.urdf")
    again = load_mechanism(out)
    assert np.allclose(
        again.forward(np.array([2.0, 1.1])).homogeneous,
        mech.forward(np.array([2.0, 1.1])).homogeneous,
        atol=1e-12,
    )

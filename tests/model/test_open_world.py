"""Public-model habits (the open world): small machines written the way many public
closed-loop URDF + robot.yaml files are, under tests/model/machines/."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import pincal
from pincal.model import load_mechanism, parameters, sample_actuators

MACHINES = Path(__file__).parent / "machines"


@pytest.fixture(scope="module")
def fivebar():
    return load_mechanism(MACHINES / "fivebar")


def _fd_identification_jacobian(mech, params, rows, h=1e-6):
    cols = []
    for k in range(len(params)):
        e = np.zeros(len(params))
        e[k] = h
        plus = [params.apply(mech, e).forward(r).translation[:2] for r in rows]
        minus = [params.apply(mech, -e).forward(r).translation[:2] for r in rows]
        cols.append((np.concatenate(plus) - np.concatenate(minus)) / (2 * h))
    return np.stack(cols, axis=1)


# ------------------------------------------------------------- 5. closure frames = joint names
def test_closure_frames_named_by_joints_give_the_fd_identification_jacobian(fivebar):
    assert fivebar.closures[0].frame_a == "pin_l"
    assert fivebar.frame_link("pin_l") == "tip_l" and fivebar.frame_link("end_r") == "tip_r"
    assert np.max(np.abs(fivebar.closure_residual(fivebar.q_home))) < 1e-12
    params = parameters(fivebar, "full")
    home = fivebar.actuators_of(fivebar.q_home)
    rows = home + np.array([[0.0, 0.0], [0.05, -0.04], [-0.03, 0.06]])
    J = pincal.identification_jacobian(fivebar, params, rows)
    J_fd = _fd_identification_jacobian(fivebar, params, rows)
    assert J.shape == (6, len(params))
    assert np.max(np.abs(J - J_fd)) <= 1e-6 * np.max(np.abs(J))


# ------------------------------------------------- 6. <limit effort velocity/> without a range
def test_limit_without_lower_upper_is_unlimited_with_a_note(fivebar):
    assert np.all(np.isinf(fivebar.actuator_limits))
    assert any("'mot_l'" in n and "zero-width" in n and "unlimited" in n for n in fivebar.notes)
    home = fivebar.actuators_of(fivebar.q_home)
    target = fivebar.forward(home + 0.1)
    q_act = fivebar.inverse(target)  # was: "outside its limits [0, 0]"
    assert np.allclose(fivebar.forward(q_act).translation, target.translation, atol=1e-9)
    rows = sample_actuators(fivebar, 12, np.random.default_rng(3))
    assert np.all(np.ptp(rows, axis=0) > 0.3)  # was: every row equal to [0, 0]
    assert len({tuple(np.round(r, 9)) for r in rows}) == 12


def test_zero_width_range_takes_the_sidecar_workspace_range():
    xml = (MACHINES / "fivebar" / "fivebar.urdf").read_text()
    sc = pincal.model.read_sidecar(MACHINES / "fivebar" / "fivebar.yaml")
    sc["workspace"] = {"joints": {"mot_l": [1.5, 2.5]}}
    mech = pincal.Mechanism(xml, sc)
    assert np.allclose(mech.actuator_limits[0], [1.5, 2.5])
    assert np.all(np.isinf(mech.actuator_limits[1]))
    assert any("'mot_l'" in n and "[1.5, 2.5]" in n for n in mech.notes)


# ------------------------------------------------------------ 7. joint_name / joint_type
@pytest.fixture(scope="module")
def rssr():
    return load_mechanism(MACHINES / "rssr")


def test_joint_type_spherical_turns_the_placeholder_into_a_ball_joint(rssr):
    j = rssr.model.getJointId("ball_a")
    assert rssr.model.joints[j].shortname() == "JointModelSpherical"
    assert (rssr.model.nqs[j], rssr.model.nvs[j]) == (4, 3)
    assert rssr.mobility == 1
    assert any("'ball_a' is a spherical joint" in n for n in rssr.notes)
    for crank in (0.0, 0.3, 0.6, -0.4):
        q = rssr.configuration([crank])
        a = rssr.frame_placement(q, "coupler").translation
        b = rssr.frame_placement(q, "rocker_tip").translation
        assert np.isclose(np.linalg.norm(b - a), 0.17, atol=1e-12)  # coupler length kept
    params = parameters(rssr, "full")
    rows = np.array([[0.1], [0.5]])
    J = pincal.identification_jacobian(rssr, params, rows)
    cols = []
    for k in range(len(params)):
        e = np.zeros(len(params))
        e[k] = 1e-6
        plus = [params.apply(rssr, e).forward(r).translation for r in rows]
        minus = [params.apply(rssr, -e).forward(r).translation for r in rows]
        cols.append((np.concatenate(plus) - np.concatenate(minus)) / 2e-6)
    J_fd = np.stack(cols, axis=1)
    assert np.max(np.abs(J - J_fd)) <= 1e-6 * np.max(np.abs(J))


def _rssr_with(**changes):
    xml = (MACHINES / "rssr" / "rssr.urdf").read_text()
    sc = pincal.model.read_sidecar(MACHINES / "rssr" / "rssr.yaml")
    sc.update(changes)
    return xml, sc


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"joint_type": ["cylindrical"]}, "'cylindrical' of joint 'ball_a' is not supported"),
        ({"joint_name": ["ball_b"]}, "joint 'ball_b' not found"),
        ({"joint_name": ["coupler_end"]}, "is a fixed URDF joint"),
        ({"joint_type": ["spherical", "spherical"]}, "must have the same length"),
    ],
)
def test_unsupported_joint_kinds_are_clear_errors(changes, message):
    xml, sc = _rssr_with(**changes)
    with pytest.raises(pincal.PincalError, match=message):
        pincal.Mechanism(xml, sc)


# ------------------------------------------------------------- 8. default measured frame
@pytest.mark.parametrize("name", pincal.model.bundled_models())
def test_default_measured_frame_finds_the_effector_of_every_bundled_model(name):
    folder = pincal.model.loading._model_files.MODELS_DIR / name
    sc = pincal.model.read_sidecar(folder / f"{name}.yaml")
    chosen = sc.pop("measured_frame")
    mech = pincal.Mechanism((folder / f"{name}.urdf").read_text(), sc)
    # the old rule (last leaf link) gave a closure anchor on 4 of the 5 models
    assert mech.measured_frame == chosen
    assert mech.measured_frame_candidates[0] == chosen


def test_undecidable_measured_frame_lists_candidates():
    xml = (MACHINES / "fivebar" / "fivebar.urdf").read_text()
    sc = pincal.model.read_sidecar(MACHINES / "fivebar" / "fivebar.yaml")
    del sc["measured_frame"]
    with pytest.raises(pincal.errors.ModelFileError, match="choose one with --frame") as info:
        pincal.Mechanism(xml, sc)
    assert "'rod_l'" in str(info.value) and "'rod_r'" in str(info.value)
    ok = pincal.Mechanism(xml, sc, measured_frame="rod_r")
    assert ok.measured_frame == "rod_r"


# ------------------------------------------------------------------ 9. assembly branch
@pytest.fixture(scope="module")
def prs3():
    return load_mechanism(MACHINES / "prs3")


def _passive_det_sign(mech, q):
    return np.sign(np.linalg.det(mech.closure_jacobian(q)[:, mech.free_dofs]))


def test_user_home_is_kept_as_the_assembly_start(prs3):
    assert np.allclose(prs3.actuators_of(prs3.q_home), [0.2, 0.2, 0.2], atol=0)  # was 0.2009
    assert prs3.measured_frame == "platform"
    z = prs3.frame_placement(prs3.q_home).translation[2]
    assert np.isclose(z, 0.2 + np.sqrt(0.12**2 - 0.1**2), atol=1e-12)  # knees-up mode


def test_forward_kinematics_stays_on_the_home_branch(prs3):
    rows = np.array([[0.211, 0.237, 0.257], [0.208, 0.228, 0.265]])
    home_sign = _passive_det_sign(prs3, prs3.q_home)
    Q = prs3.configurations(rows)
    # a plain warm-started Newton from Q[0] lands on the other mode (det sign flips)
    plain = prs3.loop_solver.newton(prs3.with_actuators(Q[0], rows[1]), prs3.free_dofs).q
    assert _passive_det_sign(prs3, plain) == -home_sign
    assert [_passive_det_sign(prs3, q) for q in Q] == [home_sign, home_sign]
    # reference: fine continuation from Q[0] (each step a tiny move)
    q = Q[0]
    for t in np.linspace(0, 1, 201)[1:]:
        q = prs3.configuration(rows[0] + t * (rows[1] - rows[0]), q_guess=q)
    assert np.allclose(Q[1], q, atol=1e-9)
    assert not np.allclose(Q[1], plain, atol=1e-3)
    # the same answer whatever the starting guess (here: a guess on the other mode)
    assert np.allclose(prs3.configuration(rows[1], q_guess=plain), Q[1], atol=1e-9)


def test_no_solution_on_the_home_branch_names_the_pose(prs3):
    rows = np.array([[0.2, 0.2, 0.2], [0.133, 0.283, 0.131], [0.251, 0.163, 0.172]])
    with pytest.raises(pincal.errors.ConvergenceError, match="pose 2") as info:
        prs3.configurations(rows)
    assert info.value.pose_index == 2
    assert "assembly branch of home" in str(info.value)


# ---------------------------------------------------------------- 10. honest diagnoses
def _machine(name, urdf_edit=None, **sidecar_changes):
    xml = (MACHINES / name / f"{name}.urdf").read_text()
    if urdf_edit:
        xml = xml.replace(*urdf_edit)
    sc = pincal.model.read_sidecar(MACHINES / name / f"{name}.yaml")
    sc.update(sidecar_changes)
    return xml, sc


def test_singular_home_is_called_singular():
    legs = {"leg1": 0.2, "leg2": 0.2, "leg3": 0.2}
    xml, sc = _machine("rpr3", home={"ee_float": [0, 0, 0, 0, 0, 0], **legs})  # legs radial
    with pytest.raises(pincal.errors.SingularConfigurationError, match="home configuration is"):
        pincal.Mechanism(xml, sc)  # was: MobilityError "actuate more joints"
    ok = pincal.Mechanism(*_machine("rpr3"))  # the sidecar's rotated home is fine
    assert ok.mobility == 3


def test_under_actuation_names_the_free_passive_joints():
    xml, sc = _machine("rpr3", name_mot=["leg1", "leg2"])
    with pytest.raises(pincal.errors.MobilityError, match="free passive joints") as info:
        pincal.Mechanism(xml, sc)
    assert "'rev3'" in str(info.value) and "'ee_float'" in str(info.value)


def test_open_closure_blames_frame_names_or_geometry():
    pairs = [["leg1", "pin1"], ["leg2", "pin2"], ["pin3", "pin1"]]
    xml, sc = _machine("rpr3", closed_loop=pairs)
    with pytest.raises(pincal.errors.ClosureError, match="frame names are probably wrong"):
        pincal.Mechanism(xml, sc)
    xml, sc = _machine("rssr", urdf_edit=('<origin xyz="0.17 0 0"/>', '<origin xyz="0.5 0 0"/>'))
    with pytest.raises(pincal.errors.ClosureError, match="the geometry"):
        pincal.Mechanism(xml, sc)


# ------------------------------------------------------ 11. example-robot-data stub files
def test_ur3_resolves_to_the_real_robot_not_the_empty_stub():
    mech = load_mechanism("ur3")  # was: ur3.urdf, a xacro leftover with 0 links
    assert pincal.model.example_robot_urdf("ur3").name == "ur3_robot.urdf"
    assert mech.n_actuated == 6 and len(mech.tree.links) > 6
    for name in pincal.model.example_robot_names():
        assert b"<link" in pincal.model.example_robot_urdf(name).read_bytes()
        # every listed name loads by name, the qualified 'package/stem' ones too (an
        # 'anymal_b_simple/anymal' was taken for a missing file path)
        urdf, _ = pincal.model.resolve_model_path(name)
        assert urdf == pincal.model.example_robot_urdf(name)


def test_open_closure_blames_the_home_guess_when_other_starts_close():
    # all joints at 0: both chains stretched along x, the gap is along x, and no joint
    # can move a tip along x there: Newton stalls, yet the loop closes from elsewhere
    flat = {"mot_l": 0.0, "elbow_l": 0.0, "mot_r": 0.0, "elbow_r": 0.0}
    xml, sc = _machine("fivebar", home=flat)
    with pytest.raises(pincal.errors.ClosureError, match="'home' guess in the sidecar is at fault"):
        pincal.Mechanism(xml, sc)


def test_inverse_answers_only_on_the_home_branch(prs3):
    rows = np.array([[0.211, 0.237, 0.257], [0.208, 0.228, 0.265]])
    q0 = prs3.configurations(rows[:1])[0]
    start = prs3.with_actuators(q0, rows[1])
    other = prs3.loop_solver.newton(start, prs3.free_dofs).q  # other mode
    targets = [prs3.frame_placement(q) for q in (q0, other)]
    answered = 0
    for T in targets:
        try:
            q_act = prs3.inverse(T)
        except pincal.errors.UnreachablePoseError as exc:
            assert "another assembly mode" in str(exc)
            continue
        answered += 1
        back = prs3.forward(q_act)  # on home's branch: must give the target back
        assert np.allclose(back.homogeneous, T.homogeneous, atol=1e-9)
    assert answered >= 1

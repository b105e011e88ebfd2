"""Loading, closed-loop forward/inverse kinematics and input validation."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml

import pincal
from pincal.model import load_mechanism
from pincal.model.loading._model_files import MODELS_DIR

STEWART = MODELS_DIR / "stewart_6ups"
B_DEG = (-15, 15, 105, 135, 225, 255)
P_DEG = (-45, 45, 75, 165, 195, 285)


def closed_form_leg_lengths(T: pin.SE3) -> np.ndarray:
    """Plain Stewart IK from the model README's geometry: |T·a_i − b_i| [m]."""
    b = np.array([[0.3 * np.cos(t), 0.3 * np.sin(t), 0.0] for t in np.radians(B_DEG)])
    a = np.array([[0.15 * np.cos(t), 0.15 * np.sin(t), 0.0] for t in np.radians(P_DEG)])
    return np.linalg.norm((T.rotation @ a.T).T + T.translation - b, axis=1)


def random_pose(rng) -> pin.SE3:
    p = np.array([rng.uniform(-0.06, 0.06), rng.uniform(-0.06, 0.06), rng.uniform(0.41, 0.49)])
    return pin.SE3(pin.exp3(rng.uniform(-0.15, 0.15, 3)), p)


def test_stewart_loads_closed_with_mobility_six(stewart):
    assert stewart.mobility == 6
    assert stewart.actuated == tuple(f"leg{i}_slide" for i in range(1, 7))
    assert np.max(np.abs(stewart.closure_residual(stewart.q_home))) < 1e-12
    home = stewart.forward(stewart.actuators_of(stewart.q_home))
    assert np.allclose(home.translation, [0, 0, 0.45], atol=1e-12)


def test_generic_ik_and_fk_agree_with_closed_form(stewart):
    rng = np.random.default_rng(3)
    for _ in range(10):
        T = random_pose(rng)
        q_act = stewart.inverse(T)
        assert np.max(np.abs(q_act - closed_form_leg_lengths(T))) <= 1e-12
        T_fk = stewart.forward(closed_form_leg_lengths(T))
        assert np.max(np.abs(T_fk.translation - T.translation)) <= 1e-12
        # orientation error expressed as the displacement it causes at the platform
        # joints (radius 0.15 m), the quantity the 1e-12 m closure tolerance controls
        angle = np.linalg.norm(pin.log3(T_fk.rotation.T @ T.rotation))
        assert angle * 0.15 <= 1e-12


def test_configuration_closes_loops_to_1e12(stewart, stewart_poses):
    for q in stewart.configurations(stewart_poses):
        assert np.max(np.abs(stewart.closure_residual(q))) <= 1e-12


def write_model(tmp_path: Path, urdf: str, sidecar: dict | None) -> Path:
    path = tmp_path / "m.urdf"
    path.write_text(urdf)
    if sidecar is not None:
        path.with_suffix(".yaml").write_text(yaml.safe_dump(sidecar))
    return path


def stewart_files():
    urdf = (STEWART / "stewart_6ups.urdf").read_text()
    sidecar = yaml.safe_load((STEWART / "stewart_6ups.yaml").read_text())
    return urdf, sidecar


def test_malformed_urdf(tmp_path):
    path = write_model(tmp_path, "<robot name='x'><link name='a'></robot>", None)
    with pytest.raises(pincal.ModelFileError, match="not well-formed XML"):
        load_mechanism(path)


def test_unknown_closure_frame_lists_valid_links(tmp_path):
    urdf, sidecar = stewart_files()
    sidecar["closed_loop"][2] = ["leg3_tip", "platform_p9"]
    with pytest.raises(
        pincal.UnknownNameError, match="frame 'platform_p9' not found.*'platform_p3'"
    ):
        load_mechanism(write_model(tmp_path, urdf, sidecar))


def test_unknown_actuated_joint_and_measured_frame(tmp_path, stewart):
    urdf, sidecar = stewart_files()
    sidecar["name_mot"][0] = "leg1_motor"
    with pytest.raises(pincal.UnknownNameError, match="actuated joint 'leg1_motor'.*'leg1_slide'"):
        load_mechanism(write_model(tmp_path, urdf, sidecar))
    with pytest.raises(pincal.UnknownNameError, match="frame 'tool' not found"):
        load_mechanism(STEWART, measured_frame="tool")


def test_non_closing_loop_reports_residual(tmp_path):
    urdf, sidecar = stewart_files()
    # two points of the same rigid platform can never coincide
    sidecar["closed_loop"].append(["platform_p1", "platform_p2"])
    sidecar["type"].append("3d")
    with pytest.raises(pincal.ClosureError, match=r"platform_p1 ↔ platform_p2 stays open.* mm"):
        load_mechanism(write_model(tmp_path, urdf, sidecar))


def test_mobility_mismatch_says_numbers(tmp_path):
    urdf, sidecar = stewart_files()
    sidecar["name_mot"] = sidecar["name_mot"][:5]
    with pytest.raises(pincal.MobilityError, match="5 actuated joints"):
        load_mechanism(write_model(tmp_path, urdf, sidecar))


def test_unreachable_target(stewart):
    far = pin.SE3(np.eye(3), np.array([0.0, 0.0, 2.0]))
    with pytest.raises(pincal.UnreachablePoseError, match="outside its limits|unreachable"):
        stewart.inverse(far)


def test_unknown_model_name_lists_bundled():
    with pytest.raises(pincal.UnknownNameError, match="stewart_6ups"):
        load_mechanism("no_such_model")


def test_input_files_untouched(stewart, stewart42, tmp_path):
    before = (STEWART / "stewart_6ups.urdf").read_bytes()
    stewart42.apply(stewart, np.full(42, 1e-4))
    assert (STEWART / "stewart_6ups.urdf").read_bytes() == before


def test_huge_axis_is_normalised_not_overflowed():
    from pincal.model import UrdfTree

    xml = (
        "<robot name='r'><link name='a'/><link name='b'/>"
        "<joint name='j' type='revolute'><parent link='a'/><child link='b'/>"
        "<axis xyz='1e300 1e300 0'/><limit lower='-1' upper='1' effort='1' velocity='1'/>"
        "</joint></robot>"
    )
    axis = UrdfTree(xml).joints["j"].axis
    assert np.allclose(axis, [2**-0.5, 2**-0.5, 0.0])

"""Tests of pincal.model.loading._dh: DH tables → URDF, DH error parameters, example-robot-data."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin
import pytest

from pincal.errors import (
    ModelFileError,
    UnknownNameError,
)
from pincal.model import (
    DHError,
    DHRow,
    dh_apply_errors,
    dh_errors_to_parameters,
    dh_fk,
    dh_layout,
    dh_preset,
    dh_urdf,
    example_robot_names,
    example_robot_urdf,
    parameters_to_dh_errors,
)

# ---------------------------------------------------------------- independent reference


def _rz(t):
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


def _rx(t):
    c, s = math.cos(t), math.sin(t)
    return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1.0]])


def _tz(d):
    T = np.eye(4)
    T[2, 3] = d
    return T


def _tx(a):
    T = np.eye(4)
    T[0, 3] = a
    return T


def reference_frames(rows, q, convention, errors=None, probe=None):
    """DH frames T_0i as elementary-matrix products (test-local, no library code)."""
    errors = errors or [DHError()] * len(rows)
    T = np.eye(4)
    frames = []
    k = 0
    for row, e in zip(rows, errors, strict=True):
        theta, d = row.theta_offset + e.dtheta, row.d + e.dd
        a, alpha = row.a + e.da, row.alpha + e.dalpha
        if row.joint_type == "revolute":
            theta += q[k]
            k += 1
        elif row.joint_type == "prismatic":
            d += q[k]
            k += 1
        if convention == "standard":
            step = _rz(theta) @ _tz(d) @ _tx(a) @ _rx(alpha)
        else:
            step = _rx(alpha) @ _tx(a) @ _rz(theta) @ _tz(d)
        T = T @ step
        frames.append(T.copy())
    if probe is not None:
        P = np.eye(4)
        P[:3, 3] = probe
        frames.append(T @ P)
    return frames


def random_table(rng, n=7, types=("revolute", "prismatic", "fixed")):
    rows = []
    for _ in range(n):
        rows.append(
            DHRow(
                a=rng.uniform(-0.5, 0.5),
                d=rng.uniform(-0.5, 0.5),
                alpha=rng.uniform(-math.pi, math.pi),
                theta_offset=rng.uniform(-math.pi, math.pi),
                joint_type=str(rng.choice(types)),
            )
        )
    return rows


def random_errors(rng, n, scale=1e-2):
    return [DHError(*rng.uniform(-scale, scale, 4)) for _ in range(n)]


def pin_frames(urdf, link_names, q_by_joint):
    """Poses (4x4) of the named links from Pinocchio at the given joint values."""
    model = pin.buildModelFromXML(urdf)
    data = model.createData()
    q = pin.neutral(model)
    for name, value in q_by_joint.items():
        q[model.joints[model.getJointId(name)].idx_q] = value
    pin.framesForwardKinematics(model, data, q)
    return [data.oMf[model.getFrameId(link)].homogeneous for link in link_names]


def joint_values(rows, layout, rng):
    q = rng.uniform(-2.0, 2.0, sum(r.joint_type != "fixed" for r in rows))
    movable = [
        nm.joint for nm, r in zip(layout.names, rows, strict=True) if r.joint_type != "fixed"
    ]
    return q, dict(zip(movable, q, strict=True))


# ---------------------------------------------------------------- DH → URDF exactness


@pytest.mark.parametrize("convention", ["standard", "modified"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_urdf_with_errors_matches_numpy_dh(convention, seed):
    rng = np.random.default_rng(seed)
    rows = random_table(rng)
    errors = random_errors(rng, len(rows))
    probe = rng.uniform(-0.2, 0.2, 3)
    erroneous = dh_apply_errors(rows, errors)
    urdf = dh_urdf(erroneous, "chain", convention=convention, probe=probe)
    layout = dh_layout(erroneous, convention, probe=True)
    links = [nm.link for nm in layout.names] + ["probe"]
    for _ in range(5):
        q, q_by_joint = joint_values(rows, layout, rng)
        expected = reference_frames(rows, q, convention, errors, probe)
        got = pin_frames(urdf, links, q_by_joint)
        for T_exp, T_got in zip(expected, got, strict=True):
            np.testing.assert_allclose(T_got, T_exp, rtol=0, atol=1e-12)
        # the library's own numpy FK agrees too
        np.testing.assert_allclose(
            dh_fk(rows, q, convention, errors, probe), expected[-1], rtol=0, atol=1e-12
        )


def test_fixed_row_and_neutral_configuration_are_the_dh_zero():
    rows = [DHRow(0.1, 0.2, math.pi / 2, 0.3), DHRow(0.0, 0.15, 0.0, 0.0, "fixed")]
    urdf = dh_urdf(rows, "two")
    (T,) = pin_frames(urdf, ["link2"], {})
    np.testing.assert_allclose(T, reference_frames(rows, [0.0], "standard")[-1], atol=1e-15)
    assert pin.buildModelFromXML(urdf).nq == 1


# ---------------------------------------------------------------- errors as origin twists


def _origin_se3(joint):
    origin = joint.find("origin")
    xyz = np.array([float(v) for v in origin.get("xyz", "0 0 0").split()])
    rpy = np.array([float(v) for v in origin.get("rpy", "0 0 0").split()])
    return pin.SE3(pin.rpy.rpyToMatrix(rpy), xyz)


def apply_twists_by_hand(urdf, values):
    """origin ← origin · exp6(v) for each '<joint>.<dof>' value; offset = twist along axis."""
    root = ET.fromstring(urdf)
    joints = {j.get("name"): j for j in root.iter("joint")}
    dof_index = {"tx": 0, "ty": 1, "tz": 2, "rx": 3, "ry": 4, "rz": 5}
    for name, value in values.items():
        jname, dof = name.split(".")
        joint = joints[jname]
        v = np.zeros(6)
        if dof == "offset":
            axis = np.array([float(x) for x in joint.find("axis").get("xyz").split()])
            if joint.get("type") == "revolute":
                v[3:] = value * axis
            else:
                v[:3] = value * axis
        else:
            v[dof_index[dof]] = value
        M = _origin_se3(joint) * pin.exp6(pin.Motion(v))
        origin = joint.find("origin")
        origin.set("xyz", " ".join(repr(float(x)) for x in M.translation))
        origin.set("rpy", " ".join(repr(float(x)) for x in pin.rpy.matrixToRpy(M.rotation)))
    return ET.tostring(root, encoding="unicode")


@pytest.mark.parametrize("convention", ["standard", "modified"])
@pytest.mark.parametrize("seed", [3, 4])
def test_dh_errors_are_single_dof_origin_twists(convention, seed):
    rng = np.random.default_rng(seed)
    rows = random_table(rng)
    errors = random_errors(rng, len(rows), scale=3e-2)
    probe = rng.uniform(-0.2, 0.2, 3)
    values = dh_errors_to_parameters(errors, rows, convention)
    assert len(values) == 4 * len(rows)
    twisted = apply_twists_by_hand(dh_urdf(rows, "c", convention, probe), values)
    erroneous = dh_urdf(dh_apply_errors(rows, errors), "c", convention, probe)
    layout = dh_layout(rows, convention, probe=True)
    links = [nm.link for nm in layout.names] + ["probe"]
    for _ in range(5):
        _, q_by_joint = joint_values(rows, layout, rng)
        for T_twisted, T_err in zip(
            pin_frames(twisted, links, q_by_joint),
            pin_frames(erroneous, links, q_by_joint),
            strict=True,
        ):
            np.testing.assert_allclose(T_twisted[:3, 3], T_err[:3, 3], rtol=0, atol=1e-9)
            np.testing.assert_allclose(T_twisted[:3, :3], T_err[:3, :3], rtol=0, atol=1e-9)
    # and the twist is not a no-op: the nominal probe differs by more than the errors' size
    nominal = pin_frames(dh_urdf(rows, "c", convention, probe), ["probe"], q_by_joint)[0]
    assert np.linalg.norm(nominal[:3, 3] - T_err[:3, 3]) > 1e-3


def test_parameter_mapping_round_trip_and_preset_names():
    rows = [
        DHRow(0.1, 0.2, 0.3, 0.0),
        DHRow(0.0, 0.1, -0.5, 0.2, "prismatic"),
        DHRow(0.0, 0.15, 0.0, 0.0, "fixed"),
    ]
    errors = [
        DHError(1e-3, 2e-3, 3e-3, 4e-3),
        DHError(-1e-3, -2e-3, -3e-3, -4e-3),
        DHError(dd=5e-4),
    ]
    values = dh_errors_to_parameters(errors, rows)
    assert values["joint1.offset"] == 4e-3  # revolute: Δθ is the encoder offset
    assert values["joint1.tz"] == 2e-3
    assert values["joint2.offset"] == -2e-3  # prismatic: Δd is the slide offset
    assert values["joint2.rz"] == -4e-3
    assert values["joint3.tz"] == 5e-4 and values["joint3.rz"] == 0.0
    assert values["joint1_ax.tx"] == 1e-3 and values["joint1_ax.rx"] == 3e-3
    assert parameters_to_dh_errors(values, rows) == errors
    preset = dh_preset(rows)
    names = [f"{e['joints']}.{d}" for e in preset for d in e["dofs"]]
    assert sorted(names) == sorted(values)
    only_theta = dh_preset(rows, quantities=["theta"], links=[0])
    assert only_theta == [{"joints": "joint1", "dofs": ["offset"]}]
    with pytest.raises(UnknownNameError, match=r"joint1\.offset"):
        parameters_to_dh_errors({"joint9.tz": 1.0}, rows)


def test_invalid_inputs_raise_pincal_errors():
    rows = [DHRow(0.1, 0.2, 0.3)]
    with pytest.raises(UnknownNameError, match="standard"):
        dh_urdf(rows, "x", convention="craig")
    with pytest.raises(ModelFileError, match="2 names"):
        dh_urdf(rows, "x", joint_names=["a", "b"])
    with pytest.raises(ModelFileError, match="duplicate"):
        dh_urdf(rows + rows, "x", joint_names=["j", "j"])
    with pytest.raises(ModelFileError, match="probe"):
        dh_urdf(rows, "x", probe=[1.0, 2.0])
    with pytest.raises(UnknownNameError):
        dh_urdf([DHRow(0, 0, 0, 0, "ball")], "x")


def test_visuals_are_cylinders_along_the_links():
    rows = [DHRow(0.3, 0.2, 0.0), DHRow(0.0, 0.0, 0.0, 0.0, "fixed")]
    root = ET.fromstring(dh_urdf(rows, "v", visual_radius=0.01))
    lengths = sorted(float(c.get("length")) for c in root.iter("cylinder"))
    assert lengths == pytest.approx([0.06, 0.2, 0.3])  # joint 1 marker, d1, a1
    assert not list(ET.fromstring(dh_urdf(rows, "v", visual_radius=None)).iter("visual"))


# ---------------------------------------------------------------- example-robot-data


@pytest.mark.parametrize(
    ("name", "frame", "parent"),
    [
        ("ur10", "tool0", "wrist_3_link"),
        ("ur5", "tool0", "wrist_3_link"),
        ("panda", "panda_hand", "panda_link8"),
    ],
)
def test_example_robot_urdf_resolves_and_loads(name, frame, parent):
    path = example_robot_urdf(name)
    assert path.is_file() and path.suffix == ".urdf"
    assert "example-robot-data" in str(path)
    model = pin.buildModelFromUrdf(str(path))
    assert model.existFrame(frame)
    # the natural measured frame hangs on a fixed joint
    root = ET.parse(path).getroot()
    (joint,) = [
        j
        for j in root.iter("joint")
        if j.find("child") is not None and j.find("child").get("link") == frame
    ]
    assert joint.get("type") == "fixed"
    assert joint.find("parent").get("link") == parent


def test_example_robot_names_and_unknown_name():
    names = example_robot_names()
    for expected in ("ur10", "ur5", "panda", "ur10_robot", "kinova"):
        assert expected in names
    assert "anymal" not in names  # ambiguous stem: only the qualified names
    assert "anymal_b_simple/anymal" in names
    # qualified names are accepted for every robot
    assert example_robot_urdf("ur/ur5_robot") == example_robot_urdf("ur5")
    # example-robot-data's loader names: `talos` is its reduced humanoid
    assert example_robot_urdf("talos") == example_robot_urdf("talos_reduced")
    assert example_robot_urdf("talos_arm").stem == "talos_left_arm"
    with pytest.raises(UnknownNameError, match=r"not_a_robot.*robots are: 'TwoDofs'") as info:
        example_robot_urdf("not_a_robot")
    assert info.value.kind == "robot" and info.value.valid == names
    assert isinstance(info.value, KeyError)


def test_probe_as_transform_with_rotation():
    rng = np.random.default_rng(7)
    rows = random_table(rng, n=3, types=("revolute",))
    T_probe = pin.SE3.Random().homogeneous
    layout = dh_layout(rows, probe=True)
    q, q_by_joint = joint_values(rows, layout, rng)
    (got,) = pin_frames(dh_urdf(rows, "p", probe=T_probe), ["probe"], q_by_joint)
    expected = reference_frames(rows, q, "standard")[-1] @ T_probe
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12)
    np.testing.assert_allclose(dh_fk(rows, q, probe=T_probe), expected, rtol=0, atol=1e-12)

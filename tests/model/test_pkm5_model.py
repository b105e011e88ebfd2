"""Self-consistency of models/pkm5 (seed 003) using Pinocchio directly.

The closure solver of pincal is not used here: a small Newton solve on the passive
joints (frame Jacobians from Pinocchio) closes the loops, and the results are compared
with an independent closed-form inverse kinematics of the paper's model (eq. 1-4):
T_v = O' + R·t_v (struts 1, 2) or O' + R_X(A)·t_v (struts 3, 4), S_v = s_v + H_v·e_z,
|T_v − S_v| = L_v.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml

MODEL_DIR = Path(__file__).resolve().parents[2] / "models" / "pkm5"
URDF = MODEL_DIR / "pkm5.urdf"
SIDECAR = MODEL_DIR / "pkm5.yaml"

# Geometry table of models/pkm5/README.md [m]
T_LOCAL = {1: (0.2, -0.25, -0.15), 2: (0.2, 0.25, -0.15), 3: (-0.2, -0.2, 0.0), 4: (-0.2, 0.2, 0.0)}
S_HOME = {1: (0.2, -0.8, 0.4), 2: (0.2, 0.8, 0.4), 3: (-0.2, -0.8, 0.5), 4: (-0.2, 0.8, 0.5)}
CENTRE_HOME = np.array([0.0, 0.0, 1.05])
Z_TOOL = 0.3
PASSIVE = [
    *("plat_y", "plat_z", "plat_a", "head_b"),
    *("strut1_ux", "strut1_uy", "strut2_ux", "strut2_uy", "strut3_rx", "strut4_rx"),
]
SLIDERS = ["slider1", "slider2", "slider3", "slider4"]


def rot_x(a: float) -> np.ndarray:
    return pin.rpy.rpyToMatrix(a, 0.0, 0.0)


def rot_y(b: float) -> np.ndarray:
    return pin.rpy.rpyToMatrix(0.0, b, 0.0)


def strut_lengths() -> np.ndarray:
    return np.array(
        [
            np.linalg.norm(CENTRE_HOME + np.array(T_LOCAL[v]) - np.array(S_HOME[v]))
            for v in (1, 2, 3, 4)
        ]
    )


def closed_form_ik(y: float, z: float, a: float, b: float) -> np.ndarray:
    """Slider displacements H_v [m] for platform centre (0, y, z) and rotations A, B [rad]."""
    centre = np.array([0.0, y, z])
    lengths = strut_lengths()
    h = np.empty(4)
    for i, v in enumerate((1, 2, 3, 4)):
        rot = rot_x(a) @ rot_y(b) if v < 3 else rot_x(a)
        t_world = centre + rot @ np.array(T_LOCAL[v])
        d = t_world - np.array(S_HOME[v])
        # slider hinge above (smaller z than) the platform hinge
        z_s = t_world[2] - np.sqrt(lengths[i] ** 2 - d[0] ** 2 - d[1] ** 2)
        h[i] = z_s - S_HOME[v][2]
    return h


def region_poses(sidecar: dict, n: int = 3) -> list[tuple[float, float, float, float]]:
    poses = []
    for reg in sidecar["measurement_regions"]:
        _, y, z = reg["centre"]
        for ang in np.linspace(*reg["range"], n):
            poses.append((y, z, ang, 0.0) if reg["axis"] == "x" else (y, z, 0.0, ang))
    return poses


class Loops:
    """Closure residuals of the sidecar and a Newton solve over the passive joints."""

    def __init__(self, model: pin.Model, sidecar: dict):
        self.model, self.data = model, model.createData()
        self.pairs = [
            (model.getFrameId(a, pin.BODY), model.getFrameId(b, pin.BODY), kind)
            for (a, b), kind in zip(sidecar["closed_loop"], sidecar["type"], strict=True)
        ]
        self.iq = {n: model.joints[model.getJointId(n)].idx_q for n in PASSIVE + SLIDERS}
        self.passive = [self.iq[n] for n in PASSIVE]

    def residual_and_jacobian(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        m, d = self.model, self.data
        pin.computeJointJacobians(m, d, q)
        pin.updateFramePlacements(m, d)
        rows, jac = [], []
        for fa, fb, kind in self.pairs:
            gap = d.oMf[fb].translation - d.oMf[fa].translation
            j = (
                pin.getFrameJacobian(m, d, fb, pin.LOCAL_WORLD_ALIGNED)[:3]
                - pin.getFrameJacobian(m, d, fa, pin.LOCAL_WORLD_ALIGNED)[:3]
            )
            # [y, z] in the strut frame: that frame only turns about x, so its y-z plane is
            # the world y-z plane and the world y, z gap has the same zero set.
            sel = [0, 1, 2] if kind == "3d" else [1, 2]
            rows.append(gap[sel])
            jac.append(j[sel])
        return np.concatenate(rows), np.vstack(jac)

    def solve(self, q: np.ndarray, tol: float = 1e-13) -> np.ndarray:
        q = q.copy()
        for _ in range(30):
            r, j = self.residual_and_jacobian(q)
            if np.linalg.norm(r) < tol:
                return q
            q[self.passive] -= np.linalg.lstsq(j[:, self.passive], r, rcond=None)[0]
        raise AssertionError(f"loops did not close: residual {np.linalg.norm(r):.3e}")

    def configuration(self, h: np.ndarray, guess: np.ndarray | None = None) -> np.ndarray:
        q = pin.neutral(self.model) if guess is None else guess.copy()
        for name, value in zip(SLIDERS, h, strict=True):
            q[self.iq[name]] = value
        return self.solve(q)


@pytest.fixture(scope="module")
def sidecar() -> dict:
    return yaml.safe_load(SIDECAR.read_text())


@pytest.fixture(scope="module")
def model() -> pin.Model:
    return pin.buildModelFromUrdf(str(URDF))


def test_urdf_loads_with_expected_structure(model, sidecar):
    assert model.nq == model.nv == 14
    assert sorted(model.names[1:]) == sorted(PASSIVE + SLIDERS)
    for name in SLIDERS:
        assert model.joints[model.getJointId(name)].shortname() == "JointModelPZ"
    for pair in sidecar["closed_loop"]:
        for frame in pair:
            assert model.existFrame(frame, pin.BODY), frame
    assert model.existFrame(sidecar["measured_frame"], pin.BODY)
    assert sidecar["name_mot"] == SLIDERS
    geom = pin.buildGeomFromUrdf(model, str(URDF), pin.GeometryType.VISUAL)
    assert geom.ngeoms >= 20


def test_hinges24_are_the_fixed_joint_origins_of_the_geometry_table(sidecar):
    root = ET.parse(URDF).getroot()
    joints = {j.get("name"): j for j in root.iter("joint")}
    entries = sidecar["presets"]["hinges24"]
    names = [f"{e['joints']}.{dof}" for e in entries for dof in e["dofs"]]
    assert len(names) == len(set(names)) == 24
    for e in entries:
        joint = joints[e["joints"]]
        assert joint.get("type") == "fixed"
        origin = joint.find("origin")
        assert np.allclose([float(x) for x in origin.get("rpy").split()], 0.0)
        v = int(e["joints"][1])
        table = T_LOCAL[v] if e["joints"][0] == "T" else S_HOME[v]
        np.testing.assert_allclose([float(x) for x in origin.get("xyz").split()], table)
    ident = sidecar["presets"]["identifiable20"]
    ident_names = {f"{e['joints']}.{dof}" for e in ident for dof in e["dofs"]}
    assert set(names) - ident_names == {"T3.tx", "T4.tx", "S3.tx", "S4.tx"}


def test_home_configuration_closes_all_loops(model, sidecar):
    loops = Loops(model, sidecar)
    q_home = pin.neutral(model)
    for name, value in sidecar["home"].items():
        q_home[loops.iq[name]] = value
    r, _ = loops.residual_and_jacobian(q_home)
    assert np.max(np.abs(r)) < 1e-12
    tip = loops.data.oMf[model.getFrameId("tool_tip", pin.BODY)]
    np.testing.assert_allclose(tip.translation, CENTRE_HOME + np.array([0, 0, Z_TOOL]), atol=1e-12)
    np.testing.assert_allclose(closed_form_ik(0.0, 1.05, 0.0, 0.0), 0.0, atol=1e-12)


def test_forward_kinematics_matches_closed_form_ik_over_the_18_regions(model, sidecar):
    loops = Loops(model, sidecar)
    tip_id = model.getFrameId("tool_tip", pin.BODY)
    q = None
    for y, z, a, b in region_poses(sidecar):
        h = closed_form_ik(y, z, a, b)
        lo, hi = zip(*(sidecar["workspace"]["joints"][s] for s in SLIDERS), strict=True)
        assert np.all(h >= lo) and np.all(h <= hi)
        q = loops.configuration(h, q)  # warm start along the sequence
        got = [q[loops.iq[n]] for n in ("plat_y", "plat_z", "plat_a", "head_b")]
        np.testing.assert_allclose(got, [y, z - 1.05, a, b], atol=1e-10)
        tip = loops.data.oMf[tip_id]
        rot = rot_x(a) @ rot_y(b)
        np.testing.assert_allclose(tip.rotation, rot, atol=1e-10)
        np.testing.assert_allclose(tip.translation, [0, y, z] + rot @ [0, 0, Z_TOOL], atol=1e-10)


def _perturbed_model(joint_name: str, axis: int, delta: float) -> pin.Model:
    root = ET.parse(URDF).getroot()
    for joint in root.iter("joint"):
        if joint.get("name") == joint_name:
            origin = joint.find("origin")
            xyz = [float(x) for x in origin.get("xyz").split()]
            xyz[axis] += delta
            origin.set("xyz", " ".join(repr(x) for x in xyz))
    return pin.buildModelFromXML(ET.tostring(root, encoding="unicode"))


def test_hinge_x_of_struts_3_and_4_are_the_only_unidentifiable_coordinates(model, sidecar):
    """Central differences of the measured [y, z, rx, ry] w.r.t. the 24 hinge coordinates."""
    poses = region_poses(sidecar, n=2)
    loops = Loops(model, sidecar)
    tip_id = model.getFrameId("tool_tip", pin.BODY)
    nominal_q, nominal_tip, actuation = [], [], []
    q = None
    for pose in poses:
        h = closed_form_ik(*pose)
        q = loops.configuration(h, q)
        nominal_q.append(q)
        nominal_tip.append(loops.data.oMf[tip_id].copy())
        actuation.append(h)

    def measured(m: pin.Model) -> np.ndarray:
        lp = Loops(m, sidecar)
        out = []
        for q0, h, tip0 in zip(nominal_q, actuation, nominal_tip, strict=True):
            lp.configuration(h, q0)
            tip = lp.data.oMf[m.getFrameId("tool_tip", pin.BODY)]
            rvec = pin.log3(tip0.rotation.T @ tip.rotation)
            out.append([tip.translation[1], tip.translation[2], rvec[0], rvec[1]])
        return np.asarray(out).ravel()

    step = 1e-6
    names, cols = [], []
    for e in sidecar["presets"]["hinges24"]:
        for axis, dof in enumerate(("tx", "ty", "tz")):
            plus = measured(_perturbed_model(e["joints"], axis, step))
            minus = measured(_perturbed_model(e["joints"], axis, -step))
            names.append(f"{e['joints']}.{dof}")
            cols.append((plus - minus) / (2 * step))
    jac = np.column_stack(cols)
    norms = np.linalg.norm(jac, axis=0)
    dead = {n for n, c in zip(names, norms, strict=True) if c < 1e-6}
    assert dead == {"T3.tx", "T4.tx", "S3.tx", "S4.tx"}
    assert np.min(norms[[n not in dead for n in names]]) > 1e-2
    sv = np.linalg.svd(jac, compute_uv=False)
    assert np.sum(sv > 1e-6 * sv[0]) == 20


def test_workspace_pose_box_is_reachable_within_the_slider_ranges(sidecar):
    box = sidecar["workspace"]["pose"]
    lo, hi = zip(*(sidecar["workspace"]["joints"][s] for s in SLIDERS), strict=True)
    grid = [np.linspace(*box[k], 3) for k in ("y", "z", "rx", "ry")]
    for y_tip, z_tip, rx, ry in np.array(np.meshgrid(*grid)).reshape(4, -1).T:
        rot = pin.exp3(np.array([rx, ry, 0.0]))
        # nearest platform orientation R_X(A)·R_Y(B) (the platform has no rotation about Z)
        b = np.arcsin(rot[0, 2])
        a = np.arctan2(-rot[1, 2], rot[2, 2])
        centre = np.array([0.0, y_tip, z_tip]) - rot_x(a) @ rot_y(b) @ np.array([0, 0, Z_TOOL])
        h = closed_form_ik(centre[1], centre[2], a, b)
        assert np.all(np.isfinite(h))
        assert np.all(h >= lo) and np.all(h <= hi)

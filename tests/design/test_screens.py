"""Screens for poses a real machine can execute (issue 37, item 3).

UR5 (the issue's case: folded and stretched elbows), the Stewart platform without and
with collision geometry, and the singularity measure against Pinocchio's analytic
Jacobian.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from pincal.design import (
    Box,
    CollisionChecker,
    DesignScaling,
    ScreenSettings,
    actuator_sigma_min,
    candidate_set,
    screen_candidates,
    select_poses,
)
from pincal.errors import OptionValueError
from pincal.model import Mechanism, actuator_jacobians, load_mechanism, parameters

ELBOW = 2  # column of elbow_joint among the UR5's actuators


@pytest.fixture(scope="module")
def ur5() -> Mechanism:
    return load_mechanism("ur5")


@pytest.fixture(scope="module")
def ur5_candidates(ur5):
    return candidate_set(ur5, parameters(ur5, "full"), "random:300", rng=0)


def _srdf_geometry(mech: Mechanism) -> tuple[pin.GeometryModel, pin.GeometryData]:
    """The UR5's collision model with the vendor's SRDF pair list (not pincal's rule)."""
    src = Path(mech.source).resolve()
    share = next(p for p in src.parents if p.name == "share")
    geom = pin.buildGeomFromUrdfString(
        mech.model, mech.urdf_xml, pin.COLLISION, package_dirs=[str(share)]
    )
    geom.addAllCollisionPairs()
    pin.removeCollisionPairs(mech.model, geom, str(src.parents[1] / "srdf" / "ur5.srdf"))
    return geom, pin.GeometryData(geom)


def test_ur5_folded_elbow_collides_and_home_does_not(ur5):
    checker = CollisionChecker(ur5)
    assert checker.available and checker.n_pairs > 0
    assert checker.collisions(ur5.q_home) == (False, False)
    folded = np.array([1.365, -0.097, 3.138, 1.734, 2.077, -1.511])  # the issue's pose
    assert checker.collisions(folded)[0]
    names = {frozenset(p) for p in checker.names(folded)}
    assert frozenset({"upper_arm_link_0", "wrist_1_link_0"}) in names


def test_ur5_screens_remove_the_issues_poses(ur5, ur5_candidates):
    cands = ur5_candidates
    elbow = cands.q_act[:, ELBOW]
    issue = [np.argmin(np.abs(elbow - v)) for v in (3.138, -3.046, 0.0056)]
    assert np.allclose(elbow[issue], [3.138, -3.046, 0.0056], atol=5e-4)  # in the set
    kept, report = screen_candidates(ur5, cands)
    assert not report.kept[issue].any()
    assert report.removed["self-collision"] > 0 and report.removed["singularity margin"] > 0
    assert sum(report.removed.values()) == len(cands) - len(kept)
    assert "self-collision" in kept.summary()
    # every kept pose is free of collision under the vendor's SRDF pair list
    geom, gdata = _srdf_geometry(ur5)
    data = ur5.model.createData()
    for q in kept.q_act:
        assert not pin.computeCollisions(ur5.model, data, geom, gdata, q, True), q
    # and the removed ones include poses that the SRDF list sees colliding
    removed = cands.q_act[~report.kept]
    hits = sum(pin.computeCollisions(ur5.model, data, geom, gdata, q, True) for q in removed)
    assert hits >= report.removed["self-collision"] // 2


def test_sigma_min_matches_the_analytic_jacobian(ur5, ur5_candidates):
    rows = ur5_candidates.q_act[:20]
    sigma, L = actuator_sigma_min(ur5, rows, length=0.4)
    assert L == 0.4
    fid = ur5.frame_id(ur5.measured_frame)
    data = ur5.model.createData()
    for q, s in zip(rows, sigma, strict=True):
        J = pin.computeFrameJacobian(ur5.model, data, q, fid, pin.LOCAL).copy()
        J[:3] /= 0.4  # position rows in units of L (an orthogonal change of frame is free)
        assert s == pytest.approx(np.linalg.svd(J, compute_uv=False)[-1], rel=1e-5, abs=1e-8)
    stretched = ur5.q_home.copy()
    stretched[ELBOW] = 0.0
    assert actuator_sigma_min(ur5, stretched[None], length=0.4)[0][0] < 1e-6


def test_closed_chain_actuator_jacobian_matches_finite_differences(stewart, stewart_poses):
    """Position rows in world axes, rotation rows in the measured frame: the components
    of a measurement residual (a rotating frame's local axes would mix world x and y)."""
    G = actuator_jacobians(stewart, stewart_poses[:4])
    h = 1e-6
    for row, g in zip(stewart_poses[:4], G, strict=True):
        ref = stewart.forward(row)
        fd = np.empty_like(g)
        for k in range(len(row)):
            step = np.eye(len(row))[k] * h
            plus, minus = stewart.forward(row + step), stewart.forward(row - step)
            fd[:3, k] = (plus.translation - minus.translation) / (2 * h)
            fd[3:, k] = (
                pin.log3(ref.rotation.T @ plus.rotation) - pin.log3(ref.rotation.T @ minus.rotation)
            ) / (2 * h)
        assert np.allclose(g, fd, atol=1e-6 * np.abs(fd).max())


def test_stewart_without_collision_geometry_keeps_its_design(stewart, stewart42):
    cands = candidate_set(stewart, stewart42, "random:200", rng=0)
    kept, report = screen_candidates(stewart, cands)
    assert any("no <collision> geometry" in n for n in report.notes)
    assert "self-collision" not in report.removed
    scaling = DesignScaling(rows="noise", position_std=1e-5, orientation_std=2e-5)
    before = select_poses(cands, 18, "O1", scaling, rng=0, restarts=3).selection.value
    after = select_poses(kept, 18, "O1", scaling, rng=0, restarts=3).selection.value
    assert after >= 0.95 * before


def _stewart_with_collisions() -> Mechanism:
    """The bundled Stewart with its visual shapes declared as collision geometry too."""
    root = Path(__file__).resolve().parents[2] / "models" / "stewart_6ups"
    xml = (root / "stewart_6ups.urdf").read_text()
    xml = xml.replace('<material name="grey"/>', "").replace('<material name="blue"/>', "")
    xml = xml.replace('<material name="orange"/>', "")
    xml = xml.replace("<visual>", "<collision>").replace("</visual>", "</collision>")
    import yaml

    sidecar = yaml.safe_load((root / "stewart_6ups.yaml").read_text())
    return Mechanism(xml, sidecar, name="stewart_collisions")


def test_parallel_machine_with_collision_geometry_and_an_obstacle(stewart42):
    mech = _stewart_with_collisions()
    cands = candidate_set(mech, parameters(mech, "stewart42"), "random:200", rng=1)
    z_ceiling = 0.50  # a box whose underside is 50 mm above the platform at home (0.45)
    ceiling = Box((0.0, 0.0, z_ceiling + 0.05), (2.0, 2.0, 0.1))
    checker = CollisionChecker(mech, (ceiling,))
    assert checker.available and checker.ignored_at_home[0] > 0  # joints touch at home
    assert checker.collisions(mech.q_home) == (False, False)
    settings = ScreenSettings(joint_margin=0.0, singular_margin=0.0, obstacles=(ceiling,))
    _, report = screen_candidates(mech, cands, settings)
    assert report.removed["obstacle collision"] > 0
    # independent bounds: the platform disc (radius 180 mm, 15 mm thick) reaching the
    # ceiling collides; no part rises more than 30 mm above the disc's plane within its
    # radius (ball joints 14 mm, strut ends), so below that the ceiling is not touched
    z = cands.positions[:, 2]
    tilt = np.arccos(np.clip(cands.rotations[:, 2, 2], -1, 1))
    disc_top = z + 0.18 * np.sin(tilt) + 0.0075 * np.cos(tilt)
    assert (disc_top >= z_ceiling).sum() > 5 and not report.kept[disc_top >= z_ceiling].any()
    clear = np.flatnonzero(z + 0.18 * np.sin(tilt) + 0.03 < z_ceiling)
    assert clear.size
    for i in clear:
        assert not checker.collisions(mech.configuration(cands.q_act[i]))[1]


def test_settings_refuse_bad_margins():
    with pytest.raises(OptionValueError, match="joint margin"):
        ScreenSettings(joint_margin=0.6)
    with pytest.raises(OptionValueError, match="singularity margin"):
        ScreenSettings(singular_margin=-1)


def test_a_measured_point_the_actuators_do_not_move_keeps_a_finite_margin():
    """An MJCF four-bar loaded without a sidecar measures its rocker body at the rocker's
    pivot: the position rows of G are zero. σ_min is then the rotation's (L = 1 m), not
    NaN — with NaN every candidate was rejected as singular and `poses` refused."""
    fourbar = load_mechanism(Path(__file__).parents[1] / "model" / "mjcf" / "fourbar.xml")
    cands = candidate_set(fourbar, parameters(fourbar, "full"), "random:50", rng=0)
    sigma, L = actuator_sigma_min(fourbar, cands.q_act)
    assert L == 1.0
    assert np.all(np.isfinite(sigma)) and np.all(sigma > 0)
    _, report = screen_candidates(fourbar, cands)
    assert report.removed["singularity margin"] < len(cands) // 2

"""The point-closure Jacobian path on a machine it was not designed around.

In the bundled point-closure machines no parameterised joint moves both frames of a
closure. Here the planar 3-RPR of ``tests/model/machines/rpr3`` is remounted: its legs
and its floating platform hang from a ``mount`` fixed joint, whose six parameters move
both frames of every closure (the ``(s_b − s_a) V + W × (s_b p_b − s_a p_a)`` terms
with s_a = s_b), and a measured-frame offset turned from the platform.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pincal
from pincal.sensitivity import pose_sensitivity
from pincal.sensitivity._jacobian import jacobian_plan
from pincal.sensitivity.batch._batch_jacobian import sensitivities_batch

RPR3 = Path(__file__).parents[1] / "model" / "machines" / "rpr3"


@pytest.fixture(scope="module")
def mounted(tmp_path_factory) -> pincal.Mechanism:
    folder = tmp_path_factory.mktemp("mounted_rpr3")
    urdf = (RPR3 / "rpr3.urdf").read_text()
    urdf = urdf.replace('<parent link="world"/>', '<parent link="frame"/>')
    urdf = urdf.replace(
        '<link name="world"/>',
        '<link name="world"/><link name="frame"/><link name="tool"/>\n'
        '  <joint name="mount" type="fixed"><parent link="world"/><child link="frame"/>\n'
        '    <origin xyz="0.02 -0.01 0.1" rpy="0.01 -0.02 0.3"/></joint>\n'
        '  <joint name="tool_joint" type="fixed"><parent link="end_effector"/>'
        '<child link="tool"/>\n'
        '    <origin xyz="0.03 0.01 0.05" rpy="0.2 0.1 -0.4"/></joint>',
    )
    (folder / "mounted.urdf").write_text(urdf)
    sidecar = (RPR3 / "rpr3.yaml").read_text() + "\nmeasured_frame: tool\n"
    (folder / "mounted.yaml").write_text(sidecar)
    return pincal.load_mechanism(folder / "mounted.urdf")


def test_mount_moves_both_frames_of_every_closure(mounted):
    params = pincal.parameters(mounted, "full")
    plan = jacobian_plan(mounted, params)
    for c in mounted.closures:
        assert "mount" in plan.moves[c.frame_a] and "mount" in plan.moves[c.frame_b]
    assert all(c.is_point for c in mounted.closures)


@pytest.mark.parametrize("at_values", [False, True])
def test_point_path_matches_pose_sensitivity(mounted, at_values):
    params = pincal.parameters(mounted, "full")
    rng = np.random.default_rng(3)
    values = 1e-3 * rng.standard_normal(len(params)) if at_values else np.zeros(len(params))
    at = params.apply(mounted, values) if at_values else mounted
    rows = pincal.sample_actuators(at, 8, rng)
    qs, bk = at.configurations_batch(rows)
    batch = sensitivities_batch(at, params, qs, bk, values)
    scale = max(1.0, float(np.max(np.abs(batch.jacobian))))
    mount_cols = [k for k, p in enumerate(params.parameters) if p.joint == "mount"]
    assert np.max(np.abs(batch.jacobian[:, :, mount_cols])) > 1e-3  # the mount is seen
    for i, q in enumerate(qs):
        ref = pose_sensitivity(at, params, q, values)
        np.testing.assert_allclose(batch.jacobian[i], ref.jacobian, rtol=0, atol=1e-12 * scale)


def test_point_path_matches_central_differences(mounted):
    params = pincal.parameters(mounted, "full")
    rows = pincal.sample_actuators(mounted, 3, np.random.default_rng(5))
    qs, bk = mounted.configurations_batch(rows)
    J = sensitivities_batch(mounted, params, qs, bk).jacobian
    h = 1e-6
    fd = np.zeros_like(J)
    for k in range(len(params)):
        step = np.zeros(len(params))
        step[k] = h
        poses = []
        for sgn in (1.0, -1.0):
            m = params.apply(mounted, sgn * step)
            poses.append([m.forward(r) for r in rows])
        for i in range(len(rows)):
            plus, minus = poses[0][i], poses[1][i]
            fd[i, :3, k] = (plus.translation - minus.translation) / (2 * h)
            fd[i, 3:, k] = pin.log3(minus.rotation.T @ plus.rotation) / (2 * h)
    assert np.max(np.abs(J - fd)) <= 1e-6 * np.max(np.abs(J))

"""The body-wise batched Jacobian of serial chains against pose_sensitivity and finite differences.

The chain below has what the body-wise formation must get right: an origin on the world
body (``mount``), an unaligned revolute, a prismatic joint, a fixed joint between two
moving joints (``mid``, merged by Pinocchio into the next joint's placement), a measured
frame offset and turned from its joint (``tool_joint``) and a side branch that does not
move the measured frame (``side``).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import pincal
from pincal.model import Mechanism
from pincal.sensitivity import pose_sensitivity
from pincal.sensitivity._jacobian import jacobian_plan
from pincal.sensitivity.batch import _batch_serial
from pincal.sensitivity.batch._batch_jacobian import sensitivities_batch

LIMIT = '<limit lower="-2" upper="2" effort="1" velocity="1"/>'
CHAIN_URDF = f"""<?xml version="1.0"?>
<robot name="chain">
  <link name="world"/>
  <joint name="mount" type="fixed"><parent link="world"/><child link="base"/>
    <origin xyz="0.1 -0.2 0.05" rpy="0.1 -0.2 0.3"/></joint>
  <link name="base"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.3" rpy="0 0 0"/><axis xyz="0 0.6 0.8"/>{LIMIT}</joint>
  <link name="l1"/>
  <joint name="side" type="fixed"><parent link="l1"/><child link="camera"/>
    <origin xyz="0.05 0.05 0" rpy="0 0 1"/></joint>
  <link name="camera"/>
  <joint name="j2" type="prismatic"><parent link="l1"/><child link="l2"/>
    <origin xyz="0.4 0 0" rpy="0 0.2 0"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="0.3" effort="1" velocity="1"/></joint>
  <link name="l2"/>
  <joint name="mid" type="fixed"><parent link="l2"/><child link="l2b"/>
    <origin xyz="0.1 0.02 -0.03" rpy="0.3 0 -0.4"/></joint>
  <link name="l2b"/>
  <joint name="j3" type="revolute"><parent link="l2b"/><child link="l3"/>
    <origin xyz="0.25 0 0.1" rpy="0 0 0.5"/><axis xyz="0 1 0"/>{LIMIT}</joint>
  <link name="l3"/>
  <joint name="tool_joint" type="fixed"><parent link="l3"/><child link="tool"/>
    <origin xyz="0.05 0.02 0.12" rpy="-0.4 0.3 0.2"/></joint>
  <link name="tool"/>
</robot>
"""
SIDECAR = {"name_mot": ["j1", "j2", "j3"], "measured_frame": "tool"}
# joint j3's columns are not contiguous (index path); j2.offset: a prismatic offset
SUBSET = ["j3.tx", "j1.rz", "j3.rz", "j2.offset", "mid.ry", "side.tx", "tool_joint.tz"]


@pytest.fixture(scope="module")
def chain():
    return Mechanism(CHAIN_URDF, SIDECAR)


def _rows(mech, n, seed):
    return pincal.sample_actuators(mech, n, np.random.default_rng(seed))


def _batch(mech, params, values, rows):
    at = params.apply(mech, values)
    qs, bk = at.configurations_batch(rows)
    return at, qs, sensitivities_batch(at, params, qs, bk, values)


def _assert_matches_pose_sensitivity(at, params, values, qs, batch):
    scale = max(1.0, float(np.max(np.abs(batch.jacobian))))
    for i, q in enumerate(qs):
        ref = pose_sensitivity(at, params, q, values)
        np.testing.assert_allclose(batch.positions[i], ref.position, rtol=0, atol=1e-12)
        np.testing.assert_allclose(batch.rotations[i], ref.rotation, rtol=0, atol=1e-12)
        np.testing.assert_allclose(batch.jacobian[i], ref.jacobian, rtol=0, atol=1e-12 * scale)


@pytest.mark.parametrize("preset", ["full", "subset", "two bodies"])
@pytest.mark.parametrize("at_zero", [True, False])
def test_chain_matches_pose_sensitivity(chain, preset, at_zero):
    entries = {"full": "full", "subset": SUBSET, "two bodies": ["mount.tx", "j3.ty", "j3.rx"]}
    params = pincal.parameters(chain, entries[preset])
    rng = np.random.default_rng(11)
    values = np.zeros(len(params)) if at_zero else 1e-3 * rng.standard_normal(len(params))
    at, qs, batch = _batch(chain, params, values, _rows(chain, 9, 12))
    _assert_matches_pose_sensitivity(at, params, values, qs, batch)
    assert batch.jacobian.flags.c_contiguous
    assert not batch.breaks_closure.any()


def test_chain_layout_covers_the_index_paths(chain):
    """The subset has non-contiguous columns; 'two bodies' non-consecutive bodies."""
    values = np.zeros(len(SUBSET))
    params = pincal.parameters(chain, SUBSET)
    lay = _batch_serial._layout(chain, params, values, jacobian_plan(chain, params))
    assert any(isinstance(cols, np.ndarray) for _, cols, _ in lay.runs)
    two = pincal.parameters(chain, ["mount.tx", "j3.ty"])
    lay2 = _batch_serial._layout(chain, two, np.zeros(2), jacobian_plan(chain, two))
    assert isinstance(lay2.bodies, np.ndarray)
    assert lay2.bodies.tolist() == [0, 2]  # world (mount) and j2's body (j3's origin)


def _measured(mech, q, R_ref):
    """[p; log3(R_refᵀ R)] of the measured frame at configuration q."""
    T = mech.frame_placement(q)
    return np.concatenate([T.translation, pin.log3(R_ref.T @ T.rotation)])


@pytest.mark.parametrize("at_zero", [True, False])
def test_chain_matches_central_differences(chain, at_zero):
    params = pincal.parameters(chain, "full")
    rng = np.random.default_rng(13)
    values = np.zeros(len(params)) if at_zero else 5e-4 * rng.standard_normal(len(params))
    _, qs, batch = _batch(chain, params, values, _rows(chain, 3, 14))
    h = 1e-6
    for i, q in enumerate(qs):
        R_ref = batch.rotations[i]
        fd = np.empty((6, len(params)))
        for k in range(len(params)):
            e = np.zeros(len(params))
            e[k] = h
            plus = _measured(params.apply(chain, values + e), q, R_ref)
            minus = _measured(params.apply(chain, values - e), q, R_ref)
            fd[:, k] = (plus - minus) / (2 * h)
        assert np.max(np.abs(batch.jacobian[i] - fd)) <= 1e-8
    # the side branch does not move the tool; every other joint does
    side = [k for k, p in enumerate(params.parameters) if p.joint == "side"]
    assert not batch.jacobian[:, :, side].any()
    assert np.all(np.abs(np.delete(batch.jacobian, side, axis=2)).max(axis=(0, 1)) > 0)


def test_chain_blocks_and_out(chain):
    """Many poses (several cache blocks, a partial last one) and the ``out`` argument."""
    params = pincal.parameters(chain, "full")
    values = 1e-3 * np.random.default_rng(15).standard_normal(len(params))
    at = params.apply(chain, values)
    lay = _batch_serial._layout(at, params, values, jacobian_plan(at, params))
    block = max(32, _batch_serial.BLOCK // lay.size)
    qs, bk = at.configurations_batch(_rows(at, 2 * block + 7, 16))
    batch = sensitivities_batch(at, params, qs, bk, values)
    picks = [0, block - 1, block, 2 * block - 1, 2 * block, 2 * block + 6]
    fields = ("q", "positions", "rotations", "jacobian")
    sub = type(batch)(*(getattr(batch, f)[picks] for f in fields), batch.breaks_closure)
    _assert_matches_pose_sensitivity(at, params, values, qs[picks], sub)
    out = np.zeros((len(qs), 6, len(params)))
    Rm, pm, J = _batch_serial.serial_path(at, params, bk, values, jacobian_plan(at, params), out)
    assert J is out
    np.testing.assert_array_equal(out, batch.jacobian)
    np.testing.assert_array_equal(pm, batch.positions)
    np.testing.assert_array_equal(Rm, batch.rotations)


def test_chain_without_moving_parameters(chain):
    params = pincal.parameters(chain, ["side.tx", "side.rz"])
    at, qs, batch = _batch(chain, params, np.zeros(2), _rows(chain, 4, 17))
    assert not batch.jacobian.any()
    _assert_matches_pose_sensitivity(at, params, np.zeros(2), qs, batch)


@pytest.mark.parametrize("preset", ["chain", "base_tool", "full"])
def test_serial_arm_presets_match_pose_sensitivity(preset):
    from pincal.model import serial_mechanism

    ur = serial_mechanism("ur10", "tool0")
    params = pincal.parameters(ur, preset)
    values = 1e-3 * np.random.default_rng(18).standard_normal(len(params))
    at, qs, batch = _batch(ur, params, values, _rows(ur, 5, 19))
    _assert_matches_pose_sensitivity(at, params, values, qs, batch)


def test_scratch_is_per_thread_and_reshaped(chain):
    """The per-thread scratch maps: other shapes in between and concurrent threads."""
    from concurrent.futures import ThreadPoolExecutor

    ur = pincal.load_mechanism("ur10")
    jobs = [(chain, pincal.parameters(chain, "full")), (ur, pincal.parameters(ur, "full"))]
    data = []
    for mech, params in jobs:
        qs, bk = mech.configurations_batch(_rows(mech, 300, 20))
        data.append((mech, params, qs, bk))

    def run(i):
        mech, params, qs, bk = data[i % 2]
        return sensitivities_batch(mech, params, qs, bk).jacobian

    first = [run(0), run(1)]
    np.testing.assert_array_equal(run(0), first[0])  # after the other shape
    with ThreadPoolExecutor(4) as pool:
        for i, J in enumerate(pool.map(run, range(16))):
            np.testing.assert_array_equal(J, first[i % 2])

"""The ``flush`` kind: a face pressed flush against an unknown plane (a humanoid at a table).

TALOS stands on its left sole (the tree re-rooted there) and presses a palm frame on its
left wrist flat on a table whose placement is unknown. The truth is Pinocchio's model of
the URDF as shipped, every joint placement displaced; the touching configurations are
solved on that model alone (``reroot_sim.flush_poses``), none of pincal's model.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from pincal.errors import MeasurementError
from pincal.identification import InstrumentProblem, identify_instruments
from pincal.measure import FlushContact, artefact_class
from pincal.measure._flush_contact import flush_residuals
from pincal.model import (
    MOVABLE_TYPES,
    UrdfTree,
    chain_joints,
    parameters,
    resolve_named,
    sample_actuators,
    serial_mechanism,
)
from tests.identification.reroot_sim import flush_poses, perturbed_model

ROOT, LINK = "left_sole_link", "arm_left_7_link"
T_FACE = pin.SE3(np.eye(3), np.array([0.0, 0.0, -0.12]))  # the palm, 12 cm past the wrist
AXIS = np.array([0.0, 0.0, 1.0])  # the palm's normal in its frame
NORMAL = np.array([0.03, -0.02, -1.0]) / np.linalg.norm([0.03, -0.02, -1.0])  # true, world
OFFSET = -0.9  # NORMAL·p on the table [m]: the palm 0.9 m above the sole
STD = (2e-4, 2e-3)  # height [m], tilt [rad]


def _data(mech, q, std=STD, plane="table"):
    return FlushContact(q, mech.actuated, mech.measured_frame, plane, AXIS,
                        np.array([0.0, 0.0, -1.0]), *std)  # fmt: skip


@pytest.fixture(scope="module")
def chain():
    """TALOS from the left sole to a palm frame on the left wrist (15 joints)."""
    tree = UrdfTree(resolve_named("talos").urdf.read_text())
    on = set(chain_joints(tree, ROOT, LINK))
    lock = {n: 0.0 for n, j in tree.joints.items() if j.type in MOVABLE_TYPES and n not in on}
    return serial_mechanism("talos", LINK, lock=lock, root=ROOT, T_flange_tool=T_FACE,
                            measured="pose")  # fmt: skip


@pytest.fixture(scope="module")
def humanoid(chain):
    """(the chain, truth model, 160+ touching configurations without noise); ~10 s."""
    mech = chain
    truth = perturbed_model("talos", 1e-3, 0)
    starts = sample_actuators(mech, 900, np.random.default_rng(7))
    q = flush_poses(truth, ROOT, LINK, T_FACE, mech.actuated, starts, AXIS, NORMAL, OFFSET,
                    (0.0, 0.0), 4)  # fmt: skip
    assert len(q) >= 160
    return mech, truth, q


def test_kind_is_registered_and_checks_its_input():
    assert artefact_class("flush") is FlushContact
    with pytest.raises(MeasurementError, match="axis"):
        FlushContact(np.zeros((2, 1)), ("j",), "tool", axis=np.zeros(3))
    with pytest.raises(MeasurementError, match="std_tilt"):
        FlushContact(np.zeros((2, 1)), ("j",), "tool", std_tilt=0.0)
    with pytest.raises(MeasurementError, match=r"\(m, 1\)"):
        FlushContact(np.zeros((2, 2)), ("j",), "tool")


def test_residual_derivatives_match_finite_differences():
    rng = np.random.default_rng(0)
    P = rng.normal(0, 0.5, (4, 3))
    Rs = np.array([pin.exp3(rng.normal(0, 0.3, 3)) @ pin.rpy.rpyToMatrix(np.pi, 0, 0)
                   for _ in range(4)])  # fmt: skip
    axis, n0 = np.array([0.0, 0.6, 0.8]), np.array([0.0, 0.0, -1.0])
    phi = np.array([0.05, -0.08, 0.7])
    _, dp, dw, dphi = flush_residuals(P, Rs, axis, n0, phi)
    h = 1e-6
    for k in range(3):
        e = np.eye(3)[k] * h
        fd = (flush_residuals(P + e, Rs, axis, n0, phi)[0]
              - flush_residuals(P - e, Rs, axis, n0, phi)[0]) / (2 * h)  # fmt: skip
        assert np.abs(fd - dp[:, :, k]).max() < 1e-8
        turn = np.array([R @ pin.exp3(e) for R in Rs]), np.array([R @ pin.exp3(-e) for R in Rs])
        fd = (flush_residuals(P, turn[0], axis, n0, phi)[0]
              - flush_residuals(P, turn[1], axis, n0, phi)[0]) / (2 * h)  # fmt: skip
        assert np.abs(fd - dw[:, :, k]).max() < 1e-8
        fd = (flush_residuals(P, Rs, axis, n0, phi + e)[0]
              - flush_residuals(P, Rs, axis, n0, phi - e)[0]) / (2 * h)  # fmt: skip
        assert np.abs(fd - dphi[:, :, k]).max() < 1e-8
    assert np.abs(dw).max() > 0.1 and np.abs(dphi[:, 1:, :2]).max() > 0.1  # not all zero


def test_joint_jacobian_matches_finite_differences(chain):
    mech = chain
    q = sample_actuators(mech, 8, np.random.default_rng(2))  # touching or not: same model
    params = parameters(mech, "chain")
    prob = InstrumentProblem(mech, params, [_data(mech, q[:4]), _data(mech, q[4:8])])
    assert prob.names[-3:] == ("table.n1", "table.n2", "table.d")  # one plane, shared
    x = prob.x0 + np.random.default_rng(5).normal(0, 1e-3, prob.x0.size)
    r, J, _ = prob.evaluate(x)
    assert r.size == 3 * 8
    h = 1e-7
    Jfd = np.empty_like(J)
    for k in range(x.size):
        e = np.zeros(x.size)
        e[k] = h
        Jfd[:, k] = (prob.evaluate(x + e, False)[0] - prob.evaluate(x - e, False)[0]) / (2 * h)
    assert np.abs(J - Jfd).max() < 1e-5 * np.abs(Jfd).max()


def _held_out_whitened(mech, out, q) -> float:
    """RMS of the whitened flush residuals of the calibrated chain at poses not fitted."""
    cal = out.result.calibrated_mechanism
    T = [cal.frame_placement(c) for c in cal.configurations(q)]
    P, Rs = np.array([t.translation for t in T]), np.array([t.rotation for t in T])
    phi = out.values[[out.names.index(f"table.{s}") for s in ("n1", "n2", "d")]]
    r = flush_residuals(P, Rs, AXIS, np.array([0.0, 0.0, -1.0]), phi)[0]
    return float(np.sqrt(np.mean((r / np.array([2e-4, 2e-3, 2e-3])) ** 2)))


@pytest.mark.slow
def test_exact_touches_are_reproduced(humanoid):
    """Noise-free touches: the re-rooted chain and the plane fit them, and new ones, exactly."""
    mech, _, q = humanoid
    params = parameters(mech, "chain")
    out = identify_instruments(mech, params, [_data(mech, q[:120])], weak_bound=None)
    assert out.result.success
    assert np.abs(out.residuals[0]).max() < 1e-9
    assert _held_out_whitened(mech, out, q[120:]) < 1e-5  # nominal chain: ≫ 1
    n = out.values[[out.names.index(f"table.{s}") for s in ("n1", "n2", "d")]]
    assert abs(n[2] - OFFSET) < 0.05  # the palm's offset along its normal joins d


def _palm_params(mech):
    """The chain preset without the palm's position and its turn about its normal.

    A flush touch does not see where on the palm it lands, nor the palm's turn about its
    normal; its offset along the normal is the plane's ``d``. Kept in, those are seen
    only through the tilt noise itself, and the fit absorbs noise into them (χ²/dof
    0.70–0.75 over 3 draws of this campaign, against 0.98–1.01 without them).
    """
    params = parameters(mech, "chain")
    out = ("tool_frame.tx", "tool_frame.ty", "tool_frame.tz", "tool_frame.rz")
    return params.subset([i for i, n in enumerate(params.names) if n not in out])


def _prediction_d2(mech, params, out, q) -> float:
    """d²/k of the predicted flush residuals at exact touches ``q`` against their covariance.

    On the flush manifold the truth's residuals are 0, so the calibrated chain's are its
    prediction error ``J·(x̂ − x*)``, whose covariance is ``J C Jᵀ`` — free of whatever
    no touch sees (the gauge). k = the rank of ``J C Jᵀ``.
    """
    r, J, _ = InstrumentProblem(mech, params, [_data(mech, q)]).evaluate(out.values)
    Jf = J[:, out.fitted]
    w, V = np.linalg.eigh(Jf @ out.covariance @ Jf.T)
    keep = w > 1e-12 * w.max()
    return float(np.sum((V.T @ r)[keep] ** 2 / w[keep])) / int(keep.sum())


@pytest.mark.slow
def test_noisy_touches_recover_the_errors_to_the_cramer_rao_level(humanoid):
    """10 noise draws: χ²/dof ≈ 1, new touches at the noise, predictions at the CR level."""
    mech, truth, q = humanoid
    params = _palm_params(mech)
    chi2, held, d2 = [], [], []
    for seed in range(10):
        noisy = flush_poses(truth, ROOT, LINK, T_FACE, mech.actuated, q, AXIS, NORMAL,
                            OFFSET, STD, 100 + seed, within_limits=False)  # fmt: skip
        assert len(noisy) == len(q)
        out = identify_instruments(mech, params, [_data(mech, noisy[:120])], weak_bound=None)
        assert out.result.success
        w = out.whitened[1]
        chi2.append(float(np.sum(w**2)) / (w.size - len(out.fitted)))
        held.append(_held_out_whitened(mech, out, noisy[120:]))
        d2.append(_prediction_d2(mech, params, out, q[120:126]))
    print(
        f"chi2/dof {np.round(chi2, 3)}; held-out whitened RMS {np.round(held, 3)}; "
        f"prediction d2/k {np.round(d2, 3)}"
    )
    # 360 residuals, 64 parameters: χ²/dof has 1σ ≈ √(2/296) ≈ 0.08 per draw
    assert abs(np.mean(chi2) - 1.0) < 0.1, chi2
    # new touches: their own noise (1) plus the prediction's spread (≈ k/m ≈ 0.2 of it)
    assert 0.9 < np.mean(held) < 1.35, held
    se = np.std(d2, ddof=1) / np.sqrt(len(d2))
    assert abs(np.mean(d2) - 1.0) < max(3 * se, 0.2), (np.mean(d2), se, d2)

"""Over-constrained loops: a planar five-bar closed by a 6d weld (closure rank 3 of 6).

Parameters that move a loop out of its plane cannot change without opening the weld;
identifiability reports them apart ("breaks loop closure"), the identification
Jacobian is exact (central differences) for all the others, and those that are
identifiable are recovered from noise-free measurements.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import pincal
from pincal.errors import ConvergenceError
from pincal.model import Mechanism, parameters, sample_actuators
from pincal.sensitivity import (
    closure_breaking,
    identifiability,
    identification_jacobian,
    pose_sensitivity,
)
from tests.sensitivity.five_bar import FIVE_BAR_SIDECAR, FIVE_BAR_URDF

LOOP_JOINTS = ("act_a", "pas_a", "tip_joint", "act_b", "pas_b", "tip_b_joint")
OUT_OF_PLANE = ("tz", "rx", "ry")


@pytest.fixture(scope="module")
def five_bar() -> Mechanism:
    return Mechanism(FIVE_BAR_URDF, FIVE_BAR_SIDECAR, name="five_bar")


@pytest.fixture(scope="module")
def full(five_bar):
    return parameters(five_bar, "full")


@pytest.fixture(scope="module")
def rows(five_bar):
    return sample_actuators(five_bar, 24, np.random.default_rng(3))


def test_five_bar_is_over_constrained(five_bar):
    q = five_bar.q_home
    Jc = five_bar.closure_jacobian(q)[:, five_bar.free_dofs]
    s = np.linalg.svd(Jc, compute_uv=False)
    assert Jc.shape[0] == 6 and five_bar.mobility == 2
    assert int(np.sum(s > 1e-8 * s[0])) == 3  # the 6d weld of a planar loop has rank 3


def test_split_is_the_out_of_plane_loop_parameters(five_bar, full, rows):
    breaks = closure_breaking(five_bar, full, rows)
    expected = {f"{j}.{d}" for j in LOOP_JOINTS for d in OUT_OF_PLANE}
    assert {full.names[k] for k in np.flatnonzero(breaks)} == expected
    # per pose too
    sens = pose_sensitivity(five_bar, full, five_bar.configuration(rows[0]))
    assert np.array_equal(sens.breaks_closure, breaks)


def test_split_matches_whether_the_loop_still_closes(five_bar, full, rows):
    """Physical meaning: a closable parameter changed by 1e-4 leaves a closed mechanism;
    a breaking one leaves a weld that no passive motion closes."""
    breaks = closure_breaking(five_bar, full, rows)
    for k in range(len(full)):
        values = np.zeros(len(full))
        values[k] = 1e-4
        if breaks[k]:
            with pytest.raises((ConvergenceError, pincal.ClosureError)):
                full.apply(five_bar, values).configuration(rows[0])
        else:
            moved = full.apply(five_bar, values)
            q = moved.configuration(rows[0])
            assert np.max(np.abs(moved.closure_residual(q))) <= 1e-12


def test_serial_and_regular_loops_break_nothing(stewart, stewart42, stewart_poses):
    assert not np.any(closure_breaking(stewart, stewart42, stewart_poses[:5]))
    assert identifiability(stewart, stewart42, stewart_poses).breaks_closure.size == 0


def test_identifiability_reports_breaking_parameters_apart(five_bar, full, rows):
    ident = identifiability(five_bar, full, rows)
    breaking = set(ident.breaks_closure.tolist())
    assert len(breaking) == len(LOOP_JOINTS) * len(OUT_OF_PLANE)
    assert breaking.isdisjoint(ident.base.tolist())
    assert breaking.isdisjoint(ident.unidentifiable.tolist())
    assert len(ident.base) == ident.rank
    assert len(ident.base) + len(ident.unidentifiable) + len(breaking) == len(full)
    assert "break loop closure" in ident.summary()
    # one grouped line (issue 36: not one per parameter), counting them, naming the joints;
    # every name stays in breaks_closure_names
    closing = [line for line in ident.describe() if "loop closure" in line]
    assert len(closing) == 1
    assert closing[0].startswith(f"{len(breaking)} parameters break loop closure at ")
    assert "act_a.{" in closing[0] and "rx" in closing[0].split("act_a.{")[1].split("}")[0]
    assert "act_a.rx" in ident.breaks_closure_names
    assert len(ident.breaks_closure_names) == len(breaking)
    # the rank counts only closable columns
    closable = np.flatnonzero(~closure_breaking(five_bar, full, rows))
    J = identification_jacobian(five_bar, full, rows)[:, closable]
    norms = np.linalg.norm(J, axis=0)
    effective = norms > 1e-12 * norms.max()  # columns without effect are zero
    s = np.linalg.svd(J[:, effective] / norms[effective], compute_uv=False)
    assert ident.rank == int(np.sum(s > 1e-8 * s[0]))


def _measured(mech, q_act_rows, reference_rotations):
    out = []
    for row, R_ref in zip(q_act_rows, reference_rotations, strict=True):
        T = mech.forward(row)
        out.append(np.concatenate([T.translation, pin.log3(R_ref.T @ T.rotation)]))
    return np.concatenate(out)


@pytest.mark.parametrize("at_zero", [True, False])
def test_jacobian_matches_central_differences_on_closable_parameters(five_bar, full, rows, at_zero):
    closable = full.subset(np.flatnonzero(~closure_breaking(five_bar, full, rows)))
    rng = np.random.default_rng(8)
    values = np.zeros(len(closable)) if at_zero else rng.normal(0, 2e-4, len(closable))
    sample = rows[:3]
    J = identification_jacobian(
        five_bar, closable, sample, values, components=("x", "y", "z", "rx", "ry", "rz")
    )
    at = closable.apply(five_bar, values)
    R_ref = [at.forward(r).rotation for r in sample]
    h = 1e-6
    cols = []
    for k in range(len(closable)):
        e = np.zeros(len(closable))
        e[k] = h
        plus = _measured(closable.apply(five_bar, values + e), sample, R_ref)
        minus = _measured(closable.apply(five_bar, values - e), sample, R_ref)
        cols.append((plus - minus) / (2 * h))
    J_fd = np.stack(cols, axis=1)
    assert np.max(np.abs(J - J_fd)) <= 1e-6 * np.max(np.abs(J))


def test_noise_free_recovery_of_identifiable_closable_parameters(five_bar, full, rows):
    ident = identifiability(five_bar, full, rows)
    base = full.subset(ident.base)
    truth = np.random.default_rng(12).normal(0, 5e-4, len(base))
    actual = base.apply(five_bar, truth)
    meas = pincal.simulate_measurements(actual, rows)
    result = pincal.identify(five_bar, base, meas)
    assert result.params.names == base.names
    assert np.max(np.abs(result.values - truth)) <= 1e-9


def test_full_pose_measurement_does_not_count_breaking_parameters(rows):
    """Measuring z, rx, ry too: out-of-plane parameters have a (least-squares) column
    there, but they still cannot change, so they are not identifiable."""
    mech = Mechanism(FIVE_BAR_URDF, dict(FIVE_BAR_SIDECAR, measured="pose"), name="five_bar")
    full = parameters(mech, "full")
    ident = identifiability(mech, full, rows)
    breaking = {full.names[k] for k in ident.breaks_closure}
    assert breaking == {f"{j}.{d}" for j in LOOP_JOINTS for d in OUT_OF_PLANE}
    assert breaking.isdisjoint(ident.base_names)
    assert len(ident.base) == ident.rank
    # the closable out-of-plane parameter of the measured frame itself stays identifiable
    assert {"effector_joint.tz", "effector_joint.rx", "effector_joint.ry"} <= set(ident.base_names)
    base = full.subset(ident.base)
    truth = np.random.default_rng(2).normal(0, 5e-4, len(base))
    meas = pincal.simulate_measurements(base.apply(mech, truth), rows)
    result = pincal.identify(mech, base, meas)
    assert np.max(np.abs(result.values - truth)) <= 1e-9

"""Machine style: the Delta with 4R parallelograms (machines.delta_4r) driven far from
home — arm angles up to 77° — as a new user does (issue 36, item 1). A bare Newton from
home lands there on another assembly mode with the *same* branch sign (two legs
flipped: the sign of the product of the leg determinants stays), so forward kinematics
must follow the straight command path from home. Compared here with a continuation
written independently: small steps, Newton at each, the branch sign checked at each."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from pincal.model import load_mechanism
from tests.open_world.machines import delta_4r, write_machine

#: commands [rad] where a direct solve from home closed on another mode (home: 0, 0, 0)
FAR = np.array(
    [
        [1.3463389, 0.5195176, 0.4212860],
        [-0.2672548, -0.8441635, -1.1458915],
        [1.0181923, 1.3473461, 1.2801885],
    ]
)


@pytest.fixture(scope="module")
def mech(tmp_path_factory):
    urdf, side = delta_4r()
    assert urdf.count('lower="-0.3" upper="0.3"') == 3
    urdf = urdf.replace('lower="-0.3" upper="0.3"', 'lower="-1.5" upper="1.5"')
    return load_mechanism(write_machine(tmp_path_factory.mktemp("m"), "delta4r", urdf, side))


def _follow(mech, a_target: np.ndarray, steps: int = 150) -> np.ndarray:
    """Closed configuration at ``a_target`` reached from home in small straight steps."""
    model, free = mech.model, mech.free_dofs
    q, a0 = mech.q_home.copy(), mech.actuators_of(mech.q_home)
    for s in range(1, steps + 1):
        q = mech.with_actuators(q, a0 + s / steps * (a_target - a0))
        for _ in range(20):
            r = mech.closure_residual(q)
            if np.max(np.abs(r)) < 1e-13:
                break
            dv = np.zeros(model.nv)
            dv[free] = -np.linalg.lstsq(mech.closure_jacobian(q)[:, free], r, rcond=1e-10)[0]
            q = pin.integrate(model, q, dv)
        assert np.max(np.abs(mech.closure_residual(q))) < 1e-12
        assert mech.loop_solver.branch_sign(q) == mech.idle_branch
    return q


@pytest.fixture(scope="module")
def truth(mech):
    return [mech.frame_placement(_follow(mech, a)) for a in FAR]


def _same(got: pin.SE3, want: pin.SE3) -> bool:
    dp = np.linalg.norm(got.translation - want.translation)
    return dp <= 1e-9 and np.linalg.norm(pin.log3(got.rotation.T @ want.rotation)) <= 1e-9


def test_pose_by_pose_follows_the_path_from_home(mech, truth):
    for a, want in zip(FAR, truth, strict=True):
        assert _same(mech.forward(a), want)


def test_a_guess_on_the_path_gives_the_same_pose(mech, truth):
    near = mech.configuration(0.9 * FAR[0])
    assert _same(mech.frame_placement(mech.configuration(FAR[0], near)), truth[0])


def test_batched_rows_follow_the_path_from_home(mech, truth):
    rng = np.random.default_rng(2)
    rows = np.vstack([FAR, rng.uniform(-0.25, 0.25, (20, 3)), FAR])  # batched, ≥ 16 rows
    Q = mech.configurations(rows)
    for i, want in enumerate(truth):
        assert _same(mech.frame_placement(Q[i]), want)
        assert _same(mech.frame_placement(Q[len(rows) - 3 + i]), want)
    for q, a in zip(Q[3:-3], rows[3:-3], strict=True):
        assert _same(mech.frame_placement(q), mech.forward(a))


def test_batched_warm_guesses_on_the_path_give_the_same_pose(mech, truth):
    """Guesses at 0–90 % of each far command's path (home perturbed by 1e-9 for 0 %, so
    a warm start): a bare Newton from some of them lands on another mode (row 2 from
    25 %; rows 0 and 2 from home); batched with ≥ 16 rows, every result is the path's."""
    fractions = (0.0, 0.25, 0.5, 0.75, 0.9)
    guesses, rows, want = [], [], []
    for a, pose in zip(FAR, truth, strict=True):
        for f in fractions:
            g = mech.q_home + 1e-9 if f == 0.0 else _follow(mech, f * a, steps=60)
            guesses.append(g)
            rows.append(a)
            want.append(pose)
    rows_arr, guesses_arr = np.array(rows), np.array(guesses)
    assert len(rows_arr) >= 15
    Q = mech.configurations_batch(np.vstack([rows_arr, rows_arr[:1]]),
                                  np.vstack([guesses_arr, guesses_arr[:1]]))[0]  # fmt: skip
    for i, pose in enumerate(want):
        assert _same(mech.frame_placement(Q[i]), pose), (i // 5, fractions[i % 5])

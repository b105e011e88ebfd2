"""The reach screen's critical draws (pincal.workflow._reach_screen.critical_shifts).

The draws a candidate must survive besides the random ones: the pose change of a
3-σ error draw along the direction the actuators move the frame least, applied to the
target on the nominal model. Checked against the same error draw applied to the model
itself (``ParameterSet.apply``: another code path) on a UR5 whose elbow straightens.
"""

from __future__ import annotations

import numpy as np
import pytest

from pincal.compensation import compensate
from pincal.design import scaled_actuator_jacobians
from pincal.model import load_mechanism, parameters
from pincal.sensitivity import identification_jacobian
from pincal.workflow._reach_screen import CRITICAL_SIGMA, _moved, critical_shifts

ELBOWS = (0.005, 0.02, 0.1, 0.2, 0.5, 1.0)  # rad: straight (the edge of the reach) to bent


@pytest.fixture(scope="module")
def ur5():
    mech = load_mechanism("ur5")
    params = parameters(mech, "full")
    std = np.where(np.array(params.units) == "m", 1e-3, 10e-3) / np.sqrt(3.0)  # ±1 mm, ±10 mrad
    q = np.array([[0.3, -1.0, e, -1.2, 1.4, 0.2] for e in ELBOWS])
    return mech, params, std, q


def test_critical_shift_is_three_sigma_along_the_weakest_direction(ur5):
    mech, params, std, q = ur5
    d = critical_shifts(mech, params, q, std)
    G, scale, _ = scaled_actuator_jacobians(mech, q)
    K = identification_jacobian(mech, params, q).reshape(len(q), 6, -1)
    rng = np.random.default_rng(3)
    for i in range(len(q)):
        u = np.linalg.svd(G[i])[0][:, -1]
        # Monte Carlo of the pose change of uniform errors, projected on u (scaled)
        draws = rng.uniform(-np.sqrt(3) * std, np.sqrt(3) * std, size=(4000, len(std)))
        along = (draws @ K[i].T * scale) @ u
        assert abs((scale * d[i]) @ u) == pytest.approx(CRITICAL_SIGMA * along.std(), rel=0.05)


def test_first_order_verdict_matches_the_displaced_model(ur5):
    """Reaching T on the model displaced by the draw ⇔ the nominal reaching T moved back."""
    mech, params, std, q = ur5
    d = critical_shifts(mech, params, q, std)
    G, scale, _ = scaled_actuator_jacobians(mech, q)
    K = identification_jacobian(mech, params, q).reshape(len(q), 6, -1)
    verdicts = []
    for i in range(len(q)):
        u = np.linalg.svd(G[i])[0][:, -1]
        Ks = scale[:, None] * K[i] * std
        draw = CRITICAL_SIGMA * std * (Ks.T @ u) / np.sqrt(u @ Ks @ Ks.T @ u)
        assert np.allclose(K[i] @ draw, d[i], atol=1e-12)
        T = mech.forward(q[i])
        for sign in (1.0, -1.0):
            displaced = compensate(params.apply(mech, sign * draw), [T], starts=q[i : i + 1])
            moved = compensate(mech, [_moved(T, -sign * d[i])], starts=q[i : i + 1])
            assert displaced.reachable[0] == moved.reachable[0], (ELBOWS[i], sign)
            verdicts.append(bool(moved.reachable[0]))
    # the straightened elbows fail one of their draws, the bent ones pass both
    assert not all(verdicts[:4]) and all(verdicts[-4:])


def test_critical_draws_that_would_leave_too_little_are_not_applied(tmp_path):
    """A finger linkage (1 motor, ~0.1 m) under the default ±1 mm / ±10 mrad: its critical
    draws kept 47 of 265 candidates, of rank 12 < 13 (the design failed); the random
    draws' survivors stand and a note says why."""
    from click.testing import CliRunner

    from pincal.cli import main
    from tests.open_world.roster import ROSTER

    finger = next(mc for mc in ROSTER if mc.name == "MJCF gripper finger, two four-bars")
    args = ["poses", str(finger.write(tmp_path)), "--count", "30", "--preset", "base",
            "--candidates", "random:300", "--out", str(tmp_path / "p.csv")]  # fmt: skip
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    assert "the critical draws would leave 47 candidates of rank 12 < 13" in res.stderr

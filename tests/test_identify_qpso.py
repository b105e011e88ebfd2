"""QPSO identification (seed 003) and the pkm5 identifiability result."""

from __future__ import annotations

import numpy as np
import pytest

import pincal
from pincal.identification import (
    CalibrationProblem,
    QPSOOptions,
    qpso_identify,
)


@pytest.fixture(scope="module")
def wedge_offsets():
    """wedge3 with its three motor offsets as unknowns: a small, well-conditioned problem."""
    mech = pincal.load_mechanism("wedge3")
    params = pincal.parameters(mech, ["q0.offset", "q1.offset", "q2.offset"])
    rng = np.random.default_rng(2)
    q = pincal.sample_actuators(mech, 8, rng)
    given = np.array([2.1e-5, -1.3e-5, 0.7e-5])
    meas = pincal.simulate_measurements(params.apply(mech, given), q, None, rng)
    return mech, params, meas, given


def test_identify_qpso_recovers_offsets(wedge_offsets) -> None:
    mech, params, meas, given = wedge_offsets
    opts = QPSOOptions(n_particles=30, t_max=150, seed=1)
    res = pincal.identify(mech, params, meas, "qpso", qpso=opts)
    np.testing.assert_allclose(res.values, given, atol=2e-8)  # box ±50 µm → 0.02 µm
    assert res.method == "qpso" and res.success
    assert res.after.max_position < 1e-3 * res.before.max_position
    again = pincal.identify(mech, params, meas, "qpso", qpso=opts)
    np.testing.assert_array_equal(res.values, again.values)  # seeded


def test_identify_qpso_stepwise(wedge_offsets) -> None:
    mech, params, meas, given = wedge_offsets
    opts = QPSOOptions(n_particles=30, t_max=150, seed=1, fine_t_max=100)
    res = pincal.identify(mech, params, meas, "qpso-stepwise", qpso=opts)
    np.testing.assert_allclose(res.values, given, atol=2e-8)


def test_exact_and_linear_cost_models_agree(wedge_offsets) -> None:
    """Tiny swarm on the exact closed-loop cost (FK per particle) vs the linearised cost:
    the same seed gives the same best particle (nonlinearity ~1e-12 over ±50 µm)."""
    mech, params, meas, _ = wedge_offsets
    problem = CalibrationProblem(mech, params, meas)
    kw = dict(n_particles=6, t_max=8, seed=4)
    exact = qpso_identify(problem, options=QPSOOptions(cost_model="exact", **kw))
    linear = qpso_identify(problem, options=QPSOOptions(cost_model="linear", **kw))
    np.testing.assert_allclose(exact.values, linear.values, atol=1e-12)
    assert exact.nfev == 6 * 9
    assert exact.cost < exact.initial_cost
    r, _, _ = problem.evaluate(exact.values, jacobian=False)
    assert exact.cost == pytest.approx(0.5 * r @ r, rel=1e-12)


def test_bad_cost_model() -> None:
    with pytest.raises(pincal.ParameterError, match="cost model"):
        QPSOOptions(cost_model="quadratic")


def test_pkm5_hinges24_identifiability() -> None:
    mech = pincal.load_mechanism("pkm5")
    params = pincal.parameters(mech, "hinges24")
    q = pincal.sample_actuators(mech, 12, np.random.default_rng(0))
    ident = pincal.identifiability(mech, params, q)
    assert set(ident.unidentifiable_names) == {"T3.tx", "T4.tx", "S3.tx", "S4.tx"}
    assert ident.rank == 20


def test_pkm5_stepwise_beats_direct_but_not_gauss_newton() -> None:
    """The core claim of seed 003 on pkm5 (noise-free, errors ±0.03 mm on the 20
    identifiable coordinates, paper's N = 80, t_max = 300, box ±0.05 mm): step-wise QPSO
    reaches a lower cost than direct QPSO; neither gets near Gauss–Newton."""
    mech = pincal.load_mechanism("pkm5")
    params = pincal.parameters(mech, "identifiable20")
    rng = np.random.default_rng(3)
    q = pincal.sample_actuators(mech, 30, rng)
    given = rng.uniform(-3e-5, 3e-5, len(params))
    meas = pincal.simulate_measurements(params.apply(mech, given), q, None, rng)
    problem = CalibrationProblem(mech, params, meas)
    direct = qpso_identify(problem, options=QPSOOptions(seed=3))
    stepwise = qpso_identify(problem, stepwise=True, options=QPSOOptions(seed=3))
    assert stepwise.cost < direct.cost < 1e-2 * direct.initial_cost
    assert sorted(stepwise.order) == list(range(20))
    gn = np.zeros(len(params))
    for _ in range(2):  # two Gauss–Newton steps
        r, J, _ = problem.evaluate(gn)
        gn = gn - np.linalg.lstsq(J, r, rcond=None)[0]
    assert np.abs(gn - given).max() < 1e-9
    assert np.abs(stepwise.values - given).max() > 1e-6  # QPSO: micrometres off

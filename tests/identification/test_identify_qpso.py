"""QPSO identification (seed 003) and the pkm5 identifiability result."""

from __future__ import annotations

import numpy as np
import pytest

import pincal
from pincal.identification import (
    IdentificationProblem,
    QPSOExtras,
    QPSOOptions,
    identify,
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
    res = pincal.identify(mech, params, meas, "qpso", options=opts)
    np.testing.assert_allclose(res.values, given, atol=2e-8)  # box ±50 µm → 0.02 µm
    assert res.method == "qpso" and res.success
    assert res.after.max_position < 1e-3 * res.before.max_position
    again = pincal.identify(mech, params, meas, "qpso", options=opts)
    np.testing.assert_array_equal(res.values, again.values)  # seeded


def test_identify_qpso_stepwise(wedge_offsets) -> None:
    mech, params, meas, given = wedge_offsets
    opts = QPSOOptions(n_particles=30, t_max=150, seed=1, fine_t_max=100)
    res = pincal.identify(mech, params, meas, "qpso-stepwise", options=opts)
    np.testing.assert_allclose(res.values, given, atol=2e-8)


def test_exact_and_linear_cost_models_agree(wedge_offsets) -> None:
    """Tiny swarm on the exact closed-loop cost (FK per particle) vs the linearised cost:
    the same seed gives the same best particle (nonlinearity ~1e-12 over ±50 µm)."""
    mech, params, meas, _ = wedge_offsets
    # declared noise: the problem's own residual model is the one the swarm minimised
    noise = {"position": 0.001, "orientation": 0.001}
    problem = IdentificationProblem(mech, params, meas, noise=noise)
    kw = dict(n_particles=6, t_max=8, seed=4)
    exact = identify(problem, method="qpso", options=QPSOOptions(cost_model="exact", **kw))
    linear = identify(problem, method="qpso", options=QPSOOptions(cost_model="linear", **kw))
    np.testing.assert_allclose(exact.full_values, linear.full_values, atol=1e-12)
    assert isinstance(exact.extras, QPSOExtras)
    assert exact.extras.nfev == 6 * 9
    assert exact.extras.cost < exact.extras.initial_cost
    r, _, _ = problem.model.evaluate(exact.full_values, jacobian=False)
    assert exact.extras.cost == pytest.approx(0.5 * r @ r, rel=1e-12)


def test_bad_cost_model() -> None:
    with pytest.raises(pincal.ParameterError, match="cost model"):
        QPSOOptions(cost_model="quadratic")


@pytest.mark.parametrize(
    "kw, match",
    [
        ({"n_particles": 1}, r"n_particles must be an integer ≥ 2, got 1"),
        ({"t_max": -3}, r"t_max must be an integer ≥ 0"),
        ({"half_width_m": 0.0}, r"half_width_m must be a finite number in \(0, ∞\)"),
        ({"alpha": (1.0, -0.5)}, "alpha must be a positive number"),
        ({"passes": 0}, "passes must be an integer ≥ 1"),
    ],
)
def test_bad_qpso_options_name_the_valid_range(kw, match) -> None:
    with pytest.raises(pincal.errors.SolverOptionError, match=match):
        QPSOOptions(**kw)


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
    problem = IdentificationProblem(mech, params, meas)
    direct = identify(problem, method="qpso", options=QPSOOptions(seed=3)).extras
    stepwise = identify(problem, method="qpso-stepwise", options=QPSOOptions(seed=3))
    assert stepwise.extras.cost < direct.cost < 1e-2 * direct.initial_cost
    assert sorted(stepwise.extras.order) == list(range(20))
    gn = np.zeros(len(params))
    for _ in range(2):  # two Gauss–Newton steps
        r, J, _ = problem.model.evaluate(gn)
        gn = gn - np.linalg.lstsq(J, r, rcond=None)[0]
    assert np.abs(gn - given).max() < 1e-9
    assert np.abs(stepwise.full_values - given).max() > 1e-6  # QPSO: micrometres off

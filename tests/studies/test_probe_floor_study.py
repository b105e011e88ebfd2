"""The gate's stated detection floor on a UR5 with estimated noise, by simulation.

Uses scripts/studies/probe_floor.py (UR5 ``base``, 50 poses, noise 0.01 mm / 0.05 mrad,
not declared). Seeded draws: the rates are those of these draws; the study with 40 draws
and the rates' standard errors is in docs/quality_gate.md.
"""

from __future__ import annotations

import pytest

from tests.studies.scripts import load_script


def _refused(verdict) -> bool:
    return any(x.kind == "model" for x in verdict.refusals)


@pytest.mark.slow
def test_gain_errors_above_the_floor_are_caught_and_below_pass_saying_so():
    """A gain error at 1.5× the stated floor, on each actuator, is refused ≥ 90 %; at 0.5×
    on the floor's own scale the passing fits state what they cannot see."""
    study = load_script("probe_floor", module="probe_floor_study")
    above, below, stated = [], [], []
    for seed in range(6):
        mech, params, meas, *_ = study._draw(100 + seed, 50)
        clean = study._verdict(mech, params, meas)
        assert clean.passed
        floor = dict((n, f) for n, f, _ in clean.floors)["gains"]
        for j in range(meas.q_act.shape[1]):
            faulty = study._faulty(meas, "gains", 1.5 * floor, j)
            above.append(_refused(study._verdict(mech, params, faulty)))
            w = study._verdict(mech, params, study._faulty(meas, "gains", 0.5 * floor, j))
            below.append(_refused(w))
            if not below[-1]:
                stated.append("none of the probes spans" in w.blind_spot())
    assert sum(above) >= 0.9 * len(above), f"{sum(above)}/{len(above)} caught at 1.5× the floor"
    assert sum(below) < sum(above) / 2  # the floor separates what is caught from what is not
    assert stated and all(stated)


@pytest.mark.slow
def test_ar1_noise_is_named_correlated_never_a_model_error():
    """AR(1) noise (ρ = 0.8) along the pose order: every fit names the correlation, and no
    refusal names a drift, gain or trend (its probe fires on the correlation)."""
    study = load_script("probe_floor", module="probe_floor_study")
    named, misnamed = 0, 0
    draws = 10
    for seed in range(draws):
        mech, params, _, actual, q, rng = study._draw(200 + seed, 50)
        w = study._verdict(mech, params, study._ar1(actual, q, rng))
        named += any("correlated along the pose order" in x.message for x in w.issues)
        misnamed += any("suspected" in x.message for x in w.refusals)
    assert named == draws
    assert misnamed == 0

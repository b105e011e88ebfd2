"""Model selection by K-fold held-out error: the one-standard-error rule, and joint terms."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.errors import MeasurementError
from pincal.identification import identify
from pincal.io import write_measurements
from pincal.measure import simulate_measurements
from pincal.model import actual_joint_values, load_mechanism, sample_actuators, with_joint_terms
from pincal.sensitivity import parameters
from pincal.validation import Fitted, fitted, select_model

NOISE = {"position": 0.01, "orientation": 0.01}  # [mm], [mrad]


def _measurements(mech, compliance: float, seed: int, n: int = 48):
    """A UR5 with geometric errors and (optionally) a compliant shoulder [rad/(N·m)]."""
    params = with_joint_terms(mech, parameters(mech, "base"), ["compliance"])
    rng = np.random.default_rng(seed)
    truth = np.zeros(len(params))
    geo = np.setdiff1d(np.arange(len(params)), params.joint_terms)
    truth[geo] = rng.normal(0.0, 2e-4, geo.size)
    truth[params.index("shoulder_lift_joint.compliance")] = compliance
    rows = sample_actuators(mech, n, rng)
    meas = simulate_measurements(
        params.apply(mech, truth), actual_joint_values(mech, params, truth, rows), NOISE, rng
    )
    return dataclasses.replace(meas, q_act=rows)


def _candidates(mech):
    def make(preset):
        params = parameters(mech, preset)
        return lambda m: fitted(mech, identify(mech, params, m))

    return {"geometric": make("base"), "geometric+compliance": make("base+compliance")}


@pytest.fixture(scope="module")
def ur5():
    return load_mechanism("ur5")


def test_one_standard_error_rule_on_known_errors(ur5):
    """Given per-pose errors: the best is the lowest MSE, the smallest within 1 SE wins."""
    meas = _measurements(ur5, 0.0, seed=0, n=20)
    pose = {float(x): i for i, x in enumerate(meas.positions[:, 0])}

    def fixed(err, n):  # a "fit" whose prediction error of each pose is err[pose]
        return lambda m: Fitted(lambda mm: err[[pose[float(x)] for x in mm.positions[:, 0]]], n)

    sel = select_model(
        {
            "big": fixed(np.full(len(meas), 1.00e-3), 40),
            "small": fixed(np.full(len(meas), 1.01e-3), 10),
            "bad": fixed(np.full(len(meas), 3e-3), 5),
        },
        meas,
        k=4,
        seed=0,
    )
    names = [s.name for s in sel.scores]
    assert names[sel.best] == "big"
    # identical errors on every pose: no scatter, so "small" is NOT within one SE of "big"
    assert names[sel.recommended] == "big"
    assert sel.excess[names.index("small")][0] == pytest.approx((1.01e-3) ** 2 - 1e-6)
    rng = np.random.default_rng(1)
    a, b = np.abs(rng.normal(1e-3, 5e-4, (2, len(meas))))
    b *= 1.01 * np.sqrt(np.mean(a**2) / np.mean(b**2))  # 1 % worse on average, scattered
    sel = select_model({"big": fixed(a, 40), "small": fixed(b, 10)}, meas, k=4, seed=0)
    names = [s.name for s in sel.scores]
    assert names[sel.best] == "big" and names[sel.recommended] == "small"
    d, se = sel.excess[names.index("small")]
    assert 0 < d < se
    assert "do not pay" in sel.lines()[-1]
    with pytest.raises(MeasurementError, match="at least one"):
        select_model({}, meas)


def test_compliance_is_chosen_when_present_and_not_when_absent(ur5):
    with_c = select_model(_candidates(ur5), _measurements(ur5, 3e-5, seed=2), k=4, seed=0)
    names = [s.name for s in with_c.scores]
    assert names[with_c.recommended] == "geometric+compliance"
    d, se = with_c.excess[names.index("geometric")]
    assert d > 5 * se  # the rigid model is clearly worse held-out
    without = select_model(_candidates(ur5), _measurements(ur5, 0.0, seed=3), k=4, seed=0)
    assert [s.name for s in without.scores][without.recommended] == "geometric"
    # the information criteria beside: both pick the compliance when it is there; BIC's
    # ln n penalty (6 terms × ln 288 ≈ 34) refuses it when it is not
    assert with_c.delta("aic")[names.index("geometric+compliance")] == 0.0
    assert with_c.delta("bic")[names.index("geometric+compliance")] == 0.0
    assert without.delta("bic")[names.index("geometric")] == 0.0


@pytest.mark.parametrize("declared", [True, False])
def test_information_criteria_are_their_definitions(ur5, declared):
    """AIC = −2 ln L + 2k, BIC = −2 ln L + k ln n; −2 ln L = χ² (declared noise) or the
    per-block Gaussian profile Σ n_b ln(RSS_b / n_b) (noise estimated)."""
    meas = _measurements(ur5, 0.0, seed=6, n=30)
    if not declared:
        meas = dataclasses.replace(meas, noise=None)
    result = identify(ur5, parameters(ur5, "base"), meas)
    f = fitted(ur5, result)
    k, n = int(result.identified.sum()), 6 * len(meas)
    r = result.residuals
    if declared:
        sigma = np.array([1e-5] * 3 + [1e-5] * 3)  # [m], [rad]
        expected = float(np.sum((r / sigma) ** 2))
    else:
        expected = sum(r[:, c].size * np.log(np.sum(r[:, c] ** 2) / r[:, c].size)
                       for c in (slice(0, 3), slice(3, 6)))  # fmt: skip
    assert f.n_equations == n and f.n_parameters == k
    assert f.neg2_loglik == pytest.approx(expected, rel=1e-9)
    sel = select_model({"g": lambda m: fitted(ur5, identify(ur5, parameters(ur5, "base"), m))},
                       meas, k=3)  # fmt: skip
    assert sel.scores[0].aic == pytest.approx(expected + 2 * k, rel=1e-9)
    assert sel.scores[0].bic == pytest.approx(expected + k * np.log(n), rel=1e-9)


def test_select_model_cli(ur5, tmp_path):
    path = tmp_path / "m.csv"
    write_measurements(path, _measurements(ur5, 3e-5, seed=4))
    res = CliRunner().invoke(main, ["select-model", "ur5", "--data", str(path), "--params",
                                    "base", "--models", "geometric,geometric+compliance",
                                    "--cv", "3", "--json"])  # fmt: skip
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout.strip().splitlines()[-1])
    assert doc["recommended"] == "geometric+compliance"
    rms = {c["model"]: c["held_out_rms_mm"] for c in doc["candidates"]}
    assert rms["geometric+compliance"] < 0.03 < rms["geometric"]
    res = CliRunner().invoke(main, ["select-model", "ur5", "--data", str(path),
                                    "--models", "geometric+backlash"])  # fmt: skip
    assert res.exit_code != 0 and "unknown error-model term" in res.output

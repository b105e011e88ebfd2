"""`pincal validate`: a meaningless Cramér–Rao prediction is withheld with its reason,
and a huge --data file is bounded like calibrate's (``--yes`` past it)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from pincal.cli import _limits, main
from pincal.validation import prediction_caveat


def _run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.fixture(scope="module")
def wedge(tmp_path_factory):
    d = tmp_path_factory.mktemp("wedge")
    assert _run("simulate", "wedge3", "--random", 16, "--out", d / "m.csv").exit_code == 0
    assert _run("simulate", "wedge3", "--random", 60, "--seed", 9,
                "--out", d / "held.csv").exit_code == 0  # fmt: skip
    assert _run("calibrate", "wedge3", "--data", d / "m.csv", "--out", d / "cal").exit_code == 0
    return d


def test_caveat_names_each_reason():
    names, units = ("a.tx", "a.rx"), ("m", "rad")
    good = np.diag([1e-8, 1e-6])  # 2σ 0.2 mm, 2 mrad
    assert prediction_caveat(names, units, good) is None
    assert "not finite" in prediction_caveat(names, units, np.full((2, 2), np.nan))
    neg = np.array([[1e-8, 0.0], [0.0, -1e-6]])
    assert "not positive definite" in prediction_caveat(names, units, neg)
    # two parameters almost perfectly correlated: ill-conditioned
    s = np.sqrt(np.diag(good))
    corr = np.array([[1.0, 1 - 1e-12], [1 - 1e-12, 1.0]])
    msg = prediction_caveat(names, units, corr * np.outer(s, s))
    assert "ill-conditioned" in msg and "condition number" in msg
    # a length whose σ is 40 mm (bound 20 mm at 1σ, the fit's hold rule) is named with it
    msg = prediction_caveat(names, units, np.diag([1.6e-3, 1e-6]))
    assert "a.tx (σ 40 mm)" in msg and "a.rx" not in msg
    # σ 19 mm is kept by the fit, and predicted from
    assert prediction_caveat(names, units, np.diag([0.019**2, 1e-6])) is None


def test_validate_prints_the_reason_not_the_number(wedge, monkeypatch):
    res = _run("validate", wedge / "cal", "--data", wedge / "held.csv", "--json")
    doc = json.loads(res.stdout)
    assert doc["predicted"]["withheld"] is None
    assert doc["predicted"]["model_rms_position_mm"] > 0
    # the same calibration judged against a bound its covariance exceeds
    monkeypatch.setattr("pincal.validation._held_out.PREDICTION_COND_BOUND", 1.0)
    res = _run("validate", wedge / "cal", "--data", wedge / "held.csv", "--json")
    p = json.loads(res.stdout)["predicted"]
    assert p["model_rms_position_mm"] is None and p["observed_rms_position_mm"] is None
    assert "ill-conditioned" in p["withheld"]
    res = _run("validate", wedge / "cal", "--data", wedge / "held.csv")
    assert res.exit_code == 0
    assert "Cramér–Rao prediction not given: the calibration's covariance is ill-conditioned" in (
        res.stdout
    )
    assert "Cramér–Rao (model)" not in res.stdout


def test_validate_data_rows_are_bounded_unless_yes(wedge, monkeypatch):
    monkeypatch.setattr(_limits, "MAX_POSES", 50)
    res = _run("validate", wedge / "cal", "--data", wedge / "held.csv")
    assert res.exit_code != 0
    line = res.stderr.strip()
    assert len(line.splitlines()) == 1
    assert "--data" in line and "has 60 poses, over the 50" in line and "--yes" in line
    res = _run("validate", wedge / "cal", "--data", wedge / "held.csv", "--yes")
    assert res.exit_code == 0, res.output


def test_parameters_held_for_weakness_withhold_the_prediction():
    from pincal.measure import NoiseModel, simulate_measurements
    from pincal.model import load_mechanism, parameters, sample_actuators
    from pincal.validation import validate_held_out

    nominal = load_mechanism("wedge3")
    params = parameters(nominal, "patent")
    rng = np.random.default_rng(0)
    meas = simulate_measurements(
        nominal, sample_actuators(nominal, 5, rng), NoiseModel(0.01, 0.02), rng
    )
    cov = np.eye(len(params)) * 1e-12
    free = validate_held_out(nominal, nominal, meas, params, params.names, cov).predicted
    assert free["withheld"] is None and free["model_rms_position_mm"] is not None
    held = validate_held_out(nominal, nominal, meas, params, params.names, cov,
                             held_weak=(params.names[0],)).predicted  # fmt: skip
    assert held["model_rms_position_mm"] is None
    why = held["withheld"]
    assert f"held at nominal because the poses barely determine them ({params.names[0]})" in why

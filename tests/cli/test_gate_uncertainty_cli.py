"""`pincal calibrate` says whether its σ are linear, and widens them when they are not."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

import pincal
from pincal.cli import main
from pincal.io import write_measurements
from pincal.model import sample_actuators
from pincal.report import quality_lines


@pytest.fixture(scope="module")
def campaign(stewart, stewart42):
    rng = np.random.default_rng(33)
    actual = stewart42.apply(stewart, rng.uniform(-1e-3, 1e-3, len(stewart42)))
    return pincal.simulate_measurements(
        actual, sample_actuators(stewart, 40, rng), pincal.NoiseModel(0.01, 0.02), rng
    )


def test_a_linear_pose_fit_says_its_sigma_are_the_linearised_ones(tmp_path, campaign):
    path = tmp_path / "m.csv"
    write_measurements(path, campaign, length_unit="mm")
    out = tmp_path / "cal"
    res = CliRunner().invoke(main, ["calibrate", "stewart_6ups", "--data", str(path),
                                    "--out", str(out)])  # fmt: skip
    assert res.exit_code == 0, res.output
    assert "linearisation" not in res.stderr  # no warning
    text = (out / "report.txt").read_text()
    assert "uncertainties: linear over one σ along the 12 most uncertain directions" in text
    unc = json.loads((out / "calibration.json").read_text())["quality"]["uncertainty"]
    assert unc["linear"] is True and unc["directions_failed"] == 0
    assert abs(unc["worst_cost_ratio"] - 1) < 0.05 and unc["worst_jacobian_change"] < 0.05


def test_inflated_sigma_and_a_bootstrap_beside_are_announced_in_the_report():
    quality = {
        "passed": True,
        "warnings": [{"kind": "linearity", "message": "the fit is not linear over its own "
                      "confidence region: …; the covariance reported is the linear one inflated"}],
        "uncertainty": {"linear": False, "method": "inflated", "widened_max": 1.8,
                        "directions_checked": 12, "directions_failed": 2,
                        "bootstrap": {"draws": 20, "failed": 0, "seed": 0, "largest_ratio": 1.4},
                        "intervals": {"level": 0.95, "k": 42, "noise": "estimated", "dof": 6.3,
                                      "each_sigma": 2.42, "joint_d2": 150.0,
                                      "approximate": True}},
    }  # fmt: skip
    lines = quality_lines(quality)
    assert any("warning: the fit is not linear over its own confidence region" in x
               for x in lines)  # fmt: skip
    assert any("the σ above are the linear ones inflated along them" in x for x in lines)
    assert any("bootstrap: 20 parametric refits (seed 0, 0 failed) reported beside the σ, "
               "not as them; its σ up to 1.4× the linear ones" in x for x in lines)  # fmt: skip
    assert any("ν = 6.3 residual degrees of freedom: a 95 % interval is ±2.42σ (Student t)" in x
               and "approximate" in x for x in lines)  # fmt: skip
    assert not any("widened by a parametric bootstrap" in x for x in lines)


def _count_refits(monkeypatch) -> list[int]:
    from pincal.identification.uncertainty import _bootstrap

    calls: list[int] = []
    real = _bootstrap._refit
    monkeypatch.setattr(_bootstrap, "_refit", lambda *a: calls.append(1) or real(*a))
    return calls


@pytest.mark.slow
def test_no_refit_runs_without_bootstrap_and_twenty_beside_with_it(tmp_path, campaign,
                                                                   monkeypatch):  # fmt: skip
    path = tmp_path / "m.csv"
    write_measurements(path, campaign, length_unit="mm")
    calls = _count_refits(monkeypatch)
    res = CliRunner().invoke(main, ["calibrate", "stewart_6ups", "--data", str(path),
                                    "--out", str(tmp_path / "a")])  # fmt: skip
    assert res.exit_code == 0, res.output
    assert calls == []
    unc = json.loads((tmp_path / "a" / "calibration.json").read_text())["quality"]["uncertainty"]
    assert "bootstrap" not in unc and unc["method"] == "linear"
    res = CliRunner().invoke(main, ["calibrate", "stewart_6ups", "--data", str(path),
                                    "--out", str(tmp_path / "b"), "--bootstrap", "20",
                                    "--jobs", "1"])  # fmt: skip
    assert res.exit_code == 0, res.output
    assert len(calls) == 20
    doc = json.loads((tmp_path / "b" / "calibration.json").read_text())
    unc = doc["quality"]["uncertainty"]
    boot = unc["bootstrap"]
    assert boot["draws"] + boot["failed"] == 20 and boot["written"] is False
    ident = json.loads((tmp_path / "b" / "identification.json").read_text())
    names = [p["name"] for p in ident["parameters"] if p.get("identified", True)]
    assert set(boot["std"]) == set(boot["linear_std"]) and set(boot["std"]) <= set(names)
    lin = np.array([boot["linear_std"][n] for n in boot["std"]])
    sb = np.array([boot["std"][n] for n in boot["std"]])
    # 20 refits of a linear fit: each σ within ±60 % (relative s.e. of a σ ≈ 1/√40 = 16 %)
    assert np.all(np.abs(sb / lin - 1) < 0.6)
    # the written σ are the linear ones, not the bootstrap's
    written = {p["name"]: p["std"] for p in ident["parameters"] if p["name"] in boot["std"]}
    np.testing.assert_allclose([written[n] for n in boot["std"]], lin, rtol=1e-9)
    assert "parametric bootstrap (20 seeded refits" in res.stdout
    assert "bootstrap: 20 parametric refits" in (tmp_path / "b" / "report.txt").read_text()


def test_campaign_bootstrap_key_is_passed_to_calibrate(tmp_path):
    from pincal.cli._campaign import load_campaign
    from pincal.cli._campaign_steps import _calibrate
    from pincal.errors import CampaignError

    f = tmp_path / "c.yaml"
    f.write_text("model: stewart_6ups\nmeasurements: {poses: 10}\n"
                 "identification: {bootstrap: 20}\n")  # fmt: skip
    camp = load_campaign(f)
    assert camp.identification.bootstrap == 20

    class _Paths:
        data, out = tmp_path / "m.csv", tmp_path / "cal"

    args = _calibrate(camp, _Paths())  # type: ignore[arg-type]
    assert args is not None and args[args.index("--bootstrap") + 1] == "20"
    f.write_text("model: stewart_6ups\nmeasurements: {poses: 10}\n")
    args = _calibrate(load_campaign(f), _Paths())  # type: ignore[arg-type]
    assert args is not None and "--bootstrap" not in args  # none unless asked for
    f.write_text("model: stewart_6ups\nmeasurements: {poses: 10}\n"
                 "identification: {bootstrap: 1}\n")  # fmt: skip
    with pytest.raises(CampaignError, match="identification.bootstrap"):
        load_campaign(f)

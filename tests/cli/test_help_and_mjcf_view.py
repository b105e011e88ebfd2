"""Every subcommand has --json and examples; the group help lists every bundled model;
`pincal view` draws a model loaded from MJCF."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.model import bundled_models

MJCF = Path(__file__).parents[1] / "model" / "mjcf"


@pytest.mark.parametrize("name", sorted(main.commands))
def test_every_subcommand_has_json_and_examples(name):
    res = CliRunner().invoke(main, [name, "--help"])
    assert res.exit_code == 0
    assert "--json" in res.output, name
    assert "Examples:" in res.output and f"pincal {name}" in res.output, name


def test_group_help_lists_every_bundled_model_and_validate():
    res = CliRunner().invoke(main, ["--help"])
    models = bundled_models()
    assert len(models) >= 5
    for m in models:
        assert m in res.output
    assert "validate" in res.output


def test_view_of_a_model_loaded_from_mjcf(tmp_path):
    out = tmp_path / "delta.html"
    res = CliRunner().invoke(
        main, ["view", str(MJCF / "delta.xml"), "--random", "2", "--html", str(out), "--json"]
    )
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout)["poses"] == 2
    assert out.stat().st_size > 10_000


def test_info_json_describes_the_model():
    res = CliRunner().invoke(main, ["info", "wedge3", "--preset", "patent", "--json"])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout)
    assert doc["mobility"] == 3 and doc["measured_components"] == ["x", "z", "ry"]
    assert doc["presets"][0]["preset"] == "patent" and doc["presets"][0]["identifiable"] == 7


def test_view_calibrated_refuses_a_partial_copy_with_one_line(tmp_path):
    import numpy as np

    from pincal.identification import identify
    from pincal.io import write_calibration
    from pincal.measure import NoiseModel, simulate_measurements
    from pincal.model import load_mechanism, parameters, sample_actuators

    nominal = load_mechanism("wedge3")
    params = parameters(nominal, "patent")
    rng = np.random.default_rng(1)
    q = sample_actuators(nominal, 10, rng)
    meas = simulate_measurements(
        params.apply(nominal, np.full(7, 1e-4)), q, NoiseModel(0.01, 0.01), rng
    )
    write_calibration(tmp_path / "cal", identify(nominal, params, meas), model_source="wedge3")
    args = ["view", "wedge3", "--random", "2", "--calibrated", str(tmp_path / "cal"),
            "--html", str(tmp_path / "v.html")]  # fmt: skip
    assert CliRunner().invoke(main, args).exit_code == 0
    other = CliRunner().invoke(main, ["view", "pkm5", *args[2:]])
    assert other.exit_code == 1 and "is of model 'wedge3'" in other.stderr
    (tmp_path / "cal" / "calibrated.yaml").unlink()
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 1
    assert "calibrated.yaml" in res.stderr and len(res.stderr.strip().splitlines()) == 1


def test_select_model_offers_no_option_it_refuses():
    """select-model ranks by held-out positions without a prior: it does not list --prior
    or a marker body's orientation (calibrate does), and giving one is a usage error."""
    sel = CliRunner().invoke(main, ["select-model", "--help"])
    cal = CliRunner().invoke(main, ["calibrate", "--help"])
    assert sel.exit_code == 0 and cal.exit_code == 0
    for option in ("--prior", "--orientation-columns", "--orientation "):
        assert option not in sel.output, option
        assert option in cal.output, option
    assert "--marker-columns" in sel.output and "--link" in sel.output
    res = CliRunner().invoke(main, ["select-model", "ur5", "--link", "wrist_3_link", "--data",
                                    "m.csv", "--prior", "1,1"])  # fmt: skip
    assert res.exit_code == 2 and "No such option" in res.output and "--prior" in res.output

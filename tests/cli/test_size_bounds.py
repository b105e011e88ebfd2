"""Unbounded options (issue 16): validated and costed before any work; ``--yes`` to pass.

Every refusal is exit code 1 with one line naming the option, the value and what is
valid (or the estimate and the bound), no traceback, and it comes at once (the 0.1
behaviour was minutes, a hang or a MemoryError).
"""

from __future__ import annotations

import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.design import (
    MAX_CANDIDATES,
    candidate_cost,
    candidate_set,
    parse_candidate_spec,
)
from pincal.design import _candidate_sources as candidate_sources
from pincal.errors import InputLimitError, OptionValueError, PincalError
from pincal.model import load_mechanism, parameters


def refused(args: list[str], error: str, *needles: str) -> str:
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 1, res.output
    assert "Traceback" not in res.output
    line = res.output.strip().splitlines()[-1]
    assert line.startswith(f"pincal: error: {error}: "), line
    for n in needles:
        assert n in line, (n, line)
    return line


@pytest.mark.parametrize(
    ("args", "error", "needles"),
    [
        (["poses", "hexaslide_6pus", "--candidates", "grid:100"], "InputLimitError",
         ["--candidates grid:100", "1e+12 candidate poses", "GB", "bound is 200000", "--yes"]),
        (["poses", "hexaslide_6pus", "--candidates", "oa:1000"], "InputLimitError",
         ["--candidates oa:1000", "1.02e+06 candidate poses", "bound", "--yes"]),
        (["poses", "hexaslide_6pus", "--candidates", "random:1e8"], "InputLimitError",
         ["--candidates random:100000000", "1e+08 candidate poses", "--yes"]),
        (["poses", "wedge3", "--candidates", "random:2.5"], "OptionValueError",
         ["--candidates", "not an integer >= 1", "grid:LEVELS"]),
        (["poses", "wedge3", "--candidates", "grid:inf"], "OptionValueError",
         ["--candidates grid:inf: inf is not an integer >= 2"]),
        (["poses", "wedge3", "--count", "0"], "OptionValueError",
         ["--count 0", "integer >= 1"]),
        (["poses", "wedge3", "--count", "10000000"], "InputLimitError",
         ["--count 10000000", "bound is 100000", "--yes"]),
        (["poses", "wedge3", "--restarts", "100000"], "InputLimitError",
         ["--restarts 100000", "bound is 1000"]),
        (["poses", "wedge3", "--K", "inf"], "OptionValueError", ["--K inf", "finite number > 0"]),
        (["poses", "wedge3", "--noise", "0", "1"], "OptionValueError",
         ["--noise (position) 0.0", "finite number > 0"]),
        (["simulate", "hexaslide_6pus", "--random", "100000000", "--out", "x.csv"],
         "InputLimitError", ["--random 100000000", "bound is 100000", "--yes"]),
        (["simulate", "wedge3", "--random", "5", "--error-size", "inf,inf", "--out", "x.csv"],
         "OptionValueError", ["--error-size inf,inf", "finite and >= 0"]),
        (["simulate", "wedge3", "--random", "5", "--noise", "nan,1", "--out", "x.csv"],
         "OptionValueError", ["--noise nan,1", "finite"]),
        (["simulate", "wedge3", "--random", "5", "--noise", "1", "--out", "x.csv"],
         "OptionValueError", ["--noise 1", "expected two numbers"]),
        (["calibrate", "wedge3", "--data", "m.csv", "--noise", "0,1", "--out", "c"],
         "OptionValueError", ["--noise 0,1", "pos_mm,ori_mrad", "> 0"]),
        (["acceptance", "wedge3", "--cycles", "1000000"], "InputLimitError",
         ["--cycles 1000000", "bound is 20000", "--yes"]),
        (["acceptance", "wedge3", "--error-size", "1,-2"], "OptionValueError",
         ["--error-size 1,-2", ">= 0"]),
        (["acceptance", "wedge3", "--repeatability", "inf"], "OptionValueError",
         ["--repeatability inf", "finite"]),
        (["demo", "--poses", "1000000"], "InputLimitError", ["--poses 1000000", "--yes"]),
        (["demo", "--validation", "0"], "OptionValueError", ["--validation 0", ">= 1"]),
        (["demo", "--candidates", "oa:1000", "--no-report"], "InputLimitError",
         ["--candidates oa:1000", "candidate poses", "--yes"]),
        (["demo", "--candidates", "grid:x"], "OptionValueError", ["--candidates grid:x"]),
    ],
)  # fmt: skip
def test_cli_refuses_unbounded_or_invalid_numbers(args, error, needles, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    refused(args, error, *needles)
    assert not list(tmp_path.iterdir())  # nothing written


def test_import_tracker_numbers(tmp_path):
    for name in ("p.txt", "l.csv", "t.csv"):
        (tmp_path / name).write_text("x\n")
    base = ["import-tracker", str(tmp_path / "p.txt"), "--log", str(tmp_path / "l.csv"),
            "--targets", str(tmp_path / "t.csv"), "--model", "wedge3",
            "--out", str(tmp_path / "o.csv")]  # fmt: skip
    refused([*base, "--tolerance", "-1"], "OptionValueError", "--tolerance -1", "> 0")
    refused([*base, "--point-std", "inf"], "OptionValueError", "--point-std inf", "> 0")


def test_yes_goes_past_the_pose_bound(tmp_path, monkeypatch):
    monkeypatch.setattr("pincal.cli.simulate.MAX_POSES", 4)
    args = ["simulate", "wedge3", "--random", "6", "--out", str(tmp_path / "m.csv")]
    refused(args, "InputLimitError", "--random 6", "bound is 4")
    res = CliRunner().invoke(main, [*args, "--yes"])
    assert res.exit_code == 0, res.output
    assert (tmp_path / "m.csv").is_file()


def test_yes_goes_past_the_candidate_bound(tmp_path, monkeypatch):
    monkeypatch.setattr("pincal.design.MAX_CANDIDATES", 10)
    args = ["poses", "wedge3", "--count", "6", "--candidates", "random:30",
            "--out", str(tmp_path / "p.csv")]  # fmt: skip
    refused(args, "InputLimitError", "--candidates random:30", "bound is 10 poses")
    res = CliRunner().invoke(main, [*args, "--yes"])
    assert res.exit_code == 0, res.output


@pytest.mark.parametrize(
    ("key", "value"),
    [("noise", "[.inf, 0.05]"), ("error_size", "[1, .nan]"), ("noise", f"[1{'0' * 400}, 1]")],
)
def test_run_campaign_rejects_non_finite_numbers_up_front(key, value, tmp_path):
    camp = tmp_path / "c.yaml"
    camp.write_text(f"model: wedge3\nmeasurements: {{poses: 5, {key}: {value}}}\n")
    line = refused(["run", str(camp), "--out", str(tmp_path / "cal")], "CampaignError",
                   f"measurements.{key}[", "expected a finite number")  # fmt: skip
    assert len(line) < 300


def test_run_campaign_checks_the_candidate_spec_and_forwards_yes(tmp_path, monkeypatch):
    camp = tmp_path / "c.yaml"
    camp.write_text("model: wedge3\ndesign: {count: 6, candidates: 'grid:two'}\n")
    refused(["run", str(camp), "--dry-run"], "CampaignError", "design.candidates", "grid:two")
    monkeypatch.setattr("pincal.cli.simulate.MAX_POSES", 4)
    camp.write_text("model: wedge3\npreset: patent\nmeasurements: {poses: 12}\n"
                    "validation: {source: none}\nreport: false\n")  # fmt: skip
    res = CliRunner().invoke(main, ["run", str(camp), "--out", str(tmp_path / "cal")])
    assert res.exit_code == 1 and "--random 12" in res.output and "--yes" in res.output
    res = CliRunner().invoke(main, ["run", str(camp), "--out", str(tmp_path / "cal"), "--yes"])
    assert res.exit_code == 0, res.output


# ----------------------------------------------------------------------------- library


def test_candidate_cost_estimates():
    assert candidate_cost("grid", 4, 6, 6, 42).rows == 4096
    assert candidate_cost("grid", 100, 6, 6, 42).rows == 10**12
    assert candidate_cost("oa", 5, 6, 6, 42).rows == 25
    assert candidate_cost("oa", 3, 6, 6, 42).rows == 25  # p = 5 for six factors
    assert candidate_cost("oa", 1000, 6, 6, 42).rows == 1009**2
    big = candidate_cost("random", 10**8, 6, 6, 42)
    assert big.bytes == 10**8 * 8 * (6 * 42 + 6 * 42 + 12 + 18)
    with pytest.raises(InputLimitError, match="bound is 200000 poses"):
        big.check("random:1e8")
    candidate_cost("grid", 4, 6, 6, 42).check("grid:4")  # the default is fine


def test_library_candidate_set_bounds(monkeypatch):
    mech = load_mechanism("hexaslide_6pus")
    params = parameters(mech, next(iter(mech.presets)))

    def never(*args, **kwargs):
        raise AssertionError("candidate work started before the cost was checked")

    with monkeypatch.context() as m:
        for name in ("evaluate_candidates", "sample_actuators"):
            m.setattr(candidate_sources, name, never)
        for spec in ("grid:100", "oa:1000", "random:100000000"):
            with pytest.raises(InputLimitError, match=r"candidate poses, ~.* GB; the bound is"):
                candidate_set(mech, params, spec)
    with pytest.raises(InputLimitError):
        candidate_set(mech, params, "random:20", max_candidates=10)
    assert len(candidate_set(mech, params, "random:20", rng=0, max_candidates=None)) > 0
    assert MAX_CANDIDATES == 200_000


@pytest.mark.parametrize("spec", ["grid:1", "random:0", "oa:-3", "random:nan", "grid:1e400",
                                  "oa:abc", "mesh:4"])  # fmt: skip
def test_parse_candidate_spec_rejects(spec):
    with pytest.raises(OptionValueError) as e:
        parse_candidate_spec(spec)
    assert isinstance(e.value, PincalError) and "grid:LEVELS" in str(e.value)


def test_parse_candidate_spec_accepts_integral_notation():
    assert parse_candidate_spec("random:1e3") == ("random", 1000)
    assert parse_candidate_spec("grid") == ("grid", 4)

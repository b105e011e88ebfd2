"""Extreme option and header values are refused naming the option and the valid range.

No internal name (``m``, ``joblib``, a URDF parse error) and no numpy warning reaches
the user: each case exits 1 (or 2 for click's own types) with one line.
"""

from __future__ import annotations

import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.cli._environment import limits_from_environment
from pincal.errors import InputLimitError, MeasurementFormatError
from pincal.io import read_measurement_file
from pincal.model import load_mechanism


def one_line_error(args: list[str], code: int = 1) -> str:
    res = CliRunner().invoke(main, args)
    assert res.exit_code == code, res.output
    assert "Traceback" not in res.output and "Warning" not in res.output, res.output
    return res.stderr.strip().splitlines()[-1]


@pytest.mark.parametrize("value", ["inf", "nan", "-1", "0", "1e30", "lots"])
def test_max_file_mb_must_be_a_finite_positive_number(monkeypatch, value):
    monkeypatch.setenv("PINCAL_MAX_FILE_MB", value)
    with pytest.raises(InputLimitError, match=r"PINCAL_MAX_FILE_MB=.* in \(0, 1000000000\]"):
        limits_from_environment({"PINCAL_MAX_FILE_MB": value})
    line = one_line_error(["info", "wedge3"])
    assert "PINCAL_MAX_FILE_MB" in line and "unset it" in line


def test_poses_count_above_the_candidates_names_count():
    line = one_line_error(["poses", "wedge3", "--count", "8", "--candidates", "grid:4",
                           "--out", "/tmp/unused-p.csv"])  # fmt: skip
    assert "--count 8 is more than the 4 feasible candidate poses" in line
    assert "m must be" not in line
    assert "relax the screens that removed them (none did)" in line


def test_too_few_poses_left_by_the_screens_names_the_options_that_relax_them():
    line = one_line_error(["poses", "ur5", "--count", "8", "--candidates", "random:40",
                           "--joint-margin", "0.45", "--out", "/tmp/unused-p.csv"])  # fmt: skip
    assert "feasible candidate poses" in line
    assert "relax the screens that removed them (--joint-margin" in line


@pytest.mark.parametrize("command", [
    ["simulate", "wedge3", "--random", "3", "--out", "/tmp/unused.csv"],
    ["poses", "wedge3", "--count", "3", "--out", "/tmp/unused.csv"],
    ["view", "wedge3", "--html", "/tmp/unused.html"],
])  # fmt: skip
def test_negative_seed_names_the_option(command):
    line = one_line_error([*command, "--seed", "-1"], code=2)
    assert "'--seed'" in line and "x>=0" in line


@pytest.mark.parametrize(
    "args, option",
    [
        (["simulate", "wedge3", "--random", "3", "--error-size", "1e308,1"], "--error-size"),
        (["simulate", "wedge3", "--random", "3", "--noise", "1e-300,0.01"], "--noise"),
        (["simulate", "wedge3", "--random", "3", "--noise", "1e300,0.01"], "--noise"),
        (["acceptance", "wedge3", "--error-size", "1,1e300"], "--error-size"),
    ],
)
def test_extreme_sizes_and_noise_name_the_option_and_range(tmp_path, args, option):
    line = one_line_error([*args, "--out", str(tmp_path / "o.csv")])
    assert f"OptionValueError: {option}" in line and "between 1e-06 and 1000" in line
    assert not (tmp_path / "o.csv").exists()


def test_calibrate_and_poses_noise_bounds(tmp_path):
    line = one_line_error(["calibrate", "wedge3", "--data", "x.csv", "--noise", "1e-300,1",
                           "--out", str(tmp_path / "cal")])  # fmt: skip
    assert "--noise" in line and "between 1e-06 and 1000" in line
    line = one_line_error(["poses", "wedge3", "--noise", "1e300", "1", "--out",
                           str(tmp_path / "p.csv")])  # fmt: skip
    assert "--noise (position)" in line and "between 1e-06 and 1000" in line


@pytest.fixture(scope="module")
def measured(tmp_path_factory):
    d = tmp_path_factory.mktemp("bounds")
    res = CliRunner().invoke(main, ["simulate", "wedge3", "--random", "12",
                                    "--out", str(d / "m.csv")])  # fmt: skip
    assert res.exit_code == 0, res.output
    return d / "m.csv"


@pytest.mark.parametrize("sigma", ["1e-300", "1e300"])
def test_header_noise_out_of_range_names_file_and_range(measured, tmp_path, sigma):
    text = measured.read_text().splitlines()
    text = [f"# noise: position_mm={sigma} orientation_mrad=0.05" if t.startswith("# noise")
            else t for t in text]  # fmt: skip
    f = tmp_path / "n.csv"
    f.write_text("\n".join(text) + "\n")
    with pytest.raises(MeasurementFormatError, match=r"n.csv: noise entry .* between 1e-06"):
        read_measurement_file(f, load_mechanism("wedge3"))
    line = one_line_error(["calibrate", "wedge3", "--data", str(f), "--out", str(tmp_path / "c")])
    assert "n.csv" in line and "between 1e-06 and 1000" in line
    assert not (tmp_path / "c").exists()


def test_per_pose_std_out_of_range_names_row_and_column(measured, tmp_path):
    lines = measured.read_text().splitlines()
    head = next(i for i, t in enumerate(lines) if not t.startswith("#"))
    comps = ["x", "z", "ry"]
    lines[head] += "," + ",".join(f"std_{c}" for c in comps)
    for i in range(head + 1, len(lines)):
        lines[i] += ",1e300,0.01,0.01" if i == head + 2 else ",0.01,0.01,0.01"
    f = tmp_path / "s.csv"
    f.write_text("\n".join(lines) + "\n")
    line = one_line_error(["calibrate", "wedge3", "--data", str(f), "--out", str(tmp_path / "c")])
    assert "s.csv data row 2, column 'std_x'" in line and "between 1e-06 and 1000" in line


def test_jobs_zero_names_the_option_and_range(tmp_path):
    line = one_line_error(["poses", "wedge3", "--jobs", "0", "--out", str(tmp_path / "p.csv")])
    assert "--jobs 0 is not valid" in line and "-1 for every CPU" in line
    assert "n_jobs" not in line


def test_jobs_above_the_cpu_count_is_clamped_with_a_note(tmp_path, monkeypatch):
    monkeypatch.setattr("os.cpu_count", lambda: 1)  # one worker: no process pool in the test
    res = CliRunner().invoke(main, ["poses", "wedge3", "--count", "6", "--candidates",
                                    "random:100", "--jobs", "1000000",
                                    "--out", str(tmp_path / "p.csv")])  # fmt: skip
    assert res.exit_code == 0, res.output
    assert "pincal: note: --jobs 1000000 is more than the 1 CPUs; using 1" in res.stderr

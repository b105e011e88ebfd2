"""Malformed measurement files name the file, the line and what is valid."""

from __future__ import annotations

from pathlib import Path

import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.errors import MeasurementFormatError
from pincal.io import read_measurement_file
from pincal.model import load_mechanism


@pytest.fixture(scope="module")
def measured(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("formats")
    res = CliRunner().invoke(main, ["simulate", "wedge3", "--random", "12",
                                    "--out", str(d / "m.csv")])  # fmt: skip
    assert res.exit_code == 0, res.output
    return d / "m.csv"


def _variant(measured: Path, tmp_path: Path, name: str, edit) -> Path:
    lines = measured.read_text().splitlines()
    f = tmp_path / name
    f.write_text("\n".join(edit(lines)) + "\n")
    return f


def _refused(f: Path, pattern: str) -> None:
    with pytest.raises(MeasurementFormatError, match=pattern):
        read_measurement_file(f, load_mechanism("wedge3"))
    res = CliRunner().invoke(main, ["calibrate", "wedge3", "--data", str(f), "--params",
                                    "patent", "--out", str(f.parent / "cal")])  # fmt: skip
    assert res.exit_code == 1 and "Traceback" not in res.output
    assert f.name in res.stderr and not (f.parent / "cal").exists()


def test_a_newer_format_version_is_refused(measured, tmp_path):
    f = _variant(measured, tmp_path, "v2.csv", lambda ls: ["# pincal measurements 2", *ls[1:]])
    _refused(f, r"v2.csv line 1: format version 2; this pincal reads version 1")


def test_a_malformed_format_version_is_refused(measured, tmp_path):
    f = _variant(measured, tmp_path, "vx.csv", lambda ls: ["# pincal measurements 1.x", *ls[1:]])
    _refused(f, r"vx.csv line 1: format version 1.x is not valid")


def test_semicolon_columns_are_named(measured, tmp_path):
    def semi(ls):
        return [t if t.startswith("#") else t.replace(",", ";") for t in ls]

    f = _variant(measured, tmp_path, "semi.csv", semi)
    _refused(f, r"semi.csv line \d+: the columns are separated by ';'")


def test_trailing_comma_is_named(measured, tmp_path):
    f = _variant(measured, tmp_path, "trail.csv",
                 lambda ls: [t if t.startswith("#") else t + "," for t in ls])  # fmt: skip
    _refused(f, r"trail.csv line \d+: column \d+ of \d+ has no title \(a trailing ','")


def test_symbolic_link_loop_is_named_as_a_loop(tmp_path):
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    a.symlink_to(b)
    b.symlink_to(a)
    res = CliRunner().invoke(main, ["calibrate", "wedge3", "--data", str(a),
                                    "--out", str(tmp_path / "cal")])  # fmt: skip
    assert res.exit_code == 1 and "Traceback" not in res.output
    assert "--data" in res.stderr and "is a symbolic link loop" in res.stderr

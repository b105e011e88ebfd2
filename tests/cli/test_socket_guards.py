"""Socket calibrations bounded as the pose route is (issue 38, item 5).

A simulated UR5 socket file, then the slips: a ball declared 1000 km off the flange
(its −1e9 mm wrist offset was written), a seating σ of 1e300 (a directory with no
parameters was written, replacing a good one), one file given twice or as a byte copy
(fitted twice, σ understated by √2). Each is refused in one line before any fit. And a
wrong ``joint_reference`` (a fit with ≈ 300 mm changes was written with a warning):
refused after the fit by the pose route's bound, naming the joint reference, nothing
replaced.
"""

from __future__ import annotations

import json
import shutil

import pytest
from click.testing import CliRunner

from pincal.cli import main


def _run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.fixture(scope="module")
def sockets(tmp_path_factory):
    s = tmp_path_factory.mktemp("sockets") / "s.csv"
    r = _run("simulate", "ur5", "--random", "20", "--instrument", "socket",
             "--errors", "seed:3", "--seed", "1", "--out", s)  # fmt: skip
    assert r.exit_code == 0, r.output
    return s


def _header(src, tmp_path, key: str, value: str):
    lines = src.read_text().splitlines(True)
    out = tmp_path / f"{key}.csv"
    out.write_text("".join(f"# {key}: {value}\n" if ln.startswith(f"# {key}:") else ln
                           for ln in lines))  # fmt: skip
    return out


def _refused(r, tmp_path, kind: str, *words: str) -> None:
    assert r.exit_code != 0, r.output
    line = r.output.strip().splitlines()[-1]
    assert line.startswith("pincal: error: " + kind), r.output
    for w in words:
        assert w in line, line
    assert not (tmp_path / "cal").exists()


@pytest.mark.parametrize("key, value, words", [
    ("ball", "1e6, 0, 0", ("1e+06 m from the flange", "within 2 m")),
    ("std", "1e300", ("header 'std'", "between 1e-06 and 1000 mm")),
    ("distance", "A, B, 0.05, 1e300", ("header 'distance' std",)),
])  # fmt: skip
def test_implausible_socket_headers_are_refused(tmp_path, sockets, key, value, words):
    r = _run("calibrate", "ur5", "--data", _header(sockets, tmp_path, key, value),
             "--out", tmp_path / "cal")  # fmt: skip
    _refused(r, tmp_path, "MeasurementFormatError", *words)


@pytest.mark.parametrize("copy", [False, True])
def test_one_file_twice_is_refused(tmp_path, sockets, copy):
    other = sockets
    if copy:
        other = tmp_path / "copy.csv"
        shutil.copy(sockets, other)
    r = _run("calibrate", "ur5", "--data", sockets, "--data", other, "--out", tmp_path / "cal")
    _refused(r, tmp_path, "DuplicateDataError", "fitted twice", "√2")


def _with_reference(src, dst, shift, declare: str | None):
    """``src``'s readings minus ``shift`` (one value per joint column), ``declare`` as the
    file's ``# joint_reference:`` header (None: no header)."""
    lines = src.read_text().splitlines()
    k = next(i for i, ln in enumerate(lines) if not ln.startswith("#"))
    rows = [",".join([*(f"{float(v) - s:.15g}" for v, s in zip(ln.split(",")[:-1], shift,
                                                                   strict=True)),
                      ln.split(",")[-1]]) for ln in lines[k + 1:]]  # fmt: skip
    head = [f"# joint_reference: {declare}"] if declare else []
    dst.write_text("\n".join([*lines[:k], *head, lines[k], *rows]) + "\n")
    return dst


@pytest.mark.parametrize("readings, declared", [
    ("absolute", "home"),      # absolute readings declared relative to home
    ("home", None),            # readings relative to home, declared absolute (no header)
])  # fmt: skip
def test_a_wrong_joint_reference_is_refused_and_nothing_replaced(tmp_path, sockets, readings,
                                                                   declared):
    """The fit absorbs home's joint values into the joint zeros (≈ 300 mm and 0.26 rad of
    changes, χ² as good as the right fit's): it was written with a warning. Now refused
    as the pose route refuses, naming the joint reference; a good calibration in --out
    is left as it was."""
    from pincal.model import load_mechanism

    mech = load_mechanism("ur5")
    home = mech.actuators_of(mech.q_home)
    shift = home if readings == "home" else 0.0 * home
    wrong = _with_reference(sockets, tmp_path / "wrong.csv", shift, declared)
    cal = tmp_path / "cal"
    assert _run("calibrate", "ur5", "--data", sockets, "--out", cal).exit_code == 0
    before = {p.name: p.read_bytes() for p in cal.iterdir()}
    r = _run("calibrate", "ur5", "--data", wrong, "--out", cal)
    assert r.exit_code != 0, r.output
    line = r.output.strip().splitlines()[-1]
    assert line.startswith("pincal: error: QualityGateError: calibration refused"), line
    for w in ("moved beyond 20 mm / 0.1 rad", "Likely cause: joint reference",
              "wrist_2_joint.offset", "'joint_reference: home'", "Nothing was written"):
        assert w in line, line
    assert {p.name: p.read_bytes() for p in cal.iterdir()} == before
    # --force writes it, the override recorded
    r = _run("calibrate", "ur5", "--data", wrong, "--out", tmp_path / "forced", "--force")
    assert r.exit_code == 0, r.output
    assert "--force: writing despite the quality gate" in r.output
    quality = json.loads((tmp_path / "forced" / "calibration.json").read_text())["quality"]
    assert quality["overridden"] is True and quality["cause"] == "joint reference"


def test_a_seating_sigma_too_large_to_place_anything_is_refused(tmp_path, sockets):
    """A σ inside the bounds (100 mm) but too large for 20 seatings to place any
    parameter: every direction is held at nominal. That directory (no parameter) was
    refused only by its own read-back, naming a temporary directory; now refused in one
    line before anything is written, and a good calibration in --out stays as it was."""
    cal = tmp_path / "cal"
    assert _run("calibrate", "ur5", "--data", sockets, "--out", cal).exit_code == 0
    before = {p.name: p.read_bytes() for p in cal.iterdir()}
    r = _run("calibrate", "ur5", "--data", _header(sockets, tmp_path, "std", "0.1"),
             "--out", cal)  # fmt: skip
    assert r.exit_code != 0, r.output
    line = r.output.strip().splitlines()[-1]
    assert line.startswith("pincal: error: UnidentifiableError: the fit placed no parameter")
    for w in ("held at nominal", "too weakly", "'# std:'", "nothing was written"):
        assert w in line, line
    assert "pincal-tmp" not in line
    assert {p.name: p.read_bytes() for p in cal.iterdir()} == before
    assert sorted(p.name for p in tmp_path.iterdir() if p.name.startswith(".")) == []


@pytest.mark.parametrize("std", ["1e300", "0", "nan", "5000", "1e-30"])
def test_import_sockets_bounds_std(tmp_path, sockets, std):
    """--std of `pincal import-sockets` is bounded as the header's std: one line, of the
    format error's class, the table named once, nothing written."""
    table = tmp_path / "lab.csv"
    table.write_text("".join(ln for ln in sockets.read_text().splitlines(True)
                             if not ln.startswith("#")))  # fmt: skip
    out = tmp_path / "s.csv"
    r = _run("import-sockets", table, "--model", "ur5", "--distance", "A,B,50,0.01",
             "--std", std, "--out", out)  # fmt: skip
    assert r.exit_code != 0, r.output
    line = r.output.strip().splitlines()[-1]
    assert line.startswith("pincal: error: MeasurementFormatError: lab.csv: the seating std"), line
    assert line.count("lab.csv") == 1 and "between 1e-06 and 1000 mm" in line, line
    assert not out.exists()

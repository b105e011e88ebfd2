"""Socket calibrations bounded as the pose route is (issue 38, item 5).

A simulated UR5 socket file, then the slips: a ball declared 1000 km off the flange
(its −1e9 mm wrist offset was written), a seating σ of 1e300 (a directory with no
parameters was written, replacing a good one), one file given twice or as a byte copy
(fitted twice, σ understated by √2). Each is refused in one line before any fit.
"""

from __future__ import annotations

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

"""The Agile Eye (a spherical parallel wrist, `robot.urdf` + `robot.yaml`): with ``--params
full`` 55 parameters break loop closure. `calibrate` and `info` say so in one line — the
count, grouped by loop (each leg's own loop, leg 1 — in the tree with the platform —
shared by both), a few joints by name, "and K more joints" — not in 55 lines (issue 36);
every name is still in identification.json's ``identifiability.breaks_closure``."""

from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.model import load_mechanism
from pincal.sensitivity import closure_loops, parameters
from tests.open_world.roster import ROSTER

EYE = next(m for m in ROSTER if m.name.startswith("Agile Eye"))


def _run(*args: object) -> str:
    res = CliRunner().invoke(main, [str(a) for a in args])
    assert res.exit_code == 0, res.output + repr(res.exception)
    return res.stdout


@pytest.fixture(scope="module")
def eye(tmp_path_factory):
    folder = tmp_path_factory.mktemp("eye")
    return EYE.write(folder), folder


def _closure_lines(text: str) -> list[str]:
    """The lines that say which parameters break loop closure (not the counts' headlines)."""
    return [line for line in text.splitlines()
            if "break loop closure" in line and "not identifiable" in line
            and not line.startswith("solver:")]  # fmt: skip


def test_info_says_the_breaking_parameters_in_one_line(eye):
    model, _ = eye
    out = _run("info", model, "--preset", "full")
    lines = _closure_lines(out)
    assert len(lines) == 1, lines
    assert lines[0].strip().startswith("55 parameters break loop closure in 2 loops")
    for words in ("loop wrist2↔seat2: 20 at 4 joints (base2.{tx ty tz rx ry}",
                  "loop wrist3↔seat3: 20 at 4 joints (base3.{tx ty tz rx ry}",
                  "shared by both loops: 15 at 3 joints (base1.{tx ty tz rx ry}"):  # fmt: skip
        assert words in lines[0]
    assert lines[0].endswith("and 1 more joint)")


def test_the_loops_are_the_tree_paths_between_the_closure_frames(eye):
    model, _ = eye
    mech = load_mechanism(model)
    params = parameters(mech, "full")
    loops = {label: {params.parameters[k].joint for k in on}
             for label, on in closure_loops(mech, params)}  # fmt: skip
    leg1 = {"base1", "elbow1", "wrist1"}  # the platform hangs on leg 1 in the tree
    assert loops == {"wrist2↔seat2": leg1 | {"base2", "elbow2", "wrist2", "seat2"},
                     "wrist3↔seat3": leg1 | {"base3", "elbow3", "wrist3", "seat3"}}  # fmt: skip


def test_calibrate_full_says_them_in_one_line_and_keeps_every_name(eye):
    model, folder = eye
    data = folder / "m.csv"
    _run("simulate", model, "--random", 20, "--noise", "0,0", "--out", data)
    out = _run("calibrate", model, "--data", data, "--params", "full", "--out", folder / "cal")
    lines = _closure_lines(out)
    assert len(lines) == 1, lines
    assert "55 parameters break loop closure in 2 loops" in lines[0]
    report = (folder / "cal" / "report.txt").read_text(encoding="utf-8")
    assert _closure_lines(report) == lines
    doc = json.loads((folder / "cal" / "identification.json").read_text(encoding="utf-8"))
    names = doc["identifiability"]["breaks_closure"]
    assert len(names) == 55 and len(set(names)) == 55
    assert {"base1.tx", "wrist3.ry", "seat3.rz"} & set(names) == {"base1.tx", "wrist3.ry"}

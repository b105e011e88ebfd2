"""Issue 38's marker route and messages, re-attacked with shapes the first tests did not have.

One simulated UR5 marker table (the fixture of ``test_marker_guards``), then per class:

* 3 — the marker route's guards: a link moved by one joint (an ``IndexError``
  traceback: pinocchio's (6,) Jacobian), every row at one joint reading and a marker
  on the axis of the only joint moving it ("points_local: … collinear"), one 9 km cell
  (diagnosed as micrometres read as millimetres), ``--root`` named as "the robot's root";
* 10 — messages: one-word joint units that are no unit (taken as a length and ignored),
  ``import-sockets`` naming ``--delimiter`` / ``--decimal``, options it does not have.

Further, messages: a directory whose files disagree shown with numpy reprs, a frame no
joint moves ("zero-size array to reduction"). Every refusal is one line naming its
error class, nothing written.
"""

from __future__ import annotations

import pytest
from click.testing import CliRunner

from pincal.cli import main
from tests.cli.test_marker_guards import LINK, _calibrate, _refused, _write
from tests.cli.test_marker_guards import table as table  # the module's fixture

JOINTS = ("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint",
          "wrist_2_joint", "wrist_3_joint")  # fmt: skip


def _one_reading(rows):
    first = rows[0].split(",")[3:]
    return [",".join(r.split(",")[:3] + first) for r in rows]


def _wild_cell(rows):
    cells = rows[5].split(",")
    cells[1] = "9e6"  # mm: 9 km, inside the coordinate bound
    return [*rows[:5], ",".join(cells), *rows[6:]]


@pytest.mark.parametrize("case, edit, extra, kind, words", [
    ("one joint", None, ["--link", "shoulder_link"], "UnidentifiableError",
     ["'shoulder_link'", "collinear", "shoulder_pan_joint", "--marker X,Y,Z"]),
    ("one reading", _one_reading, [], "UnidentifiableError",
     ["every row has the same joint readings", repr(LINK)]),
    ("wild cell", _wild_cell, [], "BadValueError", ["line 7", "9e+03 m", "mistyped"]),
    ("root", None, ["--root", "tool0"], "MobilityError",
     ["between the chain's start 'tool0' and link"]),
])  # fmt: skip
def test_the_marker_route_refuses_in_one_line(tmp_path, table, case, edit, extra, kind, words):
    title, rows, *_ = table
    path = _write(tmp_path / "m.csv", title, edit(rows) if edit else rows)
    link = [] if "--link" in extra else ["--link", LINK]
    args = ["calibrate", "ur5", "--data", path, "--length-unit", "mm", "--out",
            tmp_path / "cal", *link, *extra]  # fmt: skip
    r = CliRunner().invoke(main, [str(a) for a in args])
    line = _refused(r, tmp_path, kind, *words)
    assert "Traceback" not in r.output and "um read as" not in line, r.output


@pytest.mark.parametrize("units, words", [
    ("furlong", ["'furlong' is neither an angle unit", "nor a length unit"]),
    ("angle=deg length=inch", ["length='inch': not a length unit", "m, mm, um"]),
])  # fmt: skip
def test_joint_units_that_are_no_unit_are_refused(tmp_path, table, units, words):
    title, rows, *_ = table
    path = _write(tmp_path / "m.csv", title, rows, f"# joint_units: {units}\n")
    r = _calibrate(tmp_path, path, "--length-unit", "mm")
    _refused(r, tmp_path, "MeasurementFormatError", *words)


@pytest.mark.parametrize("body, words", [
    ("1,0.1,0.2,0.3,0.4,0.5,0.6\n2,0.1,0.2,0.3,0.4,0.5\n", ["6 fields", "one cell per title"]),
    ("1,0.1,0.2,0.3,0.4,0.5,abc\n2,0.1,0.2,0.3,0.4,0.5,0.6\n", ["'abc' is not a finite"]),
])  # fmt: skip
def test_import_sockets_names_no_option_it_lacks(tmp_path, body, words):
    path = tmp_path / "lab.csv"
    path.write_text("socket," + ",".join(JOINTS) + "\n" + body)
    out = tmp_path / "s.csv"
    r = CliRunner().invoke(main, ["import-sockets", str(path), "--model", "ur5", "--distance",
                                  "1,2,50,0.002", "--out", str(out)])  # fmt: skip
    assert r.exit_code == 1, r.output
    line = next(ln for ln in r.output.splitlines() if ln.startswith("pincal: error"))
    for w in [*words, "lab.csv line"]:
        assert w in line, line
    assert "--delimiter" not in line and "--decimal" not in line, line
    assert not out.exists()


def test_a_disagreeing_directory_shows_plain_numbers(tmp_path, table):
    """An edited calibration.json value: the refusal shows 0.5…, not np.float64(0.5…)."""
    import json

    path = _write(tmp_path / "m.csv", *table[:2])
    assert _calibrate(tmp_path, path, "--length-unit", "mm", "--prior", "none").exit_code == 0
    manifest = tmp_path / "cal" / "calibration.json"
    doc = json.loads(manifest.read_text())
    doc["parameters"][0]["value"] += 0.5
    manifest.write_text(json.dumps(doc))
    r = CliRunner().invoke(main, ["validate", str(tmp_path / "cal"), "--data", str(path)])
    assert r.exit_code == 1, r.output
    line = next(ln for ln in r.output.splitlines() if ln.startswith("pincal: error"))
    assert "CalibrationDirectoryError" in line and "disagree" in line, line
    assert "np." not in line, line
    shown = float(line.split(" is ")[1].split()[0])
    assert shown == pytest.approx(doc["parameters"][0]["value"], rel=1e-12)


@pytest.mark.parametrize("args", [
    ["info", "ur5", "--frame", "base_link"],
    ["poses", "ur5", "--frame", "base_link", "--count", "5"],
    ["info", "ur5", "--lock", ",".join(f"{j}=0" for j in JOINTS)],
])  # fmt: skip
def test_a_frame_nothing_moves_is_a_mobility_error(tmp_path, args):
    """It was "ValueError: zero-size array to reduction operation maximum …"."""
    extra = ["--out", str(tmp_path / "p.csv")] if args[0] == "poses" else []
    r = CliRunner().invoke(main, [*args, *extra])
    assert r.exit_code == 1, r.output
    line = next(ln for ln in r.output.splitlines() if ln.startswith("pincal: error"))
    assert line.startswith("pincal: error: MobilityError: nothing moves frame"), line
    assert "lock fewer joints" in line and "zero-size" not in line, line
    assert not (tmp_path / "p.csv").exists()


def _home_lines(*args: str) -> tuple[str, str]:
    r = CliRunner().invoke(main, ["info", "ur5", "--frame", LINK, *args])
    assert r.exit_code == 0, r.output
    home = next(ln for ln in r.output.splitlines() if "home (searched)" in ln)
    locked = next((ln for ln in r.output.splitlines() if "locked:" in ln), "")
    return home.split("(no SRDF")[0].strip(), locked.strip()


@pytest.mark.parametrize("lock, value", [
    ("elbow_joint=home", "elbow_joint = -0.785398"),  # it was 0: 'home' was q = 0 here
    ("wrist_2_joint=0", "wrist_2_joint = 0"),  # the others' home was searched again
])  # fmt: skip
def test_a_lock_does_not_move_home(lock, value):
    """One home (issue 38 item 4): with --lock, info prints the home it prints without,
    and 'JOINT=home' locks the joint at that home (it was q = 0: elbow 0, not −45°)."""
    free, _ = _home_lines()
    home, locked = _home_lines("--lock", lock)
    assert "elbow_joint = -45°" in free, free
    assert home == free, (home, free)
    assert value in locked, locked

"""The marker route's guards, as strict as the pose route's (issue 38, item 3; 35's headers).

One simulated UR5 table (marker on wrist_3_link, positions in mm, joints in rad), then
each case a lab's export or a user's slip produces: a 1e300 cell (it hung the
closed-form registration), two columns with one title, ``--noise`` (it was ignored), a
unit in the title (ignored), millimetres read as metres (diagnosed as "no common
unit"), a link nothing moves ("cannot reshape array of size 0"), an export's preamble
and a title line shifted against its data, more rows than the pose route fits, and
readings relative to home (home was q = 0 here, the searched home in ``pincal info``).
Every refusal is one line naming its error class, before any fit, nothing written.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.cli._limits import MAX_POSES
from pincal.io import read_marker_data
from pincal.measure import MarkerSetup, marker_mechanism
from pincal.model import BASE_JOINT, TOOL_JOINT, load_mechanism, sample_actuators, with_joint_origin

T_TRUE = pin.SE3(pin.rpy.rpyToMatrix(0.1, -0.2, 0.7), np.array([1.2, -0.4, 0.3]))
MARKER = np.array([0.03, -0.05, 0.12])
LINK = "wrist_3_link"


@pytest.fixture(scope="module")
def table():
    """(title line, data lines, q (n, 6) [rad], positions (n, 3) [m]) of 30 poses."""
    mech = marker_mechanism("ur5", MarkerSetup(LINK))
    actual = with_joint_origin(mech, BASE_JOINT, T_TRUE)
    actual = with_joint_origin(actual, TOOL_JOINT, pin.SE3(np.eye(3), MARKER))
    q = sample_actuators(mech, 30, np.random.default_rng(1))
    P = np.array([actual.frame_placement(c).translation for c in actual.configurations(q)])
    P += np.random.default_rng(2).normal(0, 2e-5, P.shape)
    title = ",".join(["x", "y", "z", *mech.actuated])
    rows = [",".join(f"{v:.6f}" for v in P[i] * 1e3) + "," + ",".join(f"{v:.9f}" for v in q[i])
            for i in range(len(q))]  # fmt: skip
    return title, rows, q, P


def _write(path, title, rows, head=""):
    path.write_text(head + title + "\n" + "\n".join(rows) + "\n")
    return path


def _calibrate(tmp_path, data, *extra):
    args = ["calibrate", "ur5", "--link", LINK, "--data", data, "--out", tmp_path / "cal", *extra]
    r = CliRunner().invoke(main, [str(a) for a in args])
    return r


def _refused(r, tmp_path, kind: str, *words: str) -> str:
    assert r.exit_code != 0, r.output
    line = next(ln for ln in r.output.splitlines() if ln.startswith(("pincal: error", "Error")))
    assert kind in line, r.output
    for w in words:
        assert w in line, line
    assert not (tmp_path / "cal").exists()
    return line


def test_a_huge_coordinate_is_named_not_registered(tmp_path, table):
    title, rows, *_ = table
    cells = rows[3].split(",")
    cells[0] = "1e300"
    bad = [*rows[:3], ",".join(cells), *rows[4:]]
    r = _calibrate(tmp_path, _write(tmp_path / "m.csv", title, bad), "--length-unit", "mm")
    _refused(r, tmp_path, "BadValueError", "line 5", "'x'", "10 km")


def test_two_columns_with_one_title_are_refused_naming_both(tmp_path, table):
    title, rows, *_ = table
    r = _calibrate(tmp_path, _write(tmp_path / "m.csv", title + ",X", [r + ",5" for r in rows]),
                   "--length-unit", "mm")  # fmt: skip
    _refused(r, tmp_path, "ColumnError", "columns 1 ('x') and 10 ('X')")


def test_an_unused_repeated_title_is_not_a_problem(tmp_path, table):
    title, rows, _q, P = table
    path = _write(tmp_path / "m.csv", title + ",frame,frame", [r + ",1,2" for r in rows])
    setup = MarkerSetup(LINK, length_unit="mm")
    read = read_marker_data(path, marker_mechanism("ur5", setup), setup)
    assert np.allclose(read.sets[0].positions, P, atol=1e-9)


def test_noise_is_refused_on_the_marker_route(tmp_path, table):
    path = _write(tmp_path / "m.csv", *table[:2])
    r = _calibrate(tmp_path, path, "--length-unit", "mm", "--noise", "0.01,0.1")
    _refused(r, tmp_path, "--noise", "drop --noise")


def test_the_title_unit_is_read(tmp_path, table):
    title, rows, _q, P = table
    titled = title.replace("x,y,z", "x [mm],y [mm],z [mm]", 1)
    path = _write(tmp_path / "m.csv", titled, rows)
    setup = MarkerSetup(LINK)  # declared m: the titles say mm, and win
    read = read_marker_data(path, marker_mechanism("ur5", setup), setup)
    assert np.allclose(read.sets[0].positions, P, atol=1e-9)
    assert any("read in their title's unit" in n for n in read.notes), read.notes


def test_millimetres_read_as_metres_name_the_unit(tmp_path, table):
    r = _calibrate(tmp_path, _write(tmp_path / "m.csv", *table[:2]))
    _refused(r, tmp_path, "UnitMismatchError", "mm read as m", "--length-unit mm")


@pytest.mark.parametrize("link, lock", [
    ("base_link", None),
    ("wrist_1_link", "shoulder_pan_joint=0,shoulder_lift_joint=0,elbow_joint=0,wrist_1_joint=0"),
])  # fmt: skip
def test_nothing_moving_the_marker_is_said(tmp_path, table, link, lock):
    path = _write(tmp_path / "m.csv", *table[:2])
    args = ["calibrate", "ur5", "--link", link, "--data", path, "--length-unit", "mm",
            "--out", tmp_path / "cal", *(["--lock", lock] if lock else [])]  # fmt: skip
    r = CliRunner().invoke(main, [str(a) for a in args])
    _refused(r, tmp_path, "MobilityError", "nothing moves the marker", repr(link))


def test_a_preamble_before_the_title_line_is_skipped_and_said(tmp_path, table):
    title, rows, q, P = table
    head = "Format Version,1.23,Take Name,session 1\nCapture Frame Rate,120\n\n"
    path = _write(tmp_path / "m.csv", title, rows, head)
    setup = MarkerSetup(LINK, length_unit="mm")
    read = read_marker_data(path, marker_mechanism("ur5", setup), setup)
    assert np.allclose(read.sets[0].positions, P, atol=1e-9)
    assert np.allclose(read.sets[0].q_act, q, atol=1e-8)
    assert any("line(s) 1–2 before the title line skipped" in n for n in read.notes), read.notes


def test_a_title_line_shifted_against_its_data_is_named(tmp_path, table):
    title, rows, *_ = table
    path = _write(tmp_path / "m.csv", title, [f"{i},0.1,a,b," + r for i, r in enumerate(rows)])
    r = _calibrate(tmp_path, path, "--length-unit", "mm")
    line = _refused(r, tmp_path, "ShiftedHeaderError", "13 cells under the 9 titles",
                    "4 column(s) without a title")  # fmt: skip
    assert "--delimiter" not in line  # calibrate has no such option


def test_more_rows_than_the_pose_route_fits_are_refused_without_yes(tmp_path, table):
    title, rows, *_ = table
    many = (rows * (MAX_POSES // len(rows) + 1))[: MAX_POSES + 1]
    r = _calibrate(tmp_path, _write(tmp_path / "m.csv", title, many), "--length-unit", "mm")
    _refused(r, tmp_path, "InputLimitError", f"{MAX_POSES + 1} poses", "--yes")
    # select-model fits every candidate k + 1 times: the same bound (it had none)
    args = ["select-model", "ur5", "--link", LINK, "--data", tmp_path / "m.csv",
            "--length-unit", "mm", "--models", "geometric"]  # fmt: skip
    r = CliRunner().invoke(main, [str(a) for a in args])
    line = _refused(r, tmp_path, "InputLimitError", f"{MAX_POSES + 1} poses", "--yes")
    assert " 0 s " not in line  # no cost estimate without a parameter count


def test_readings_relative_to_home_use_the_home_info_prints(tmp_path, table):
    """UR5 has no SRDF pose: `pincal info ur5 --frame wrist_3_link` searches a home
    (elbow −45°, wrist 2 +15°); the marker route reads 'joint_reference: home' from it."""
    title, rows, q, _P = table
    home = load_mechanism("ur5", LINK)
    h = home.actuators_of(home.q_home)
    assert np.abs(h).max() > 0.1  # a searched home, not q = 0
    rel = q - h
    lines = [",".join(r.split(",")[:3] + [f"{v:.9f}" for v in rel[i]]) for i, r in enumerate(rows)]
    path = _write(tmp_path / "m.csv", title, lines, "# joint_reference: home\n")
    setup = MarkerSetup(LINK, length_unit="mm")
    read = read_marker_data(path, marker_mechanism("ur5", setup), setup)
    assert np.allclose(read.sets[0].q_act, q, atol=1e-8)
    note = next(n for n in read.notes if "joint_reference: home" in n)
    assert f"elbow_joint = {h[2]:.6g}" in note


def test_fewer_poses_than_folds_are_named_as_such(tmp_path, table):
    """Two rows: the route's own 5-fold judgement needs 5 poses (it said "cross-validation
    needs 2 ≤ K ≤ 2 poses, got K = 5", a K the user never gave)."""
    title, rows, *_ = table
    r = _calibrate(tmp_path, _write(tmp_path / "m.csv", title, rows[:2]), "--length-unit", "mm")
    _refused(r, tmp_path, "TooFewPosesError", "2 poses", "5-fold", "at least 5")


def test_a_missing_marker_column_names_the_option_and_the_triples_found(tmp_path, table):
    """Columns not named x, y, z: the refusal suggests --marker-columns with the file's
    first x/y/z-like triple (titles without their unit), lists every such triple and the
    columns; the suggestion, given, reads the table."""
    title, rows, *_ = table
    titled = title.replace("x,y,z", "Hand_X [mm],Hand_Y [mm],Hand_Z [mm]", 1)
    titled += ",ref_x,ref_y,ref_z"
    path = _write(tmp_path / "m.csv", titled, [r + ",1,2,3" for r in rows])
    r = _calibrate(tmp_path, path)
    line = _refused(r, tmp_path, "ColumnError", "no marker column 'x'",
                    "--marker-columns Hand_X,Hand_Y,Hand_Z",
                    "Hand_X,Hand_Y,Hand_Z ref_x,ref_y,ref_z",
                    "'Hand_X [mm]'", "'shoulder_pan_joint'")  # fmt: skip
    assert len(r.output.strip().splitlines()) == 1, r.output
    suggested = line.split("--marker-columns ")[1].split()[0]
    ok = _calibrate(tmp_path, path, "--marker-columns", suggested, "--prior", "none")
    assert ok.exit_code == 0, ok.output


def test_a_unit_in_parentheses_is_suggested_as_the_length_unit(tmp_path, table):
    """'x (mm)' titles are read without a unit: the --marker-columns suggestion adds
    --length-unit mm (alone it would read the millimetres as metres), and given, it fits."""
    title, rows, *_ = table
    titled = title.replace("x,y,z", "Hand_X (mm),Hand_Y (mm),Hand_Z (mm)", 1)
    path = _write(tmp_path / "m.csv", titled, rows)
    r = _calibrate(tmp_path, path)
    cols = "Hand_X (mm),Hand_Y (mm),Hand_Z (mm)"
    _refused(r, tmp_path, "ColumnError", f"--marker-columns {cols} --length-unit mm")
    ok = _calibrate(tmp_path, path, "--marker-columns", cols, "--length-unit", "mm",
                    "--prior", "none")  # fmt: skip
    assert ok.exit_code == 0, ok.output

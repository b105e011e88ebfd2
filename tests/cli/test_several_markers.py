"""Several markers on one link from the CLI: fitted together, copies used once.

A simulated UR5 measured by a capture system 1.2 m away (turned 40°), with two distinct
markers on wrist_3_link (truth known) and the arm's own geometric errors (±1 mm /
mrad); the table also carries a copy of marker 2 under other names, as mocap exports do.
"""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.identification import is_registration
from pincal.measure import MarkerSetup, marker_frame, marker_mechanism
from pincal.model import BASE_JOINT, TOOL_JOINT, parameters, sample_actuators, with_joint_origin

T_TRUE = pin.SE3(pin.rpy.rpyToMatrix(0.1, -0.2, 0.7), np.array([1.2, -0.4, 0.3]))
MARKERS = (np.array([0.03, -0.05, 0.12]), np.array([-0.06, 0.04, 0.08]))
SETUP = MarkerSetup("wrist_3_link", more_columns=(("x2", "y2", "z2"),))


def _run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def _actual():
    mech = marker_mechanism("ur5", SETUP)
    actual = with_joint_origin(mech, BASE_JOINT, T_TRUE)
    actual = with_joint_origin(actual, TOOL_JOINT, pin.SE3(np.eye(3), MARKERS[0]))
    actual = with_joint_origin(actual, marker_frame(1)[0], pin.SE3(np.eye(3), MARKERS[1]))
    params = parameters(actual, "chain")
    x = np.random.default_rng(5).uniform(-1e-3, 1e-3, len(params))
    return mech, params.apply(actual, np.where([is_registration(n) for n in params.names], 0, x))


def _points(mech, q, k: int) -> np.ndarray:
    frame = marker_frame(k)[1]
    return np.array([mech.frame_placement(c, frame).translation for c in mech.configurations(q)])


def _table(path, actual, q, noise: float, seed: int) -> None:
    """Markers 1, 2 and a copy of 2 (x3..z3) [mm], then the joints [rad]."""
    rng = np.random.default_rng(seed)
    P = [_points(actual, q, k) + rng.normal(0, noise, (len(q), 3)) for k in range(2)]
    cols = ["x1", "y1", "z1", "x2", "y2", "z2", "x3", "y3", "z3", *actual.actuated]
    rows = [[*(P[0][i] * 1e3), *(P[1][i] * 1e3), *(P[1][i] * 1e3), *q[i]] for i in range(len(q))]
    text = ",".join(cols) + "\n" + "".join(",".join(repr(float(v)) for v in r) + "\n" for r in rows)
    path.write_text(text)


def test_two_markers_fitted_together_recover_the_truth(tmp_path):
    mech, actual = _actual()
    q = sample_actuators(mech, 30, np.random.default_rng(1))
    _table(tmp_path / "m.csv", actual, q, 2e-5, 2)
    r = _run("calibrate", "ur5", "--link", "wrist_3_link", "--data", tmp_path / "m.csv",
             "--marker-columns", "x1,y1,z1;x2,y2,z2", "--marker-columns", "x3,y3,z3",
             "--length-unit", "mm", "--out", tmp_path / "cal", "--json")  # fmt: skip
    assert r.exit_code == 0, r.output
    # the copy is found, said, and not fitted as a third marker
    assert "columns x3,y3,z3 repeat x2,y2,z2 value for value" in r.stderr
    doc = json.loads(r.stdout.splitlines()[-1])["markers"]
    assert doc["more_columns"] == [["x2", "y2", "z2"]]
    assert any("repeat x2,y2,z2" in n for n in doc["notes"])
    assert len(doc["identified"]["more_markers_mm"]) == 1
    from pincal.io import read_calibration

    cal = read_calibration(tmp_path / "cal").calibrated()
    # both markers predicted at unseen poses at the noise level (the arm errors move them
    # by millimetres), and the distance between the markers recovered
    q_new = sample_actuators(mech, 30, np.random.default_rng(9))
    for k in range(2):
        err = np.linalg.norm(_points(cal, q_new, k) - _points(actual, q_new, k), axis=1)
        assert np.sqrt(np.mean(err**2)) < 1e-4, (k, err.max())
    joints = cal.tree.joints
    gap = joints[marker_frame(1)[0]].origin.translation - joints[TOOL_JOINT].origin.translation
    assert abs(np.linalg.norm(gap) - np.linalg.norm(MARKERS[1] - MARKERS[0])) < 1e-4
    out = _run("validate", tmp_path / "cal", "--cv", 3, "--json")
    assert out.exit_code == 0, out.output
    cv = json.loads(out.stdout)["cv"]
    assert cv["held_out_rms_mm"] < 0.1 < cv["baseline"]["held_out_rms_mm"]
    # held-out poses: every marker judged (the second in its own frame)
    _table(tmp_path / "held.csv", actual, q_new, 2e-5, 8)
    out = _run("validate", tmp_path / "cal", "--data", tmp_path / "held.csv", "--json")
    assert out.exit_code == 0, out.output
    doc = json.loads(out.stdout)
    assert doc["after"]["rms_position_mm"] < 0.1
    (second,) = doc["more_markers"]
    assert second["columns"] == ["x2", "y2", "z2"]
    assert second["after_rms_position_mm"] < 0.1 < second["before_rms_position_mm"]
    text = _run("validate", tmp_path / "cal", "--data", tmp_path / "held.csv").stdout
    assert "marker x2 y2 z2: position RMS nominal" in text


def test_registration_only_with_two_markers_shows_the_arm_errors(tmp_path):
    """The instrument frame and both offsets alone cannot absorb the arm's errors: the
    cross-validated error over both markers shows them."""
    mech, actual = _actual()
    q = sample_actuators(mech, 24, np.random.default_rng(3))
    _table(tmp_path / "m.csv", actual, q, 2e-5, 4)
    base = ["calibrate", "ur5", "--link", "wrist_3_link", "--data", tmp_path / "m.csv",
            "--length-unit", "mm"]  # fmt: skip
    assert _run(*base, "--marker-columns", "x1,y1,z1;x2,y2,z2", "--out", tmp_path / "two",
                "--params", "base_tool").exit_code == 0  # fmt: skip
    two = json.loads(_run("validate", tmp_path / "two", "--cv", 3, "--json").stdout)["cv"]
    # base_tool cannot absorb the arm errors: both markers show them, on every fold
    assert two["held_out_rms_mm"] > 0.2
    assert two["baseline"]["model"] == "registration only"


def test_marker_option_and_campaign_errors_are_named(tmp_path):
    mech, actual = _actual()
    q = sample_actuators(mech, 10, np.random.default_rng(3))
    _table(tmp_path / "m.csv", actual, q, 2e-5, 4)
    base = ["calibrate", "ur5", "--link", "wrist_3_link", "--data", tmp_path / "m.csv",
            "--out", tmp_path / "c"]  # fmt: skip
    r = _run(*base, "--marker-columns", "x1,y1,z1;x2,y2")
    assert r.exit_code != 0 and "three columns per marker" in r.output
    r = _run(*base, "--marker-columns", "x1,y1,z1;x1,y1,z1")
    assert r.exit_code != 0 and "named twice" in r.output
    r = _run(*base, "--marker-columns", "x1,y1,z1;x2,y2,z2", "--marker", "1,2,3")
    assert r.exit_code != 0 and "--marker unknown" in r.output
    r = _run(*base, "--marker-columns", "x1,y1,z1;x9,y9,z9")
    assert r.exit_code != 0 and "x9" in r.output
    text = (
        "model: ur5\npreset: chain\nout: cal\n"
        "measurements: {source: file, file: m.csv}\n"
        "markers: {link: wrist_3_link, columns: [x1, y1, z1], more_columns: [[x2, y2, z2]], "
        "length_unit: mm}\n"
        "validation: {source: none}\nreport: false\n"
    )
    (tmp_path / "c.yaml").write_text(text)
    r = _run("run", tmp_path / "c.yaml")
    assert r.exit_code == 0, r.output
    cal = json.loads((tmp_path / "cal" / "calibration.json").read_text())
    assert cal["markers"]["more_columns"] == [["x2", "y2", "z2"]]
    (tmp_path / "bad.yaml").write_text(text.replace("[[x2, y2, z2]]", "[[x2, y2]]"))
    bad = _run("run", tmp_path / "bad.yaml", "--dry-run")
    assert bad.exit_code != 0 and "markers.more_columns[0]" in bad.output


@pytest.mark.slow  # ~45 s (TIAGo); two markers are checked fast above
def test_tiago_file_two_markers_and_its_copies(tmp_path):
    """The real TIAGo export: markers 1 and 2 fitted together; columns 4 found to repeat 3."""
    from pathlib import Path

    data = Path(__file__).resolve().parents[2] / "docs/examples/tiago-mocap/measurements.csv"
    r = _run("calibrate", "tiago", "--link", "arm_7_link", "--data", data,
             "--marker-columns", "x1,y1,z1;x2,y2,z2;x3,y3,z3;x4,y4,z4",
             "--out", tmp_path / "cal", "--json")  # fmt: skip
    assert r.exit_code == 0, r.output
    assert "columns x4,y4,z4 repeat x3,y3,z3 value for value" in r.stderr
    doc = json.loads(r.stdout.splitlines()[-1])
    assert doc["markers"]["more_columns"] == [["x2", "y2", "z2"], ["x3", "y3", "z3"]]
    res = doc["residuals"]
    assert res["after"]["rms_position_mm"] < res["before"]["rms_position_mm"]
    # the markers' fitted offsets on the link are as far apart as the capture saw them
    table = np.genfromtxt(data, delimiter=",", names=True)
    seen = [np.c_[table[f"x{k}"], table[f"y{k}"], table[f"z{k}"]] * 1e3 for k in (1, 2)]
    seen_gap = float(np.mean(np.linalg.norm(seen[1] - seen[0], axis=1)))  # 158.24 mm
    ident = doc["markers"]["identified"]
    gap = np.linalg.norm(np.subtract(ident["more_markers_mm"][0], ident["marker_mm"]))
    assert abs(gap - seen_gap) < 1.0, (gap, seen_gap)

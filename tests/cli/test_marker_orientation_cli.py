"""A 6-D marker body on the command line: calibrate, validate --cv --json, bad columns.

The table is simulated with Pinocchio alone (perturbed UR5 joint placements;
:mod:`tests.identification.marker_body_sim`), noise 0.05 mm per coordinate and
0.2 mrad per rotation axis: a rotation error angle of 0.35 mrad RMS.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from pincal.cli import main
from tests.identification.marker_body_sim import body_poses, write_body_table

BODY = ("--link", "wrist_3_link", "--length-unit", "mm", "--orientation-columns",
        "roll,pitch,yaw", "--orientation", "rpy-deg", "--prior", "none")  # fmt: skip


def _run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.fixture(scope="module")
def table(tmp_path_factory) -> Path:
    q, P, R = body_poses(40, 3)
    return write_body_table(tmp_path_factory.mktemp("body") / "body.csv", q, P, R)


def test_calibrate_and_cv_report_position_and_orientation(tmp_path, table):
    r = _run("calibrate", "ur5", "--data", table, *BODY, "--out", tmp_path / "cal")
    assert r.exit_code == 0, r.output
    assert "marker body on wrist_3_link" in r.output and "identified body rotation" in r.output
    out = _run("validate", tmp_path / "cal", "--cv", 5, "--json")
    assert out.exit_code == 0, out.output
    cv = json.loads(out.output)["cv"]
    base = cv["baseline"]
    assert base["model"] == "registration only" and cv["beats_baseline"]
    # the angle of 0.2 mrad per axis: 0.35 mrad RMS; fold fits use up 31 of 240 equations
    assert 0.25 < cv["held_out_orientation_rms_mrad"] < 0.5
    assert cv["fit_orientation_rms_mrad"] < cv["held_out_orientation_rms_mrad"]
    # the robot's ±0.5 mm / mrad errors left in the registration-only model
    assert base["held_out_orientation_rms_mrad"] > 3 * cv["held_out_orientation_rms_mrad"]
    assert 0.07 < cv["held_out_rms_mm"] < 0.13 and base["held_out_rms_mm"] > 0.5
    text = _run("validate", tmp_path / "cal", "--cv", 5)
    assert "rotation angle [mrad]" in text.output


def test_the_same_table_read_for_positions_only_reports_positions(tmp_path, table):
    r = _run("calibrate", "ur5", "--data", table, "--link", "wrist_3_link", "--length-unit",
             "mm", "--prior", "none", "--out", tmp_path / "cal")  # fmt: skip
    assert r.exit_code == 0, r.output
    assert "marker on wrist_3_link" in r.output
    assert "body rotation" not in r.output and "rotation angle" not in r.output
    cv = json.loads(_run("validate", tmp_path / "cal", "--cv", 3, "--json").output)["cv"]
    assert not any("orientation" in k for k in (*cv, *cv["baseline"]))


def _edit(table: Path, tmp: Path, line: int, column: str, value: str) -> Path:
    rows = [r.split(",") for r in table.read_text().splitlines()]
    rows[line - 1][rows[0].index(column)] = value
    out = tmp / "edited.csv"
    out.write_text("\n".join(",".join(r) for r in rows) + "\n")
    return out


def _quaternion_table(table: Path, tmp: Path, scale: float) -> Path:
    """The table with its rpy replaced by quaternions w x y z (times ``scale`` on line 5)."""
    import pinocchio as pin

    rows = [r.split(",") for r in table.read_text().splitlines()]
    out = [",".join([*rows[0][:9], "qw", "qx", "qy", "qz"])]
    for i, r in enumerate(rows[1:]):
        R = pin.rpy.rpyToMatrix(*np.radians([float(v) for v in r[9:12]]))
        x, y, z, w = pin.Quaternion(R).coeffs() * (scale if i == 3 else 1.0)
        out.append(",".join(r[:9] + [repr(float(v)) for v in (w, x, y, z)]))
    path = tmp / f"quat{scale:g}.csv"
    path.write_text("\n".join(out) + "\n")
    return path


def test_bad_orientation_columns_are_named(tmp_path, table):
    def calibrate(data, *opts):
        args = ["--link", "wrist_3_link", "--length-unit", "mm", *opts]
        return _run("calibrate", "ur5", "--data", data, *args, "--out", tmp_path / "c")

    bad = calibrate(table, "--orientation-columns", "roll,pitch,yawn", "--orientation", "rpy-deg")
    assert bad.exit_code != 0 and "no orientation column 'yawn'" in bad.output
    bad = calibrate(_edit(table, tmp_path, 4, "pitch", "inf"), "--orientation-columns",
                    "roll,pitch,yaw", "--orientation", "rpy-deg")  # fmt: skip
    assert bad.exit_code != 0 and "line 4" in bad.output and "'pitch'" in bad.output
    bad = calibrate(table, "--orientation-columns", "roll,pitch,yaw", "--orientation", "rpy-rad")
    assert bad.exit_code != 0 and "beyond a turn" in bad.output and "rpy-rad" in bad.output
    bad = calibrate(table, "--orientation-columns", "roll,pitch,yaw")
    assert bad.exit_code != 0 and "together" in bad.output
    bad = calibrate(table, "--orientation-columns", "roll,pitch", "--orientation", "rpy-deg")
    assert bad.exit_code != 0 and "needs 3 distinct columns" in bad.output
    bad = calibrate(table, "--orientation-columns", "roll,pitch,yaw", "--orientation", "zyx")
    assert bad.exit_code != 0 and "--orientation" in bad.output
    quat = ("--orientation-columns", "qw,qx,qy,qz", "--orientation", "quat-wxyz")
    bad = calibrate(_quaternion_table(table, tmp_path, 1.01), *quat)
    assert bad.exit_code != 0 and "line 5" in bad.output and "quaternion norm 1.01" in bad.output
    bad = _run("calibrate", "ur5", "--data", table, "--orientation", "rpy-deg", "--out",
               tmp_path / "c")  # fmt: skip
    assert bad.exit_code != 0 and "apply to marker tables" in bad.output
    assert not (tmp_path / "c").exists()


def _parameters(output: str) -> dict[str, float]:
    doc = json.loads(next(ln for ln in output.splitlines() if ln.startswith("{")))
    return {e["name"]: e["value"] for e in doc["parameters"]}


def test_a_quaternion_table_calibrates_like_the_rpy_one(tmp_path, table):
    path = _quaternion_table(table, tmp_path, 1.0)
    quat = ("--orientation-columns", "qw,qx,qy,qz", "--orientation", "quat-wxyz")
    a = _run("calibrate", "ur5", "--data", path, *BODY[:4], *quat, "--prior", "none", "--json",
             "--out", tmp_path / "q")  # fmt: skip
    b = _run("calibrate", "ur5", "--data", table, *BODY, "--json", "--out", tmp_path / "r")
    assert a.exit_code == 0 and b.exit_code == 0, a.output + b.output
    va, vb = _parameters(a.output), _parameters(b.output)
    assert va.keys() == vb.keys()
    assert np.allclose(list(va.values()), list(vb.values()), atol=1e-9)
    # the order declared wrong (x y z w for w x y z): unit norm still, but far from the robot
    wrong = ("--orientation-columns", "qw,qx,qy,qz", "--orientation", "quat-xyzw")
    c = _run("calibrate", "ur5", "--data", path, *BODY[:4], *wrong, "--prior", "none",
             "--out", tmp_path / "w")  # fmt: skip
    assert "rotation angle RMS" in c.output and "--orientation" in c.output


def test_a_campaign_declares_the_orientation(tmp_path, table):
    text = (
        "model: ur5\npreset: chain\nout: cal\n"
        f"measurements: {{source: file, file: {table}}}\n"
        "markers: {link: wrist_3_link, length_unit: mm, orientation_columns: [roll, pitch, "
        "yaw], orientation: rpy-deg}\n"
        "validation: {source: none}\nreport: false\n"
    )
    (tmp_path / "c.yaml").write_text(text)
    r = _run("run", tmp_path / "c.yaml", "--dry-run")
    assert r.exit_code == 0, r.output
    assert "--orientation-columns roll,pitch,yaw --orientation rpy-deg" in r.output
    for old, new, said in (
        ("orientation: rpy-deg", "orientation: rpy-grad", "markers.orientation"),
        (", orientation: rpy-deg", "", "go together"),
        ("yaw]", "yaw, w]", "needs 3 orientation_columns"),
    ):
        (tmp_path / "bad.yaml").write_text(text.replace(old, new))
        bad = _run("run", tmp_path / "bad.yaml", "--dry-run")
        assert bad.exit_code != 0 and said in bad.output, bad.output


def test_validate_reuses_the_gates_cross_validation_and_weighs_both_blocks(tmp_path, table):
    """calibrate records its gate's CV; validate --cv reuses it, --refit gives the same."""
    r = _run("calibrate", "ur5", "--data", table, *BODY, "--json", "--out", tmp_path / "cal")
    assert r.exit_code == 0, r.output
    held = json.loads(r.output.splitlines()[-1])["quality"]["held_out"]
    reused = json.loads(_run("validate", tmp_path / "cal", "--cv", 5, "--json").output)["cv"]
    again = json.loads(
        _run("validate", tmp_path / "cal", "--cv", 5, "--refit", "--json").output
    )["cv"]
    assert reused["recorded_by_calibrate"] and "recorded_by_calibrate" not in again
    for key in ("held_out_rms_mm", "held_out_orientation_rms_mrad", "gain_whitened"):
        assert reused[key] == pytest.approx(again[key], rel=1e-9, abs=1e-12)
    assert reused["baseline"]["held_out_rms_mm"] == pytest.approx(
        again["baseline"]["held_out_rms_mm"], rel=1e-9
    )
    # the gate judged the same whitened gain, position and orientation together
    assert held["gain_whitened"] == pytest.approx(reused["gain_whitened"], rel=1e-12)
    assert set(held["whitened_by"]) == {"position_mm", "orientation_mrad"}
    assert reused["beats_baseline"] and "whitened" in reused["verdict"]
    other = json.loads(_run("validate", tmp_path / "cal", "--cv", 4, "--json").output)["cv"]
    assert "recorded_by_calibrate" not in other  # other folds: refitted

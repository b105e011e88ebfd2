"""A lab's plain CSV of ball-in-socket seatings, calibrated from a campaign file.

A simulated UR5 (seeded errors) seats its ball in two sockets 50 mm apart; the seatings
are rewritten as a lab would ship them: no pincal header, ``;`` delimiter, joints named
``Joint 1``…``Joint 6`` in degrees, the socket as a number 1/2, extra columns. A campaign's
``sockets`` section declares what the table lacks; ``pincal run`` then ``pincal validate
--cv 5`` must recover the plate's known distance on held-out seatings (≤ 0.2 mm, far
better than the nominal arm). Without the distance the scale is reported unidentifiable.
"""

from __future__ import annotations

import json
import math

import pytest
from click.testing import CliRunner

from pincal.cli import main

JOINTS = ("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint",
          "wrist_2_joint", "wrist_3_joint")  # fmt: skip
COLUMNS = "\n".join(f"    Joint {k}: {j}" for k, j in enumerate(JOINTS, start=1))


def _run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.fixture(scope="module")
def lab(tmp_path_factory):
    """(directory, lab table) of 40 simulated seatings, 20 per socket."""
    d = tmp_path_factory.mktemp("lab")
    s = d / "s.csv"
    r = _run("simulate", "ur5", "--random", "40", "--instrument", "socket",
             "--errors", "seed:3", "--seed", "1", "--out", s)  # fmt: skip
    assert r.exit_code == 0, r.output
    rows = [ln.split(",") for ln in s.read_text().splitlines() if not ln.startswith("#")]
    assert rows[0] == [*JOINTS, "socket"]
    out = ["sample;" + ";".join(f"Joint {k}" for k in range(1, 7)) + ";Hole;operator"]
    for i, row in enumerate(rows[1:]):
        deg = [f"{math.degrees(float(v)):.7f}" for v in row[:6]]
        out.append(";".join([str(i), *deg, {"A": "1", "B": "2"}[row[6]], "kim"]))
    table = d / "lab.csv"
    table.write_text("\n".join(out) + "\n")
    return d, table


def assert_clean_failure(res, words: str) -> None:
    """Refused in one ``pincal: error:`` line naming ``words`` (a model note may precede)."""
    assert res.exit_code == 1, res.output
    assert "Traceback" not in res.output, res.output
    last = res.stderr.strip().splitlines()[-1]
    assert last.startswith("pincal: error:") and words in last, res.stderr


def _campaign(d, table, out, extra=""):
    text = (
        f"model: ur5\nout: {out}\nmeasurements:\n  source: file\n  file: {table.name}\n"
        f"sockets:\n  column: hole\n  std: 0.01\n  joint_units: deg\n  columns:\n{COLUMNS}\n"
        f"{extra}validation:\n  source: none\n"
    )
    path = d / f"{out}.yaml"
    path.write_text(text)
    return path


def test_plain_table_campaign_recovers_the_known_distance(lab, tmp_path, monkeypatch):
    d, table = lab
    before = table.read_bytes()
    camp = _campaign(d, table, "cal", "  distances: [[1, 2, 50, 0.01]]\n")
    monkeypatch.chdir(d)
    r = _run("run", camp, "--out", "cal")  # a relative --out
    assert r.exit_code == 0, r.output
    assert table.read_bytes() == before  # the lab's file is only read
    monkeypatch.chdir(tmp_path)  # validate finds the imported table from anywhere
    v = _run("validate", d / "cal", "--cv", "5", "--json")
    assert v.exit_code == 0, v.output
    cv = json.loads(v.stdout)["cv"]
    assert cv["poses"] == 40
    assert cv["socket_distance_error_rms_mm"] <= 0.2
    base = cv["baseline"]["socket_distance_error_rms_mm"]
    assert cv["socket_distance_error_rms_mm"] < base / 5
    assert cv["held_out_rms_mm"] < cv["baseline"]["held_out_rms_mm"]


def test_plain_table_without_distance_says_the_scale_is_unidentifiable(lab):
    d, table = lab
    r = _run("run", _campaign(d, table, "nodist"))
    assert r.exit_code != 0
    assert "nothing measured fixes the length scale" in r.output, r.output
    assert "sockets.distances" in r.output
    assert not (d / "nodist" / "calibration.json").exists()


@pytest.mark.parametrize(
    ("options", "words"),
    [
        (["--socket-column", "socket"], "no socket column 'socket'"),
        (["--distance", "1,3,50,0.01"], "names socket(s) ['3']"),
        (["--distance", "1,2,-50,0.01"], "must be finite and > 0 [mm]"),
        (["--distance", "1,1,50,0.01"], "lab.csv: a known distance joins two sockets"),
        (["--columns", "Joint 1=shoulder_pan_joint"], "missing actuator columns"),
        (["--columns", "J1=shoulder_pan_joint"], "has no column 'J1'"),
        (["--columns", "Joint 1=shoulder_pan"], "does not actuate"),
    ],
)
def test_import_sockets_bad_declarations(lab, options, words):
    d, table = lab
    cols = ",".join(f"Joint {k}={j}" for k, j in enumerate(JOINTS, start=1))
    args = ["import-sockets", table, "--model", "ur5", "--socket-column", "hole",
            "--columns", cols, "--joint-units", "deg", "--out", d / "x.csv", *options]  # fmt: skip
    res = CliRunner().invoke(main, [str(a) for a in args])
    assert_clean_failure(res, words)
    assert not (d / "x.csv").exists()


def test_import_sockets_json_summary(lab, tmp_path):
    _, table = lab
    cols = ",".join(f"Joint {k}={j}" for k, j in enumerate(JOINTS, start=1))
    res = _run("import-sockets", table, "--model", "ur5", "--socket-column", "hole",
               "--columns", cols, "--joint-units", "deg", "--distance", "1,2,50,0.01",
               "--out", tmp_path / "s.csv", "--json")  # fmt: skip
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout)
    assert doc["seatings"] == 40 and doc["sockets"] == {"1": 20, "2": 20}
    assert doc["distances_mm"] == [["1", "2", 50.0, 0.01]]
    assert (tmp_path / "s.csv").read_text().startswith("# pincal sockets 1")


def test_import_sockets_single_socket(lab, tmp_path):
    _, table = lab
    one = tmp_path / "one.csv"
    one.write_text("".join(ln for ln in table.read_text().splitlines(True) if ";2;" not in ln))
    cols = ",".join(f"Joint {k}={j}" for k, j in enumerate(JOINTS, start=1))
    res = _run("import-sockets", one, "--model", "ur5", "--socket-column", "Hole",
               "--columns", cols, "--joint-units", "deg", "--out", tmp_path / "x.csv")  # fmt: skip
    assert_clean_failure(res, "every row names socket '1'")


@pytest.mark.parametrize(
    ("section", "words"),
    [
        ("sockets:\n  distances: [[1, 2, 50]]\n", "sockets.distances[0]"),
        ("sockets:\n  distances: [[1, 1, 50, 0.1]]\n", "joins two sockets"),
        ("sockets:\n  std: 0\n", "sockets.std must be > 0"),
        ("sockets:\n  colum: hole\n", "did you mean 'column'"),
    ],
)
def test_campaign_socket_section_checked(tmp_path, section, words):
    (tmp_path / "lab.csv").write_text("J1;hole\n0;1\n")
    path = tmp_path / "c.yaml"
    path.write_text(f"model: ur5\nmeasurements:\n  source: file\n  file: lab.csv\n{section}"
                    "validation:\n  source: none\n")  # fmt: skip
    res = _run("run", path, "--dry-run")
    assert_clean_failure(res, words)

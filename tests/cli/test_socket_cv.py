"""``pincal validate --cv`` of a ball-in-socket calibration: held-out socket distances.

A simulated UR5 (seeded errors) seats its ball in two sockets 50 mm apart. Every fold
refits machine, ball and socket centres without its seatings; the distance between the
mean predicted ball centres of each socket's held-out seatings must match the plate's
known distance far better than the nominal arm does. Without the known distance the
scale is unidentifiable, and both calibrate and validate say so.
"""

from __future__ import annotations

import json

from click.testing import CliRunner

from pincal.cli import main


def _run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_held_out_socket_distance(tmp_path):
    s = tmp_path / "s.csv"
    r = _run("simulate", "ur5", "--random", "40", "--instrument", "socket",
             "--errors", "seed:3", "--seed", "1", "--out", s)  # fmt: skip
    assert r.exit_code == 0, r.output
    r = _run("calibrate", "ur5", "--data", s, "--out", tmp_path / "cal")
    assert r.exit_code == 0, r.output
    v = _run("validate", tmp_path / "cal", "--cv", "4", "--json")
    assert v.exit_code == 0, v.output
    cv = json.loads(v.stdout)["cv"]
    assert cv["poses"] == 40
    base = cv["baseline"]
    assert cv["socket_distance_error_rms_mm"] < 0.2
    assert cv["socket_distance_error_rms_mm"] < base["socket_distance_error_rms_mm"] / 5
    assert cv["held_out_rms_mm"] < base["held_out_rms_mm"]
    text = _run("validate", tmp_path / "cal", "--cv", "4")
    assert "held-out socket-distance error" in text.output

    # without the known distance: refused by calibrate; forced, validate says why not
    (tmp_path / "n.csv").write_text(
        "".join(ln for ln in s.read_text().splitlines(True) if not ln.startswith("# distance"))
    )
    r = _run("calibrate", "ur5", "--data", tmp_path / "n.csv", "--out", tmp_path / "c2")
    assert r.exit_code != 0 and "nothing measured fixes the length scale" in r.output
    r = _run("calibrate", "ur5", "--data", tmp_path / "n.csv", "--out", tmp_path / "c2", "--force")
    assert r.exit_code == 0, r.output
    v = _run("validate", tmp_path / "c2", "--cv", "4")
    assert v.exit_code != 0
    assert "length scale is unidentifiable" in v.output, v.output

"""`pincal compensate CAL --program FILE`: a G-code program of linear moves (issue 37).

The Stewart platform calibrated from exact simulated data; a program of 200 moves in
its workspace with comments, other codes, modal moves and CRLF lines. Checked: lines
that are not moves byte-identical; each rewritten target, commanded through the
*nominal* model (the controller), brings the *calibrated* model to the original target.
"""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.io import read_calibration, read_gcode


@pytest.fixture(scope="module")
def stewart_calibration(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("stewart")
    meas, cal = tmp / "m.csv", tmp / "cal"
    run = CliRunner().invoke
    sim = run(main, ["simulate", "stewart_6ups", "--random", "40", "--noise", "0,0",
                     "--errors", "seed:3", "--out", str(meas)])  # fmt: skip
    assert sim.exit_code == 0, sim.output
    res = run(main, ["calibrate", "stewart_6ups", "--data", str(meas), "--out", str(cal)])
    assert res.exit_code == 0, res.output
    return cal


def _program(n: int, rng: np.random.Generator) -> bytes:
    head = ["%", "(a part, mm)", "G21 G90 G17", "M3 S1000 ; spindle", "F1200"]
    lines = [ln.encode() for ln in head]
    for k in range(n):
        x, y = rng.uniform(-40, 40, 2)
        z = rng.uniform(420, 480)
        a, b, c = rng.uniform(-4, 4, 3)
        if k % 50 == 1:  # a modal move that gives one axis only
            lines.append(f"X{x:.3f}".encode())
        elif k % 7 == 0:
            lines.append(
                f"N{k} G1 X{x:.3f} Y{y:.3f} Z{z:.3f} A{a:.3f} B{b:.3f} C{c:.3f} (cut)\r".encode()
            )
        else:
            lines.append(f"G1 X{x:.3f} Y{y:.3f} Z{z:.3f} A{a:.3f} B{b:.3f} C{c:.3f}".encode())
        if k % 100 == 0:
            lines += [b"", b"(pause)", b"G4 P0.5"]
    lines.append(b"M30")
    return b"\n".join(lines) + b"\n"


def _pose(values: dict, R_home: np.ndarray) -> pin.SE3:
    a, b, c = np.radians([values["A"], values["B"], values["C"]])
    p = np.array([values["X"], values["Y"], values["Z"]]) * 1e-3
    return pin.SE3(R_home @ pin.rpy.rpyToMatrix(a, b, c), p)


def test_program_compensated_and_everything_else_kept(stewart_calibration, tmp_path):
    src, out = tmp_path / "part.ngc", tmp_path / "part_c.ngc"
    data = _program(200, np.random.default_rng(0))
    src.write_bytes(data)
    res = CliRunner().invoke(main, ["compensate", str(stewart_calibration), "--program",
                                    str(src), "--out", str(out), "--json"])  # fmt: skip
    assert res.exit_code == 0, res.output
    summary = json.loads(res.stdout)
    assert summary["moves"] == 200 and src.read_bytes() == data  # input untouched
    before, after = data.split(b"\n"), out.read_bytes().split(b"\n")
    assert len(before) == len(after)
    moves = {m.line for m in read_gcode(data.decode()).moves}
    assert len(moves) == 200
    for i, (a, b) in enumerate(zip(before, after, strict=True)):
        if i not in moves:
            assert a == b, i
        else:
            assert a != b and a.endswith(b"\r") == b.endswith(b"\r")
            if a[:1] in (b"N", b"G"):
                assert a.split(b" ")[0] == b.split(b" ")[0]  # N word or G1 kept in place
    # the controller (nominal model) commanded to each rewritten target brings the
    # calibrated machine to the program's target
    cal = read_calibration(stewart_calibration)
    nominal, calibrated = cal.nominal(), cal.calibrated()
    R_home = nominal.frame_placement(nominal.q_home).rotation
    old, new = read_gcode(data.decode()).moves, read_gcode(out.read_bytes().decode()).moves
    worst, moved = 0.0, 0.0
    for m_old, m_new in list(zip(old, new, strict=True))[::25]:
        target, asked = _pose(m_old.values, R_home), _pose(m_new.values, R_home)
        q_cmd = nominal.inverse(asked)
        reached = calibrated.forward(q_cmd)
        worst = max(worst, np.linalg.norm(reached.translation - target.translation))
        moved = max(moved, np.linalg.norm(asked.translation - target.translation))
    assert worst < 2e-6  # 4 decimals of mm written: 0.05 µm rounding, through the gains
    assert moved > 1e-4  # the calibration does change the program (> 0.1 mm)


@pytest.mark.parametrize(
    ("line", "why"),
    [("G2 X1 Y1 I1 J0", "arc"), ("G91", "incremental"), ("G92 X0", "offset")],
)
def test_constructs_the_reader_cannot_follow_are_refused(stewart_calibration, tmp_path, line, why):
    src, out = tmp_path / "p.ngc", tmp_path / "o.ngc"
    src.write_text(f"G1 X0 Y0 Z450 A0 B0 C0\n{line}\nG1 X1\n")
    res = CliRunner().invoke(main, ["compensate", str(stewart_calibration), "--program",
                                    str(src), "--out", str(out)])  # fmt: skip
    assert res.exit_code == 1 and "line 2" in res.stderr and why in res.stderr
    assert not out.exists()


def test_an_unreachable_target_refuses_the_whole_program(stewart_calibration, tmp_path):
    src, out = tmp_path / "p.ngc", tmp_path / "o.ngc"
    src.write_text("G1 X0 Y0 Z450 A0 B0 C0\nG1 X0 Y0 Z2000\nG1 Z450\n")
    res = CliRunner().invoke(main, ["compensate", str(stewart_calibration), "--program",
                                    str(src), "--out", str(out)])  # fmt: skip
    assert res.exit_code == 1 and "line 2" in res.stderr and "nothing written" in res.stderr
    assert not out.exists()


@pytest.mark.slow
def test_correction_said_over_the_axes_the_program_controls(tmp_path):
    """A 3-PRS head controls Z A B: the largest correction printed is that of the written
    Z and A B (it said 23 mm, the parasitic x y the program does not write)."""
    from tests.open_world.prs3_head import write_prs3_head

    model = write_prs3_head(tmp_path)
    run = CliRunner().invoke
    sim = run(main, ["simulate", str(model), "--random", "40", "--noise", "0,0", "--out",
                     str(tmp_path / "m.csv")])  # fmt: skip
    assert sim.exit_code == 0, sim.output
    res = run(main, ["calibrate", str(model), "--data", str(tmp_path / "m.csv"), "--params",
                     "base", "--out", str(tmp_path / "cal")])  # fmt: skip
    assert res.exit_code == 0, res.output
    src, out = tmp_path / "p.nc", tmp_path / "p_c.nc"
    src.write_text("G0 Z440 A0 B0\nG1 Z430 A5 B-2\nG1 Z420 A0 B10\n")
    res = run(main, ["compensate", str(tmp_path / "cal"), "--program", str(src), "--out",
                     str(out), "--json"])  # fmt: skip
    assert res.exit_code == 0, res.output
    summary = json.loads(res.stdout)
    old, new = read_gcode(src.read_text()).moves, read_gcode(out.read_text()).moves
    dz = max(abs(n.values["Z"] - o.values["Z"]) for o, n in zip(old, new, strict=True))
    dab = max(np.hypot(*np.radians([n.values[a] - o.values[a] for a in "AB"])) * 1e3
              for o, n in zip(old, new, strict=True))  # fmt: skip
    assert dz > 0.1  # the calibration moves the program
    assert summary["largest_correction_mm"] == pytest.approx(dz, abs=1e-3)
    assert summary["largest_correction_mrad"] == pytest.approx(dab, abs=1e-3)

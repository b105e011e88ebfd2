"""Outputs never overwrite inputs (issue 16): every command checks before any work.

Each case asserts exit code 1, one line ``OutputPathError`` naming both paths, no
traceback, and the input unchanged byte for byte.
"""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.cli._paths import guard_paths
from pincal.errors import OutputPathError

PINCAL = Path(__file__).resolve().parents[2] / "pincal"


@pytest.fixture(scope="module")
def campaign(tmp_path_factory) -> Path:
    """A small wedge3 campaign: poses.csv, m.csv and a calibration directory cal/."""
    d = tmp_path_factory.mktemp("campaign")
    runner = CliRunner()
    for args in (
        ["simulate", "wedge3", "--random", "12", "--out", str(d / "m.csv")],
        ["calibrate", "wedge3", "--data", str(d / "m.csv"), "--params", "patent",
         "--out", str(d / "cal")],
    ):  # fmt: skip
        res = runner.invoke(main, args)
        assert res.exit_code == 0, res.output
    (d / "poses.csv").write_bytes((d / "m.csv").read_bytes())
    return d


def refused(args: list[str], *named: Path, fix: str = "inputs are never modified") -> str:
    before = {p: p.read_bytes() for p in named if p.is_file()}
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 1, res.output
    assert "Traceback" not in res.output
    line = res.output.strip()
    assert "\n" not in line and line.startswith("pincal: error: OutputPathError: "), line
    assert fix in line
    for p in named:
        assert str(p) in line, (p, line)
    for p, data in before.items():
        assert p.read_bytes() == data, f"{p} was modified"
    return line


def test_compensate_out_is_its_targets(campaign):
    t = campaign / "poses.csv"
    refused(["compensate", str(campaign / "cal"), "--targets", str(t), "--out", str(t)], t)


def test_compensate_out_is_a_hard_link_of_its_targets(campaign, tmp_path):
    link = tmp_path / "link.csv"
    os.link(campaign / "poses.csv", link)
    refused(["compensate", str(campaign / "cal"), "--targets", str(campaign / "poses.csv"),
             "--out", str(link)], campaign / "poses.csv", link)  # fmt: skip


def test_compensate_out_through_a_symlink_to_its_targets(campaign, tmp_path):
    (tmp_path / "alias").symlink_to(campaign)
    t = campaign / "poses.csv"
    refused(["compensate", str(campaign / "cal"), "--targets", str(t),
             "--out", str(tmp_path / "alias" / "poses.csv")], t)  # fmt: skip


def test_simulate_out_is_its_poses(campaign):
    p = campaign / "poses.csv"
    refused(["simulate", "wedge3", "--poses", str(p), "--out", str(p)], p)


def test_calibrate_data_inside_the_output_directory(campaign):
    data = campaign / "cal" / "report.txt"
    line = refused(["calibrate", "wedge3", "--data", str(data), "--out", str(campaign / "cal")],
                   data, campaign / "cal")  # fmt: skip
    assert "inside the output directory --out" in line
    assert not list(campaign.glob(".cal.pincal-*"))  # refused before taking the lock


def test_poses_csv_and_its_json_record_are_one_file(tmp_path):
    out = tmp_path / "design.json"
    line = refused(["poses", "wedge3", "--count", "6", "--out", str(out)], out,
                   fix="give output paths that differ")  # fmt: skip
    assert "JSON record" in line and not out.exists()


def test_view_html_is_its_poses(campaign):
    p = campaign / "poses.csv"
    refused(["view", "wedge3", "--poses", str(p), "--html", str(p)], p)


def test_acceptance_out_is_its_data(campaign):
    d = campaign / "m.csv"
    refused(["acceptance", "wedge3", "--data", str(d), "--out", str(d)], d)


def test_report_name_would_overwrite_the_calibration(campaign):
    ident = campaign / "cal" / "identification.json"
    line = refused(["report", str(campaign / "cal"), "--name", "identification"], ident)
    assert "--name's json" in line


def test_guard_paths_library_cases(tmp_path):
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    a.write_text("x")
    guard_paths({"--in": a}, {"--out": b}, {"--dir": tmp_path / "d"})  # all distinct: fine
    guard_paths({"--in": None}, {"--out": a})  # absent inputs are skipped
    with pytest.raises(OutputPathError, match=r"--out .* is the same file as the input --in"):
        guard_paths({"--in": a}, {"--out": tmp_path / "." / "a.csv"})
    with pytest.raises(OutputPathError, match="are the same file"):
        guard_paths({}, {"--x": b, "--y": b})
    with pytest.raises(OutputPathError, match="inside the output directory"):
        guard_paths({"--in": a}, {}, {"--dir": tmp_path})


def test_every_output_file_goes_through_the_atomic_writer():
    """No module writes a file directly: only pincal/io/_atomic.py opens files for writing."""
    direct = re.compile(r"open\([^)]*['\"][wax]b?\+?['\"]|\.write_(text|bytes)\(|"
                        r"\.savefig\((?!buffer)|np\.save|\.tofile\(|json\.dump\(|yaml\.dump\(")
    offenders = [
        f"{path.relative_to(PINCAL.parent)}:{n}"
        for path in PINCAL.rglob("*.py") if path.name != "_atomic.py"
        for n, line in enumerate(path.read_text().splitlines(), 1) if direct.search(line)
    ]  # fmt: skip
    assert offenders == []

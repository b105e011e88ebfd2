"""Every command the README shows runs as documented.

`pincal …` commands run in order in one scratch directory (the CLI workflow builds
on the files the previous commands wrote); `python scripts/…` commands run as
subprocesses, except the long studies and benchmarks listed in ``LONG``, each of
which has a fast test of its core claim elsewhere. The README's Python example runs
as written.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest
from click.testing import CliRunner

from pincal.cli import main

ROOT = Path(__file__).resolve().parent.parent
README = (ROOT / "README.md").read_text(encoding="utf-8")
#: the README and the pages it points to (studies, performance, …): their script commands
DOCS = README + "".join(
    p.read_text(encoding="utf-8") for p in sorted((ROOT / "docs").glob("*.md"))
)
LONG = {
    "scripts/bench_core.py": "benchmark (timings, no assertion)",
    "scripts/bench_design.py": "benchmark (timings, no assertion)",
    "scripts/bench_instruments.py": "benchmark (timings, no assertion)",
    "scripts/bench_fleet.py": "benchmark; serial = Dask equality in tests/cli/test_fleet.py",
    "scripts/bench_open_world.py": "benchmark; equality in tests/model/test_batch_nonsquare.py",
    "scripts/bench_realdata.py": "benchmark (timings, no assertion; minutes per column)",
    "scripts/bench_vs_figaroh.py": "needs the optional [bench] extra",
    "scripts/studies/open_world_campaigns.py": "19 CLI campaigns (~15 min); the four-bar's "
    "and the Agile Eye's in tests/open_world/test_noisy_campaign.py",
    "scripts/studies/arms_by_name.py": "74 robots through poses, simulate and calibrate "
    "(~5 min); the xArm7, aacmm and panda_collision cases in tests/sensitivity and "
    "tests/design",
    "scripts/studies/prediction_honesty.py": "60 CLI campaigns (~5 min); the curved fits' "
    "predicted / achieved in tests/open_world/test_noisy_campaign.py",
    "scripts/studies/stewart_pose_selection.py": "Monte-Carlo; core claim in test_seed000_study.py",
    "scripts/studies/pkm5_qpso.py": "QPSO study; core claim in test_identify_qpso.py",
    "scripts/studies/instrument_campaigns.py": "Monte-Carlo study; core claim in tests/instruments",
    "scripts/studies/socket_gate.py": "180 UR5 socket fits (minutes); a wrong "
    "joint_reference refused in tests/cli/test_socket_guards.py",
    "scripts/studies/fleet_detection.py": "five 200-unit CLI fleets (~6 min); the planted "
    "unit flagged in tests/cli/test_fleet.py",
    "scripts/studies/fleet_drift.py": "21 CLI fleets of 40 sessions (~8 min); a drifted "
    "part named in tests/cli/test_fleet.py",
    "scripts/studies/fleet_small.py": "fault-free fleets, each limit calibrated by 200 more "
    "(minutes); the small-fleet limit in tests/workflow/test_fleet_stats.py",
}


def _blocks(lang: str) -> list[str]:
    return re.findall(rf"```{lang}\n(.*?)```", README, flags=re.S)


def _commands() -> list[str]:
    """Shell commands of the README: bash blocks and inline `python scripts/…` mentions."""
    cmds = []
    for block in _blocks("bash"):
        for line in block.splitlines():
            line = line.split("#")[0].strip()
            cmds += [part.strip() for part in line.split("&&") if part.strip()]
    cmds += re.findall(r"`(python scripts/[^`]+)`", DOCS)
    cmds += [c.split("&&")[-1].strip() for c in re.findall(r"`(pip install[^`]+)`", README)]
    return [c for c in dict.fromkeys(cmds) if not c.startswith("pip install")]


def test_readme_has_the_two_sacred_commands():
    assert 'pip install -e ".[test]" && pincal demo' in README
    assert 'pip install -e ".[test]" && python -m pytest' in README


@pytest.mark.slow
def test_pincal_commands(tmp_path):
    runner = CliRunner()
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        pincal = [c for c in _commands() if c.startswith("pincal ")]
        assert len(pincal) >= 8
        for cmd in pincal:
            args = shlex.split(cmd)[1:]
            if args == ["demo"]:
                args += ["--poses", "30", "--validation", "20"]  # same job, smaller validation
            result = runner.invoke(main, args)
            assert result.exit_code == 0, f"{cmd}\n{result.output}"
    finally:
        os.chdir(cwd)
    assert (tmp_path / "pincal-out" / "report.html").is_file()
    assert (tmp_path / "cal" / "report.html").is_file()
    assert (tmp_path / "commands.csv").is_file() and (tmp_path / "poses.html").is_file()


SCRIPTS = [c for c in _commands() if c.startswith("python scripts/") and c.split()[1] not in LONG]
#: scripts run in the slow lane only (each over ~20 s), with where their claim is tested fast
SLOW_SCRIPTS = {
    "scripts/studies/open_world_table.py": "tests/open_world/test_roster.py",
    "scripts/studies/hexaslide_calibration.py": "tests/studies/test_hexaslide_calibration.py",
    "scripts/studies/reach_screen.py": "tests/cli/test_poses_screens.py",
}


@pytest.mark.parametrize(
    "cmd",
    [
        pytest.param(c, marks=[pytest.mark.slow] if c.split()[1] in SLOW_SCRIPTS else [])
        for c in SCRIPTS
    ],
)
def test_script_commands(cmd):
    args = shlex.split(cmd)
    out = subprocess.run(
        [sys.executable, *args[1:]], cwd=ROOT, capture_output=True, text=True, timeout=300
    )
    assert out.returncode == 0, out.stdout[-2000:] + out.stderr[-2000:]
    assert "FAIL" not in out.stdout


def test_long_commands_are_the_only_ones_skipped():
    mentioned = {c.split()[1] for c in _commands() if c.startswith("python scripts/")}
    assert set(LONG) <= mentioned | {"scripts/bench_vs_figaroh.py"}
    assert len(SCRIPTS) >= 4
    assert set(SLOW_SCRIPTS) <= {c.split()[1] for c in SCRIPTS}
    assert all((ROOT / test).is_file() for test in SLOW_SCRIPTS.values())


def test_python_example(tmp_path, monkeypatch):
    (code,) = [b for b in _blocks("python") if "import pincal" in b]
    monkeypatch.chdir(tmp_path)
    exec(compile(code, "README.md", "exec"), {})
    assert (tmp_path / "out" / "stewart_calibrated.urdf").is_file()

"""Outputs never clobber: devices, FIFOs, links, input calibrations and users' files.

Library cases call the atomic writer; CLI cases run the commands and assert exit 1, one
line naming the option and path, and every protected file unchanged byte for byte.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.errors import OutputPathError
from pincal.io import MANIFEST, atomic_write_text, calibration_lock


@pytest.fixture(scope="module")
def work(tmp_path_factory) -> Path:
    """m.csv, its calibration cal/ and a pose file targets.csv (wedge3)."""
    d = tmp_path_factory.mktemp("outputs")
    runner = CliRunner()
    for args in (
        ["simulate", "wedge3", "--random", "12", "--out", str(d / "m.csv")],
        ["calibrate", "wedge3", "--data", str(d / "m.csv"), "--params", "patent",
         "--out", str(d / "cal")],
    ):  # fmt: skip
        res = runner.invoke(main, args)
        assert res.exit_code == 0, res.output
    (d / "targets.csv").write_bytes((d / "m.csv").read_bytes())
    return d


def _snapshot(*paths: Path) -> dict[Path, bytes]:
    out = {}
    for p in paths:
        for f in [p] if p.is_file() else sorted(p.rglob("*")) if p.is_dir() else []:
            if f.is_file():
                out[f] = f.read_bytes()
    return out


def refused(args: list[str], *protected: Path, says: str) -> str:
    before = _snapshot(*protected)
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 1, res.output
    line = res.output.strip()
    assert "\n" not in line and "Traceback" not in line, line
    assert says in line, line
    assert _snapshot(*protected) == before
    return line


# --- library: the atomic writer ------------------------------------------------------


def test_writer_refuses_a_fifo(tmp_path):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    with pytest.raises(OutputPathError, match="is a device, FIFO or socket.*regular files"):
        atomic_write_text(fifo, "x")
    assert fifo.is_fifo()


def test_writer_refuses_a_link_to_a_device_and_keeps_the_link(tmp_path):
    link = tmp_path / "null.csv"
    link.symlink_to("/dev/null")
    with pytest.raises(OutputPathError, match=r"under /dev or /proc \(the link points to /dev/n"):
        atomic_write_text(link, "x")
    assert link.is_symlink() and os.readlink(link) == "/dev/null"


@pytest.mark.parametrize("path", ["/dev/null", "/dev/stdout", "/proc/self/fd/1"])
def test_writer_refuses_system_paths(path):
    with pytest.raises(OutputPathError, match="under /dev or /proc"):
        atomic_write_text(path, "x")


def test_writer_writes_through_a_link_to_a_regular_file(tmp_path):
    target = tmp_path / "real.csv"
    target.write_text("old\n")
    link = tmp_path / "link.csv"
    link.symlink_to(target)
    assert atomic_write_text(link, "new\n") == target
    assert link.is_symlink() and target.read_text() == "new\n"


def test_writer_refuses_a_dangling_link_and_a_directory(tmp_path):
    link = tmp_path / "gone.csv"
    link.symlink_to(tmp_path / "missing.csv")
    with pytest.raises(OutputPathError, match="link to a missing file"):
        atomic_write_text(link, "x")
    with pytest.raises(OutputPathError, match="is a directory"):
        atomic_write_text(tmp_path, "x")
    assert link.is_symlink() and not (tmp_path / "missing.csv").exists()


# --- CLI: explicit outputs -----------------------------------------------------------


def test_out_dev_stdout_is_refused(work):
    refused(["simulate", "wedge3", "--random", "3", "--out", "/dev/stdout"],
            says="--out /dev/stdout is under /dev or /proc")  # fmt: skip


def test_out_fifo_is_refused_before_any_work(work, tmp_path):
    fifo = tmp_path / "f.csv"
    os.mkfifo(fifo)
    refused(["simulate", "wedge3", "--random", "3", "--out", str(fifo)],
            says="is a device, FIFO or socket")  # fmt: skip
    assert fifo.is_fifo()


def test_out_with_trailing_slash_writes_no_file(work, tmp_path):
    out = f"{tmp_path / 'newdir'}/"
    refused(["simulate", "wedge3", "--random", "3", "--out", out], says="ends with '/'")
    assert not (tmp_path / "newdir").exists()


@pytest.mark.parametrize(
    "args",
    [
        ["compensate", "{cal}", "--targets", "{w}/targets.csv",
         "--out", "{cal}/identification.json"],
        ["compensate", "{cal}", "--targets", "{w}/targets.csv", "--out", "{cal}/report.txt"],
        ["view", "wedge3", "--calibrated", "{cal}", "--html", "{cal}/calibration.json"],
        ["acceptance", "wedge3", "--calibrated", "{cal}", "--out", "{cal}/calibrated.urdf"],
        ["compensate", "{cal}", "--targets", "{w}/targets.csv", "--out", "{cal}/new.csv"],
    ],
)  # fmt: skip
def test_no_output_inside_an_input_calibration_directory(work, args):
    cal = work / "cal"
    argv = [a.format(cal=cal, w=work) for a in args]
    line = refused(argv, cal, says="is inside the input calibration directory")
    assert str(cal) in line and "never modified" in line
    assert not (cal / "new.csv").exists()


# --- calibrate --out: only directories pincal wrote ----------------------------------


def test_calibrate_refuses_a_user_directory_holding_identification_json(work, tmp_path):
    out = tmp_path / "project"
    (out / "src").mkdir(parents=True)
    (out / "src" / "main.c").write_text("int main;\n")
    (out / "README").write_text("mine\n")
    (out / "identification.json").write_text("{}\n")
    line = refused(["calibrate", "wedge3", "--data", str(work / "m.csv"), "--params", "patent",
                    "--out", str(out)], out, says="without a valid calibration.json")  # fmt: skip
    assert "never replaced" in line


def test_recalibrating_refuses_foreign_files_and_keeps_them(work, tmp_path):
    out = tmp_path / "cal"
    shutil.copytree(work / "cal", out)
    (out / "notes.txt").write_text("torque wrench 12 Nm\n")
    (out / "photos").mkdir()
    line = refused(["calibrate", "wedge3", "--data", str(work / "m.csv"), "--params", "patent",
                    "--out", str(out)], out, says="files pincal did not write")  # fmt: skip
    assert "notes.txt" in line and "photos" in line and "move them out" in line


def test_recalibrating_replaces_pincal_files_and_reports(work, tmp_path):
    out = tmp_path / "cal"
    shutil.copytree(work / "cal", out)
    (out / "report.html").write_text("<p>old report</p>\n")  # written by `pincal report`
    res = CliRunner().invoke(main, ["calibrate", "wedge3", "--data", str(work / "m.csv"),
                                    "--params", "patent", "--out", str(out)])  # fmt: skip
    assert res.exit_code == 0, res.output
    assert (out / MANIFEST).is_file() and not (out / "report.html").exists()


def test_calibrate_out_dot_inside_its_directory_exits_0(work, tmp_path, monkeypatch):
    out = tmp_path / "cal"
    shutil.copytree(work / "cal", out)
    monkeypatch.chdir(out)
    res = CliRunner().invoke(main, ["calibrate", "wedge3", "--data", str(work / "m.csv"),
                                    "--params", "patent", "--out", "."])  # fmt: skip
    assert res.exit_code == 0, res.output
    assert (out / MANIFEST).is_file()


# --- implied side files --------------------------------------------------------------


def test_simulate_keeps_a_users_truth_file(tmp_path):
    mine = tmp_path / "m.truth.json"
    mine.write_text('{"mine": true}\n')
    refused(["simulate", "wedge3", "--random", "3", "--out", str(tmp_path / "m.csv")], mine,
            says="--out's truth file")  # fmt: skip
    assert not (tmp_path / "m.csv").exists()


def test_simulate_replaces_its_own_truth_file(tmp_path):
    args = ["simulate", "wedge3", "--random", "3", "--out", str(tmp_path / "m.csv")]
    for _ in range(2):
        res = CliRunner().invoke(main, args)
        assert res.exit_code == 0, res.output


def test_poses_keeps_a_users_json_and_commands_file(tmp_path):
    mine = tmp_path / "p.json"
    mine.write_text('{"my": "notes"}\n')
    line = refused(["poses", "wedge3", "--count", "3", "--out", str(tmp_path / "p.csv")], mine,
                   says="exists and was not written by pincal")  # fmt: skip
    assert "--out's JSON record" in line
    mine.unlink()
    (tmp_path / "p.commands.csv").write_text("a,b\n1,2\n")
    line = refused(["poses", "wedge3", "--count", "3", "--out", str(tmp_path / "p.csv")],
                   tmp_path / "p.commands.csv", says="--out's commands file")  # fmt: skip
    assert "--overwrite" in line


def test_overwrite_replaces_a_users_side_files(tmp_path):
    (tmp_path / "m.truth.json").write_text('{"my": "notes"}\n')
    args = ["simulate", "wedge3", "--random", "3", "--out", str(tmp_path / "m.csv")]
    assert CliRunner().invoke(main, args).exit_code == 1
    res = CliRunner().invoke(main, [*args, "--overwrite"])
    assert res.exit_code == 0, res.output
    assert "my" not in json.loads((tmp_path / "m.truth.json").read_text())


# --- campaign ------------------------------------------------------------------------

EXAMPLE = Path(__file__).resolve().parents[2] / "docs" / "examples" / "campaign.yaml"


def _campaign(tmp_path: Path, out: str) -> Path:
    text = EXAMPLE.read_text()
    lines = [ln for ln in text.splitlines() if not ln.startswith("out:")]
    f = tmp_path / "c.yaml"
    f.write_text("\n".join(lines) + f"\nout: {out}\n")
    return f


def test_campaign_out_root_is_refused_before_any_step(tmp_path):
    line = refused(["run", str(_campaign(tmp_path, "/"))], says="is the file system root")
    assert "out: campaign-out" in line and not Path("/-inputs").exists()


def test_campaign_refuses_a_users_file_where_a_generated_input_goes(tmp_path):
    inputs = tmp_path / "cal-inputs"
    inputs.mkdir()
    (inputs / "measurements.truth.json").write_text("{}\n")
    refused(["run", str(_campaign(tmp_path, str(tmp_path / "cal")))], inputs,
            says="the measurements step's .truth.json file")  # fmt: skip
    assert not (tmp_path / "cal").exists()


def test_campaign_inputs_folder_is_locked(tmp_path):
    """A second run into the same out stops at once while the first holds the lock."""
    inputs = tmp_path / "cal-inputs"
    holder = textwrap.dedent(f"""
        import sys, time
        from pincal.io import calibration_lock
        with calibration_lock({str(inputs)!r}):
            print("held", flush=True)
            time.sleep(60)
    """)
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[2])}
    proc = subprocess.Popen([sys.executable, "-c", holder], stdout=subprocess.PIPE, env=env)
    try:
        assert proc.stdout is not None and proc.stdout.readline().strip() == b"held"
        refused(["run", str(_campaign(tmp_path, str(tmp_path / "cal")))],
                says="another pincal is writing")  # fmt: skip
        assert not (tmp_path / "cal").exists()
    finally:
        proc.kill()
        proc.wait()
    with calibration_lock(inputs):  # released with the holder
        pass

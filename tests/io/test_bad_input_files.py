"""Issue 16, input files: no bad input file may hang, exhaust memory or leak a traceback.

One test (library and CLI) per bullet: YAML alias bombs, duplicate keys and huge
integers; bounded reads (devices, FIFOs, size caps); CSV cells (10 MB cell, BOM, ``1_0``,
non-finite); actuator values far outside the URDF limits; clipped values in messages.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from pincal._limits import Limits
from pincal.cli import main
from pincal.errors import (
    ActuatorRangeError,
    BadValueError,
    CampaignError,
    InputFileError,
    InputLimitError,
    MeasurementFileError,
    MeasurementFormatError,
    ModelFileError,
    NonFiniteValueError,
)
from pincal.io import (
    read_commands,
    read_measurement_file,
    read_pose_file,
    read_pose_rows,
    write_commands,
    write_measurements,
    write_poses,
)
from pincal.measure import simulate_measurements
from pincal.model import load_mechanism, read_sidecar, sample_actuators
from pincal.model.loading._model_files import MODELS_DIR
from tests.cli._checks import assert_clean_failure

ROOT = Path(__file__).resolve().parents[2]
CALIBRATE = (sys.executable, "-m", "pincal.cli", "calibrate", "hexaslide_6pus")
BOMB = "a: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
    f"{chr(98 + i)}: &{chr(98 + i)} [{', '.join(['*' + chr(97 + i)] * 9)}]\n" for i in range(9)
)


@pytest.fixture(scope="module")
def hexa():
    return load_mechanism("hexaslide_6pus")


@pytest.fixture(scope="module")
def meas(hexa):
    rng = np.random.default_rng(5)
    return simulate_measurements(hexa, sample_actuators(hexa, 4, rng), None, rng)


@pytest.fixture()
def good_csv(tmp_path, meas):
    return write_measurements(tmp_path / "m.csv", meas, length_unit="mm")


def _cli(*args: str):
    res = CliRunner().invoke(main, list(args))
    return res


def _one_line_error(res, *needles: str) -> str:
    """Exit 1, one line on stderr, no traceback, naming every needle."""
    assert res.exit_code == 1, res.output
    err = res.stderr.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in res.output, err
    assert len(err) < 1000, len(err)
    for n in needles:
        assert n in err, (n, err)
    return err


def _model_copy(tmp_path: Path, name: str = "wedge3") -> Path:
    d = tmp_path / name
    shutil.copytree(MODELS_DIR / name, d)
    return d


# --- bullet 1: YAML -----------------------------------------------------------------------


def test_sidecar_alias_bomb_is_refused_naming_the_file(tmp_path):
    d = _model_copy(tmp_path)
    side = d / "wedge3.yaml"
    side.write_text(side.read_text() + BOMB.replace("a:", "zz_bomb:", 1))
    assert len(BOMB) < 1024
    with pytest.raises(InputLimitError, match="wedge3.yaml.*expands to more than"):
        read_sidecar(side)
    with pytest.raises(InputLimitError):
        load_mechanism(d)
    err = _one_line_error(_cli("info", str(d)), "wedge3.yaml", "alias")
    assert "InputLimitError" in err


def test_sidecar_duplicate_key_names_key_and_lines(tmp_path):
    d = _model_copy(tmp_path)
    side = d / "wedge3.yaml"
    text = side.read_text()
    n = len(text.splitlines())
    side.write_text(text + "view_up: +z\nview_up: -z\n")
    with pytest.raises(ModelFileError) as exc:
        read_sidecar(side)
    msg = str(exc.value)
    assert "'view_up'" in msg and f"line {n + 2}" in msg and f"line {n + 1}" in msg
    assert "wedge3.yaml" in msg and "give each key once" in msg
    _one_line_error(_cli("info", str(d)), "view_up", "twice")


def test_sidecar_400_digit_integer_is_a_clipped_model_file_error(tmp_path):
    d = _model_copy(tmp_path)
    side = d / "wedge3.yaml"
    side.write_text(side.read_text().replace("home: {q0: 0.0", "home: {q0: " + "9" * 400))
    with pytest.raises(ModelFileError, match=r"home\['q0'\] must be a finite number") as exc:
        load_mechanism(d)
    assert "digits>" in str(exc.value) and len(str(exc.value)) < 300
    _one_line_error(_cli("info", str(d)), "home", "finite number")


def test_yaml_value_errors_are_clipped(tmp_path):
    d = _model_copy(tmp_path)
    side = d / "wedge3.yaml"
    side.write_text(side.read_text() + "view_up: [" + ", ".join(["z"] * 5000) + "]\n")
    with pytest.raises(ModelFileError, match="view_up") as exc:
        load_mechanism(d)
    assert len(str(exc.value)) < 300


def test_campaign_yaml_goes_through_the_safe_loader(tmp_path):
    camp = tmp_path / "campaign.yaml"
    camp.write_text("model: wedge3\nmodel: hexaslide_6pus\n")
    runner_res = _cli("run", str(camp))
    _one_line_error(runner_res, "campaign.yaml", "'model'", "twice")
    from pincal.cli._campaign import load_campaign

    with pytest.raises(CampaignError, match="line 2: key 'model' is given twice"):
        load_campaign(camp)
    camp.write_text(BOMB)
    with pytest.raises(InputLimitError, match="campaign file"):
        load_campaign(camp)


# --- bullet 2: bounded reads ----------------------------------------------------------


@pytest.mark.skipif(not Path("/dev/zero").exists(), reason="no /dev/zero")
def test_device_files_are_refused_at_once(hexa):
    for read in (
        lambda p: read_measurement_file(p, hexa),
        read_pose_file,
        lambda p: read_commands(p, hexa),
        lambda p: read_pose_rows(p, hexa),
        read_sidecar,
    ):
        with pytest.raises(InputFileError, match="not a regular file"):
            read(Path("/dev/zero"))
    _one_line_error(
        _cli("calibrate", "hexaslide_6pus", "--data", "/dev/zero", "--out", "x"),
        "/dev/zero",
        "regular file",
    )
    _one_line_error(
        _cli("simulate", "hexaslide_6pus", "--poses", "/dev/zero", "--out", "x.csv"),
        "/dev/zero",
    )


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs")
def test_fifo_without_writer_fails_at_once(tmp_path, hexa):
    fifo = tmp_path / "data.csv"
    os.mkfifo(fifo)
    with pytest.raises(MeasurementFileError, match="data.csv is not a regular file"):
        read_measurement_file(fifo, hexa)
    with pytest.raises(MeasurementFileError):
        read_pose_rows(fifo, hexa)
    proc = subprocess.run(  # a blocking read would end in TimeoutExpired
        [*CALIBRATE, "--data", str(fifo), "--out", str(tmp_path / "cal")],
        capture_output=True,
        text=True,
        timeout=120,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )
    assert proc.returncode == 1 and "Traceback" not in proc.stderr, proc.stderr
    assert "data.csv" in proc.stderr and "regular file" in proc.stderr


def test_size_cap_applies_before_reading(tmp_path, hexa, good_csv, monkeypatch):
    big = tmp_path / "big.csv"
    big.write_bytes(good_csv.read_bytes() + b"#" * (2 * 1024 * 1024))
    with (
        Limits(file_bytes=2**20).applied(),
        pytest.raises(InputLimitError, match="big.csv.*PINCAL_MAX_FILE_MB"),
    ):
        read_measurement_file(big, hexa)
    monkeypatch.setenv("PINCAL_MAX_FILE_MB", "1")  # the command line reads it
    _one_line_error(
        _cli("calibrate", "hexaslide_6pus", "--data", str(big), "--out", str(tmp_path / "c")),
        "big.csv",
        "PINCAL_MAX_FILE_MB",
    )


# --- bullet 3: CSV cells -----------------------------------------------------------------


def test_ten_megabyte_cell_is_a_format_error_naming_the_line(tmp_path, hexa, good_csv):
    lines = good_csv.read_text().splitlines()
    k = next(i for i, ln in enumerate(lines) if not ln.startswith("#")) + 2
    lines[k] = "1" * 10_000_000 + lines[k]
    bad = tmp_path / "cell.csv"
    bad.write_text("\n".join(lines) + "\n")
    with pytest.raises(MeasurementFormatError, match=f"cell.csv line {k + 1}: cannot be split"):
        read_measurement_file(bad, hexa)
    err = _one_line_error(
        _cli("calibrate", "hexaslide_6pus", "--data", str(bad), "--out", str(tmp_path / "c")),
        "cell.csv",
        f"line {k + 1}",
    )
    assert len(err) < 400


def test_byte_order_mark_is_accepted_by_every_reader(tmp_path, hexa, meas, good_csv):
    files = {
        "m": good_csv,
        "p": write_poses(tmp_path / "p.csv", [pin_pose(meas, i) for i in range(len(meas))]),
        "c": write_commands(tmp_path / "c.csv", hexa.actuated, meas.q_act),
    }
    for f in files.values():
        f.write_bytes(b"\xef\xbb\xbf" + f.read_bytes())
    assert read_measurement_file(files["m"], hexa).measurements.q_act.shape == (4, 6)
    assert len(read_pose_file(files["p"]).poses) == 4
    assert np.array_equal(read_commands(files["c"], hexa)[1], meas.q_act)
    assert read_pose_rows(files["c"], hexa).shape == (4, 6)
    bom = b"\xef\xbb\xbf"
    side = tmp_path / "s.yaml"
    side.write_bytes(bom + b"measured_frame: platform\n")
    assert read_sidecar(side) == {"measured_frame": "platform"}
    table = tmp_path / "t.csv"
    table.write_bytes(bom + b"point,x,y,z\nT1,1,2,3\n")
    from pincal.io._delimited import read_table

    assert read_table(table).columns == ("point", "x", "y", "z")
    raw = tmp_path / "raw.csv"
    raw.write_bytes(
        bom + b",".join(j.encode() for j in hexa.actuated) + b"\n" + b"0.1," * 5 + b"0.1\n"
    )
    assert read_pose_rows(raw, hexa).shape == (1, 6)


def pin_pose(meas, i):
    import pinocchio as pin

    return pin.SE3(meas.rotations[i], meas.positions[i])


@pytest.mark.parametrize("cell", ["1_0", "١", "0x10", "1,5", " 1 2"])
def test_python_only_number_spellings_are_refused(tmp_path, hexa, meas, cell):
    path = write_commands(tmp_path / "c.csv", hexa.actuated, meas.q_act)
    lines = path.read_text().splitlines()
    cells = lines[3].split(",")
    cells[2] = f'"{cell}"' if "," in cell else cell
    lines[3] = ",".join(cells)
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(BadValueError, match="data row 2, column 'leg2_slide'") as exc:
        read_commands(path, hexa)
    assert "plain decimal" in str(exc.value)
    assert exc.value.row == 2 and exc.value.column == "leg2_slide"


def test_underscore_cell_refused_through_the_cli(tmp_path, good_csv):
    lines = good_csv.read_text().splitlines()
    k = next(i for i, ln in enumerate(lines) if not ln.startswith("#")) + 1
    cells = lines[k].split(",")
    cells[0] = "1_0"
    lines[k] = ",".join(cells)
    good_csv.write_text("\n".join(lines) + "\n")
    _one_line_error(
        _cli("calibrate", "hexaslide_6pus", "--data", str(good_csv), "--out", str(tmp_path / "c")),
        "BadValueError",
        "data row 1",
        "leg1_slide",
        "'1_0'",
    )


@pytest.mark.parametrize("cell", ["nan", "-inf", "Infinity", "1e999"])
def test_non_finite_cells_are_refused(tmp_path, hexa, meas, cell):
    path = write_commands(tmp_path / "c.csv", hexa.actuated, meas.q_act)
    lines = path.read_text().splitlines()
    cells = lines[2].split(",")
    cells[1] = cell
    lines[2] = ",".join(cells)
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(NonFiniteValueError, match="data row 1, column 'leg1_slide'"):
        read_commands(path, hexa)


def test_header_numbers_are_strict(tmp_path, hexa, good_csv):
    text = good_csv.read_text().replace(
        "# length_unit: mm", "# length_unit: mm\n# noise: position_mm=1_0 orientation_mrad=1"
    )
    good_csv.write_text(text)
    with pytest.raises(MeasurementFormatError, match="noise entry 'position_mm=1_0'"):
        read_measurement_file(good_csv, hexa)


# --- bullet 5: actuator ranges --------------------------------------------------------------


@pytest.mark.parametrize("value", ["1000", "1e308", "-0.13"])
def test_actuator_far_outside_its_limits_is_refused(tmp_path, hexa, good_csv, value):
    lines = good_csv.read_text().splitlines()
    k = next(i for i, ln in enumerate(lines) if not ln.startswith("#")) + 3
    cells = lines[k].split(",")
    cells[4] = value
    lines[k] = ",".join(cells)
    good_csv.write_text("\n".join(lines) + "\n")
    with pytest.raises(ActuatorRangeError) as exc:
        read_measurement_file(good_csv, hexa)
    msg = str(exc.value)
    assert "m.csv data row 3, column 'leg5_slide'" in msg
    assert "[-0.1, 0.3] m" in msg and exc.value.joint == "leg5_slide"
    assert exc.value.limits == (-0.1, 0.3) and exc.value.row == 3
    _one_line_error(
        _cli("calibrate", "hexaslide_6pus", "--data", str(good_csv), "--out", str(tmp_path / "c")),
        "ActuatorRangeError",
        "leg5_slide",
        "[-0.1, 0.3]",
    )


def test_actuator_slightly_past_a_limit_is_read(tmp_path, hexa, meas):
    q = meas.q_act.copy()
    q[0, 0] = 0.3 + 0.015  # 3.75 % of the 0.4 m range past the upper limit
    path = write_commands(tmp_path / "c.csv", hexa.actuated, q)
    assert read_commands(path, hexa)[1][0, 0] == q[0, 0]
    q[0, 0] = 0.3 + 0.03
    write_commands(path, hexa.actuated, q)
    with pytest.raises(ActuatorRangeError, match="data row 1, column 'leg1_slide'"):
        read_commands(path, hexa)


def test_pose_file_actuators_out_of_range_are_refused_for_viewing(tmp_path, hexa, meas):
    q = meas.q_act.copy()
    q[1, 2] = 1000.0
    poses = [pin_pose(meas, i) for i in range(len(meas))]
    path = write_poses(tmp_path / "p.csv", poses, actuated=hexa.actuated, q_act=q)
    assert read_pose_file(path).q_act[1, 2] == 1000.0  # the file alone has no limits
    with pytest.raises(ActuatorRangeError, match="p.csv data row 2, column 'leg3_slide'"):
        read_pose_rows(path, hexa)


def test_joint_without_range_is_exempt(tmp_path):
    urdf = """<robot name="r"><link name="base"/><link name="tool"/>
<joint name="spin" type="continuous"><parent link="base"/><child link="tool"/>
<origin xyz="0 0 0.1"/><axis xyz="0 0 1"/></joint></robot>"""
    (tmp_path / "r.urdf").write_text(urdf)
    mech = load_mechanism(tmp_path / "r.urdf")
    path = write_commands(tmp_path / "c.csv", mech.actuated, np.array([[1000.0]]))
    assert read_commands(path, mech)[1][0, 0] == 1000.0


# --- bullet 6: clipped values ------------------------------------------------------------


def test_huge_header_and_cell_values_are_clipped(tmp_path, hexa, good_csv):
    text = good_csv.read_text().replace("# kind: pose", "# kind: " + "p" * 100_000)
    good_csv.write_text(text)
    with pytest.raises(MeasurementFormatError, match="kind 'ppp") as exc:
        read_measurement_file(good_csv, hexa)
    assert len(str(exc.value)) < 400
    path = write_commands(tmp_path / "c.csv", hexa.actuated, np.zeros((1, 6)))
    path.write_text(path.read_text().replace("0.0,", "x" * 100_000 + ",", 1))
    with pytest.raises(BadValueError) as exc2:
        read_commands(path, hexa)
    assert len(str(exc2.value)) < 400


# --- every data-file option of the CLI against each bad-file class ---------------------

_COMMANDS = {
    "calibrate": lambda f, out: ["calibrate", "hexaslide_6pus", "--data", f, "--out", out],
    "simulate": lambda f, out: ["simulate", "hexaslide_6pus", "--poses", f, "--out", out],
    "compensate": lambda f, out: ["compensate", "hexaslide_6pus", "--targets", f, "--out", out],
    "view": lambda f, out: ["view", "hexaslide_6pus", "--poses", f, "--html", out],
    "acceptance": lambda f, out: ["acceptance", "hexaslide_6pus", "--data", f, "--out", out],
    "import-tracker": lambda f, out: [
        "import-tracker",
        f,
        "--log",
        f,
        "--targets",
        f,
        "--model",
        "hexaslide_6pus",
        "--out",
        out,
    ],
}


def _bad_file(kind: str, tmp_path: Path, monkeypatch) -> str:
    path = tmp_path / "bad.csv"
    if kind == "device":
        return "/dev/zero"
    if kind == "directory":
        path.mkdir()
    elif kind == "too_big":
        path.write_bytes(b"# pincal measurements 1\n" + b"0," * 700_000)
        monkeypatch.setenv("PINCAL_MAX_FILE_MB", "1")
    elif kind == "huge_cell":
        path.write_text("# pincal poses 1\n# length_unit: m\nx,y,z\n" + "1" * 200_000 + ",0,0\n")
    elif kind == "not_utf8":
        path.write_bytes(b"# pincal poses 1\nx,y,z\n\xff\xfe,0,0\n")
    return str(path)


@pytest.mark.parametrize("kind", ["device", "directory", "too_big", "huge_cell", "not_utf8"])
@pytest.mark.parametrize("command", sorted(_COMMANDS))
def test_every_data_option_fails_cleanly_on_bad_files(tmp_path, monkeypatch, command, kind):
    if kind == "device" and not Path("/dev/zero").exists():
        pytest.skip("no /dev/zero")
    f = _bad_file(kind, tmp_path, monkeypatch)
    res = _cli(*_COMMANDS[command](f, str(tmp_path / "out.x")))
    assert_clean_failure(res, Path(f).name)

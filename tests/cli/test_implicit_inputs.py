"""Files a command reads without naming them are inputs too (issue 38, item 6).

A model directory stands for its URDF and sidecar, a calibration directory for its own
files, the nominal model it was fitted on and (``validate --cv``) its data file: an
output naming one of them is refused before any work, the file unchanged. Before,
``validate --out`` overwrote the nominal URDF (and the calibration's own
calibrated.urdf), ``validate --cv --folds-out`` the data file the folds were read from,
``simulate`` and ``compensate --out`` the model's sidecar.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest
from click.testing import CliRunner

from pincal.cli import main

MODELS = Path(__file__).resolve().parents[2] / "models"


@pytest.fixture(scope="module")
def local(tmp_path_factory) -> Path:
    """A copy of wedge3 as a local model directory, m.csv and its calibration cal/."""
    d = tmp_path_factory.mktemp("implicit")
    shutil.copytree(MODELS / "wedge3", d / "wedge3")
    runner = CliRunner()
    for args in (
        ["simulate", str(d / "wedge3"), "--random", "12", "--out", str(d / "m.csv")],
        ["calibrate", str(d / "wedge3"), "--data", str(d / "m.csv"), "--params", "patent",
         "--out", str(d / "cal")],
    ):  # fmt: skip
        res = runner.invoke(main, args)
        assert res.exit_code == 0, res.output
    (d / "targets.csv").write_bytes((d / "m.csv").read_bytes())
    return d


def _refused(args: list, victim: Path, named: str) -> None:
    before = victim.read_bytes()
    res = CliRunner().invoke(main, [str(a) for a in args])
    assert res.exit_code == 1, res.output
    line = res.output.strip().splitlines()[-1]
    assert line.startswith("pincal: error: OutputPathError: "), res.output
    assert named in line and "inputs are never modified" in line, line
    assert victim.read_bytes() == before, f"{victim} was modified"


def test_validate_out_is_the_nominal_model_the_calibration_loads(local):
    urdf = local / "wedge3" / "wedge3.urdf"
    _refused(["validate", local / "cal", "--data", local / "m.csv", "--out", urdf], urdf,
             "CALIBRATION's nominal model")  # fmt: skip


def test_validate_out_is_a_file_of_the_calibration(local):
    own = local / "cal" / "calibrated.urdf"
    _refused(["validate", local / "cal", "--data", local / "m.csv", "--out", own], own,
             "CALIBRATION's calibrated.urdf")  # fmt: skip
    # a new file beside them stays allowed (the README's validate --out cal/validation.json)
    res = CliRunner().invoke(main, ["validate", str(local / "cal"), "--data",
                                    str(local / "m.csv"), "--out",
                                    str(local / "cal" / "validation.json")])  # fmt: skip
    assert res.exit_code == 0, res.output


def test_validate_folds_out_is_the_data_file_cv_reads(local):
    data = local / "m.csv"
    _refused(["validate", local / "cal", "--cv", "3", "--folds-out", data], data,
             "CALIBRATION's data file")  # fmt: skip


def test_simulate_and_compensate_out_are_the_model_sidecar(local):
    side = local / "wedge3" / "wedge3.yaml"
    _refused(["simulate", local / "wedge3", "--random", "3", "--out", side], side,
             "MODEL's sidecar")  # fmt: skip
    _refused(["compensate", local / "cal", "--targets", local / "targets.csv", "--out", side],
             side, "CALIBRATION's nominal model's sidecar")  # fmt: skip

"""An instrument file's joint readings under its ``# joint_reference:`` header, both ways.

A simulated UR5 ballbar file (absolute readings) and the same readings written relative
to a reference — the home pose, or joint values given by name — with the header that
says so: the two calibrations agree. Declared relative when they are absolute, the fit
moves the joint zeros by the reference and is refused, naming the joint reference.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.model import load_mechanism

PAIRS = "shoulder_lift_joint=0.3 wrist_2_joint=-0.3"


def _run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


@pytest.fixture(scope="module")
def ballbar(tmp_path_factory):
    """A UR5 ballbar file of 40 random poses (absolute readings) and its calibration."""
    d = tmp_path_factory.mktemp("ballbar")
    r = _run("simulate", "ur5", "--random", "40", "--instrument", "distance",
             "--errors", "seed:3", "--seed", "1", "--out", d / "b.csv")  # fmt: skip
    assert r.exit_code == 0, r.output
    r = _run("calibrate", "ur5", "--data", d / "b.csv", "--out", d / "cal")
    assert r.exit_code == 0, r.output
    return d


def _reference(text: str) -> np.ndarray:
    """The actuator values [rad] a ``# joint_reference:`` entry names on the UR5."""
    mech = load_mechanism("ur5")
    if text == "home":
        return np.asarray(mech.actuators_of(mech.q_home), dtype=float)
    ref = np.zeros(len(mech.actuated))
    for pair in text.split():
        joint, value = pair.split("=")
        ref[mech.actuated.index(joint)] = float(value)
    return ref


def _rewrite(src, dst, shift: np.ndarray, declare: str):
    """``src``'s joint readings minus ``shift``, under ``# joint_reference: declare``."""
    lines = src.read_text().splitlines()
    k = next(i for i, ln in enumerate(lines) if not ln.startswith("#"))
    rows = []
    for ln in lines[k + 1:]:
        cells = ln.split(",")
        q = [f"{float(v) - s:.17g}" for v, s in zip(cells[:-1], shift, strict=True)]
        rows.append(",".join([*q, cells[-1]]))
    dst.write_text("\n".join([*lines[:k], f"# joint_reference: {declare}", lines[k], *rows]) + "\n")
    return dst


def _values(cal) -> dict[str, float]:
    doc = json.loads((cal / "calibration.json").read_text())
    return {p["name"]: p["value"] for p in doc["parameters"]}


@pytest.mark.parametrize("reference", ["home", PAIRS])
def test_relative_readings_declared_give_the_absolute_files_calibration(ballbar, tmp_path,
                                                                        reference):
    ref = _reference(reference)
    assert np.abs(ref).max() > 0.1  # the shift is large enough to be seen
    rel = _rewrite(ballbar / "b.csv", tmp_path / "rel.csv", ref, reference)
    r = _run("calibrate", "ur5", "--data", rel, "--out", tmp_path / "cal")
    assert r.exit_code == 0, r.output
    a, b = _values(ballbar / "cal"), _values(tmp_path / "cal")
    assert a.keys() == b.keys()
    assert max(abs(a[n] - b[n]) for n in a) < 1e-6  # m, rad: the same fit


def test_absolute_readings_declared_relative_are_refused(ballbar, tmp_path):
    wrong = _rewrite(ballbar / "b.csv", tmp_path / "wrong.csv", np.zeros(6), PAIRS)
    r = _run("calibrate", "ur5", "--data", wrong, "--out", tmp_path / "cal")
    assert r.exit_code != 0, r.output
    line = r.output.strip().splitlines()[-1]
    assert line.startswith("pincal: error: QualityGateError:"), line
    assert "Likely cause: joint reference" in line and "shoulder_lift_joint.offset" in line
    assert not (tmp_path / "cal").exists()

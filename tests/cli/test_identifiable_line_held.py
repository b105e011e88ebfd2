"""The ``identifiable:`` line of `pincal calibrate` says what the fit held at nominal
(issue 36): a parameter the analysis calls identifiable but the declared noise places
only beyond 20 mm / 0.1 rad (1σ) is counted, its reason and name given, on the pose
route and the marker route alike, in report.txt, identification.json and report.md."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from click.testing import CliRunner

from pincal.cli import main
from pincal.identification import MarginalBound, held_at_nominal, identify, with_held
from pincal.io import read_identification
from pincal.measure import NoiseModel, simulate_measurements
from pincal.model import load_mechanism, sample_actuators
from pincal.report import calibration_text
from pincal.sensitivity import PLACEMENT_BOUND, parameters

FOURBAR = Path(__file__).parents[1] / "model" / "mjcf" / "fourbar.xml"
LINE = ("identifiable: 10 of 10 parameters (1 held at nominal: placed beyond 20 mm / "
        "0.1 rad (1σ) by the poses — pin_C_1_frame.tx)")  # fmt: skip


def _run(*args: object):
    res = CliRunner().invoke(main, [str(a) for a in args])
    assert res.exit_code == 0, res.output + repr(res.exception)
    return res


def test_pose_route_counts_the_held_parameter(tmp_path):
    # the four-bar measured at its rocker's pivot: pin_C_1_frame.tx is placed to ~0.7 m
    data = tmp_path / "m.csv"
    _run("simulate", FOURBAR, "--random", 30, "--params", "base", "--errors", "seed:3",
         "--error-size", "0.2,1", "--out", data)  # fmt: skip
    res = _run("calibrate", FOURBAR, "--data", data, "--params", "base", "--out", tmp_path / "c")
    assert LINE in res.stdout.splitlines()
    assert LINE in (tmp_path / "c" / "report.txt").read_text(encoding="utf-8").splitlines()
    doc = json.loads((tmp_path / "c" / "identification.json").read_text(encoding="utf-8"))
    assert doc["held_at_nominal"]["names"] == ["pin_C_1_frame.tx"]
    # the record read back gives the same line, and report.md's section says it apart
    record = read_identification(tmp_path / "c" / "identification.json")
    assert held_at_nominal(record.annotations)[0] == ("pin_C_1_frame.tx",)
    assert LINE in calibration_text(record).splitlines()
    _run("report", tmp_path / "c", "--out", tmp_path / "r")
    md = next((tmp_path / "r").glob("*.md")).read_text(encoding="utf-8")
    assert ("Held at nominal although identifiable (placed beyond 20 mm / 0.1 rad (1σ) by "
            "the poses): pin_C_1_frame.tx.") in md  # fmt: skip
    assert "not identifiable): pin_C_1_frame.tx" not in md


def test_marker_route_records_its_held_parameters_in_the_same_form():
    mech = load_mechanism("wedge3")
    params = parameters(mech, "patent")
    rng = np.random.default_rng(0)
    meas = simulate_measurements(mech, sample_actuators(mech, 12, rng), NoiseModel(0.01, 0.02),
                                 rng)  # fmt: skip
    result = identify(mech, params, meas)
    names = params.names[:5]
    # what fit_markers records for the parameters its marginal bound (the default) held
    reason = f"placed beyond {MarginalBound(*PLACEMENT_BOUND).describe()} by the poses"
    marked = with_held(result, names, reason)
    line = next(t for t in calibration_text(marked).splitlines() if t.startswith("identifiable"))
    s = marked.identifiability_summary
    assert s is not None
    assert line == (
        f"identifiable: {s.rank} of {s.parameters} parameters (5 held at nominal: placed "
        f"beyond 20 mm / 0.1 rad (2σ) by the poses — {', '.join(names[:3])} and 2 more)"
    )
    # nothing held: the line is the plain count, as before
    assert f"identifiable: {s.rank} of {s.parameters} parameters\n" in calibration_text(
        with_held(result, (), reason))

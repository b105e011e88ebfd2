"""A pose file calibrated from Python (pincal.workflow) as `pincal calibrate` does it.

The same simulated wedge3 file is calibrated by the command and by the workflow's
functions: the same parameters and σ, the same verdict; the workflow reports its steps
through :class:`pincal.workflow.Steps` and prints nothing.
"""

from __future__ import annotations

import json
from contextlib import contextmanager

import numpy as np
import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.errors import QualityGateError
from pincal.identification import GateLimits
from pincal.model import load_mechanism
from pincal.workflow import Steps, calibrate_pose_file, pose_parameters, pose_problem


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    path = tmp_path_factory.mktemp("pose") / "m.csv"
    res = CliRunner().invoke(main, ["simulate", "wedge3", "--random", "40", "--errors",
                                    "seed:2", "--noise", "0.005,0.01", "--seed", "3",
                                    "--out", str(path)])  # fmt: skip
    assert res.exit_code == 0, res.output
    return path


def test_the_workflow_fits_what_the_command_fits(data, tmp_path, capsys):
    res = CliRunner().invoke(main, ["calibrate", "wedge3", "--data", str(data), "--out",
                                    str(tmp_path / "cal"), "--json"])  # fmt: skip
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout)
    said, counted, iterations = [], [], []

    @contextmanager
    def iterate(label):
        iterations.append(label)
        yield lambda i, cost: None

    @contextmanager
    def count(label):
        counted.append(label)
        yield lambda done, total: None

    mech = load_mechanism("wedge3")
    preset, params = pose_parameters(mech, None, ())
    assert preset == next(iter(mech.presets))
    problem = pose_problem(mech, params, data, GateLimits(), force=False)
    run = calibrate_pose_file(problem, "gauss-newton",
                              steps=Steps(say=said.append, iterations=iterate,
                                          counted=count))  # fmt: skip
    assert capsys.readouterr().out == ""
    assert said[0].startswith(f"identifying {problem.rank} of {len(params)} parameters")
    assert iterations == ["identifying"] and counted == ["bootstrap refits"]
    assert run.verdict.passed and run.uncertainty is not None and run.notes == ()
    by_name = {p["name"]: p for p in doc["parameters"]}
    names = run.result.names
    assert sorted(names) == sorted(by_name)
    values = np.array([by_name[n]["value"] for n in names])
    np.testing.assert_allclose(run.result.full_values, values, rtol=1e-9, atol=1e-12)
    fitted = [n for n, k in zip(names, run.result.identified, strict=True) if k]
    std = np.array([by_name[n]["std"] for n in fitted])
    np.testing.assert_allclose(run.result.std, std, rtol=1e-6, atol=1e-15)


def test_a_refused_file_stops_before_the_fit_unless_forced(data, tmp_path):
    mm = tmp_path / "mm.csv"  # the positions written in mm while the header says m
    lines = data.read_text().splitlines()
    head = [ln for ln in lines if ln.startswith("#")]
    rows = [ln for ln in lines if not ln.startswith("#")]
    cols = rows[0].split(",")
    xyz = [cols.index(c) for c in ("x", "y", "z") if c in cols]
    assert xyz, cols
    scaled = [rows[0]]
    for row in rows[1:]:
        v = row.split(",")
        for i in xyz:
            v[i] = repr(float(v[i]) * 1e3)
        scaled.append(",".join(v))
    mm.write_text("\n".join([*head, *scaled]) + "\n")
    mech = load_mechanism("wedge3")
    _, params = pose_parameters(mech, None, ())
    with pytest.raises(QualityGateError):
        pose_problem(mech, params, mm, GateLimits(), force=False)
    problem = pose_problem(mech, params, mm, GateLimits(), force=True)
    assert not problem.data.passed

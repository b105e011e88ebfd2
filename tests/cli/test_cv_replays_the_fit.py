"""`validate --cv` of a pose-file calibration refits every fold as calibrate ran it.

A wedge3 campaign with one pose moved by 3 mm, calibrated with ``--method lm --loss
huber`` and a declared noise: the cross-validation's held-out errors are those of the
same robust fit with the same noise, computed here fold by fold, not of least squares.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.identification import LMOptions, identify
from pincal.io import read_calibration, read_measurement_file
from pincal.sensitivity import parameters
from pincal.validation import cross_validate


def _run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def test_cv_replays_loss_and_declared_noise(tmp_path):
    assert _run("simulate", "wedge3", "--random", 30, "--seed", 5,
                "--out", tmp_path / "m.csv").exit_code == 0  # fmt: skip
    lines = (tmp_path / "m.csv").read_text().splitlines()
    head = next(i for i, line in enumerate(lines) if not line.startswith("#"))
    cols = lines[head].split(",")
    row = lines[head + 7].split(",")
    x = cols.index("x")
    row[x] = repr(float(row[x]) + 0.003)  # one pose 3 mm off along x
    lines[head + 7] = ",".join(row)
    (tmp_path / "m.csv").write_text("\n".join(lines) + "\n")
    r = _run("calibrate", "wedge3", "--data", tmp_path / "m.csv", "--method", "lm",
             "--loss", "huber", "--noise", "0.01,0.05", "--out", tmp_path / "cal")  # fmt: skip
    assert r.exit_code == 0, r.output
    out = _run("validate", tmp_path / "cal", "--cv", 3, "--json")
    assert out.exit_code == 0, out.output
    cv = json.loads(out.output)["cv"]
    cal = read_calibration(tmp_path / "cal")
    nominal = cal.nominal()
    meas = read_measurement_file(tmp_path / "m.csv", nominal).measurements
    params = parameters(nominal, cal.preset)

    def fit(loss):
        opts = LMOptions(loss=loss)
        noise = {"position": 0.01, "orientation": 0.05}
        return lambda m: identify(nominal, params, m, "lm", noise=noise,
                                  options=opts).calibrated_mechanism  # fmt: skip

    huber = cross_validate(fit("huber"), meas, 3, 0).rms
    linear = cross_validate(fit("linear"), meas, 3, 0).rms
    assert abs(huber - linear) > 1e-3 * huber  # the two procedures differ here
    assert cv["held_out_rms_mm"] == pytest.approx(huber * 1e3, rel=1e-9)
    assert np.isfinite(cv["baseline"]["held_out_rms_mm"])

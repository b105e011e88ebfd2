"""`pincal calibrate` on a file without a noise header: estimated, or --noise; --loss."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
from click.testing import CliRunner

import pincal
from pincal.cli import main
from pincal.io import write_measurements


@pytest.fixture(scope="module")
def bare_file(tmp_path_factory, stewart, stewart42, stewart_poses):
    rng = np.random.default_rng(31)
    truth = rng.normal(0.0, 3e-4, len(stewart42))
    noise = pincal.NoiseModel(0.01, 0.02)
    meas = pincal.simulate_measurements(stewart42.apply(stewart, truth), stewart_poses, noise, rng)
    path = tmp_path_factory.mktemp("data") / "m.csv"
    write_measurements(path, dataclasses.replace(meas, noise=None))
    assert "noise" not in path.read_text()
    return path


def _run(path, out, *extra):
    args = ["calibrate", "stewart_6ups", "--data", str(path), "--out", str(out), "--json"]
    return CliRunner().invoke(main, [*args, *extra])


def test_no_noise_header_is_estimated(bare_file, tmp_path):
    res = _run(bare_file, tmp_path / "a")
    assert res.exit_code == 0, res.output
    w = json.loads(res.stdout)["weighting"]
    assert w["source"] == "estimated"
    assert w["position_std"] == pytest.approx(1e-5, rel=0.3)
    assert w["orientation_std"] == pytest.approx(2e-5, rel=0.3)


def test_noise_option_and_loss(bare_file, tmp_path):
    res = _run(bare_file, tmp_path / "b", "--noise", "0.01,0.02")
    assert res.exit_code == 0, res.output
    w = json.loads(res.stdout)["weighting"]
    assert w["source"] == "declared" and w["position_std"] == pytest.approx(1e-5)
    res = _run(bare_file, tmp_path / "c", "--loss", "huber")  # Gauss–Newton, re-weighted
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout)["weighting"]["loss"] == "huber"
    res = _run(bare_file, tmp_path / "c2", "--loss", "huber", "--method", "qpso")
    assert res.exit_code != 0 and "gauss-newton or lm" in res.output
    res = _run(bare_file, tmp_path / "d", "--noise", "0.01")
    assert res.exit_code != 0 and "pos_mm,ori_mrad" in res.output


@pytest.mark.slow
def test_robust_loss_from_the_command_line(bare_file, tmp_path):
    res = _run(bare_file, tmp_path / "e", "--method", "lm", "--loss", "soft_l1", "--noise",
               "0.01,0.02")  # fmt: skip
    assert res.exit_code == 0, res.output
    w = json.loads(res.stdout)["weighting"]
    assert w["loss"] == "soft_l1" and w["f_scale"] == pytest.approx(np.sqrt(3.0))
    assert len(w["pose_weights"]) == 30

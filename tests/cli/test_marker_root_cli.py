"""``pincal calibrate --link LINK --root ROOT``: a humanoid's marker chain from its sole.

The table is simulated with Pinocchio's model of TALOS as shipped (``reroot_sim``);
the calibration records the root, and ``validate --cv`` replays the re-rooted chain.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.measure import MarkerSetup, marker_mechanism
from pincal.model import sample_actuators
from tests.identification.reroot_sim import marker_points, perturbed_model

ROOT, LINK = "left_sole_link", "arm_left_7_link"


def _run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def _table(path, n: int) -> None:
    mech = marker_mechanism("talos", MarkerSetup(LINK, root=ROOT))
    q = sample_actuators(mech, n, np.random.default_rng(3))
    P = marker_points(perturbed_model("talos", 1e-3, 0), ROOT, LINK, mech.actuated, q, 1e-4, 4)
    lines = [",".join([*mech.actuated, "x", "y", "z"])]
    for qi, p in zip(q, P, strict=True):
        lines.append(",".join(repr(float(v)) for v in (*qi, *(p * 1e3))))
    path.write_text("\n".join(lines) + "\n")


def test_root_needs_a_marker_table(tmp_path):
    r = _run("calibrate", "talos", "--root", ROOT, "--data", tmp_path / "x.csv",
             "--out", tmp_path / "cal")  # fmt: skip
    assert r.exit_code != 0 and "--root" in r.output


@pytest.mark.slow
def test_calibrate_from_the_sole_and_cross_validate(tmp_path):
    _table(tmp_path / "m.csv", 80)
    r = _run("calibrate", "talos", "--link", LINK, "--root", ROOT, "--data", tmp_path / "m.csv",
             "--length-unit", "mm", "--prior", "30,30", "--out", tmp_path / "cal",
             "--json")  # fmt: skip
    assert r.exit_code == 0, r.output
    cal = json.loads((tmp_path / "cal" / "calibration.json").read_text())
    assert cal["markers"]["root"] == ROOT
    assert "leg_left_6_joint_reversed" in (tmp_path / "cal" / "nominal.urdf").read_text()
    r = _run("validate", tmp_path / "cal", "--cv", "5", "--seed", "0", "--json")
    assert r.exit_code == 0, r.output
    cv = json.loads(r.output.splitlines()[-1])["cv"]
    held, baseline = cv["held_out_rms_mm"], cv["baseline"]["held_out_rms_mm"]
    # the 99 parameters fitted on 64 poses per fold; √3·0.1 mm of noise on each new point
    assert held < 0.35 and baseline > 3.0

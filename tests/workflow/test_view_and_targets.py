"""The workflow behind ``pincal view`` and ``pincal compensate --targets``, called directly.

A targets file's nominal commands are put in the machine's actuator order whatever the
file's column order; the poses a view draws are the file's followed by the random ones,
closed into configurations; a calibration that changes nothing moves no prediction.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from pincal.io import PoseFile
from pincal.model import load_mechanism, sample_actuators
from pincal.workflow import nominal_starts, prediction_changes, view_poses


def test_nominal_starts_follow_the_machines_actuator_order():
    mech = load_mechanism("stewart_6ups")
    q = sample_actuators(mech, 3, np.random.default_rng(0))
    order = list(reversed(range(len(mech.actuated))))
    pf = PoseFile([pin.SE3.Identity()] * 3, ("x", "y", "z"),
                  tuple(mech.actuated[k] for k in order), q[:, order])  # fmt: skip
    starts, note = nominal_starts(pf, mech)
    assert starts is not None and np.array_equal(starts, q)
    assert "3 in the targets file" in note
    none, why = nominal_starts(PoseFile(pf.poses, pf.components), mech)
    assert none is None and "nearest solved" in why
    other = PoseFile(pf.poses, pf.components, ("a", "b"), q[:, :2])
    none, why = nominal_starts(other, mech)
    assert none is None and "are not the machine's" in why


def test_view_poses_are_the_files_then_the_random_ones(tmp_path):
    mech = load_mechanism("wedge3")
    rows = sample_actuators(mech, 2, np.random.default_rng(5))
    path = tmp_path / "poses.csv"
    lines = [",".join(mech.actuated), *(",".join(f"{v:.17g}" for v in r) for r in rows)]
    path.write_text("\n".join(lines) + "\n")
    poses = view_poses(mech, path, 3, seed=7)
    drawn = sample_actuators(mech, 3, np.random.default_rng(7))
    assert len(poses) == 5 and np.allclose(poses.rows, np.vstack([rows, drawn]), atol=1e-15)
    assert poses.configurations.shape == (5, mech.model.nq)
    for row, q in zip(poses.rows, poses.configurations, strict=True):
        assert np.allclose(mech.actuators_of(q), row, atol=1e-9)
    assert len(view_poses(mech, None, None, seed=0)) == 5
    same = prediction_changes(mech, mech, poses)
    assert same.nominal.shape == (5, 3) and same.largest_mm == 0.0
    assert np.array_equal(same.nominal, same.calibrated)

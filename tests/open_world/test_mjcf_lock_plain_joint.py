"""Machine style: the MJCF toe leg of test_mjcf_spring_lock with a plain toe hinge (no
``stiffness``): the user locks it in the sidecar all the same (issue 36, item 6: a
``lock:`` on a joint without a spring raised an uncaught ``KeyError``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

from pincal.errors import MobilityError
from pincal.model import load_mjcf
from tests.open_world.roster import mjcf_toe_leg


def _write(folder: Path, sidecar: dict) -> Path:
    text = mjcf_toe_leg()
    spring = 'range="-30 30" stiffness="5"'
    assert spring in text
    path = folder / "toe_leg_plain.xml"
    path.write_text(text.replace(spring, 'range="-30 30"'), encoding="utf-8")
    path.with_suffix(".yaml").write_text(yaml.safe_dump(sidecar), encoding="utf-8")
    return path


def test_a_plain_joint_locks_like_a_spring_one(tmp_path):
    side = {"measured_frame": "tool", "measured": "position", "lock": {"toe_joint": 0.2}}
    mech = load_mjcf(_write(tmp_path, side))
    assert "toe_joint" not in list(mech.model.names) and mech.actuated == ("crank_joint",)
    said = [n for n in mech.notes if n.startswith("locked")]
    assert said and "toe_joint = 0.2" in said[0] and "spring" not in said[0].split("toe")[1]
    assert np.all(np.isfinite(mech.forward(np.array([-0.3])).translation))


def test_locking_a_loop_joint_is_a_mobility_error_not_a_traceback(tmp_path):
    """The coupler hinge is inside the four-bar: locked, the crank cannot turn."""
    side = {"measured_frame": "coupler", "lock": {"coupler_joint": "home", "toe_joint": 0}}
    with pytest.raises(MobilityError, match="mobility 0"):
        load_mjcf(_write(tmp_path, side))

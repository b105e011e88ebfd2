"""Machine style: a new user's Delta whose rod ends are plain revolutes (issue 36).

The rods must be ball-ended; the mobility error names every elbow and gives the sidecar
text (robot.yaml joint kinds) that declares them spherical, and that text loads.
"""

from __future__ import annotations

import re

import pytest
import yaml

from pincal.errors import ClosureError, MobilityError
from pincal.model import load_mechanism
from tests.open_world.first_machines import delta_elbows
from tests.open_world.machines import ankle_2rsu, write_machine

ELBOWS = [f"elbow{i}{s}" for i in (1, 2, 3) for s in "ab"]


def test_mobility_error_names_every_elbow_and_the_override(tmp_path):
    with pytest.raises(MobilityError) as info:
        load_mechanism(write_machine(tmp_path, "delta", *delta_elbows("revolute")))
    text = str(info.value)
    assert "has mobility 1" in text and "\n" not in text
    names = re.search(r"'joint_name: \[([^\]]*)\]' and 'joint_type: SPHERICAL'", text)
    assert names is not None, text
    assert names.group(1).split(", ") == ELBOWS
    assert "the mobility is then 3, the 3 actuated joints" in text


def test_the_hinted_text_loads(tmp_path):
    urdf, sidecar = delta_elbows("revolute")
    with pytest.raises(MobilityError) as info:
        load_mechanism(write_machine(tmp_path / "bad", "delta", urdf, sidecar))
    quoted = re.findall(r"'(joint_(?:name|type): [^']*)'", str(info.value))
    sidecar.update(yaml.safe_load("\n".join(quoted)))  # the user pastes the two lines
    mech = load_mechanism(write_machine(tmp_path / "good", "delta", urdf, sidecar))
    assert mech.mobility == 3
    j = mech.model.getJointId("elbow2b")
    assert mech.model.joints[j].shortname() == "JointModelSpherical"


def test_no_hint_when_joint_kinds_are_not_the_cause(tmp_path):
    urdf, sidecar = ankle_2rsu()
    with pytest.raises(MobilityError) as info:
        load_mechanism(write_machine(tmp_path, "ankle", urdf, {**sidecar, "name_mot": ["mot_l"]}))
    assert "SPHERICAL" not in str(info.value)


@pytest.mark.parametrize("tilt, said", [(0.05, "16.9 mm"), (1e-5, "1.79 µm")])
def test_open_loop_names_the_residual_and_the_ball_ends(tmp_path, tilt, said):
    """Rod 1a drawn off its anchor: the revolute elbows cannot close the loop (before:
    "stays open … the geometry probably cannot close this loop", no joint kind named);
    the refusal names the residual in readable units and the ball ends, and the quoted
    sidecar text loads."""
    urdf, sidecar = delta_elbows("revolute", rod_tilt=tilt)
    with pytest.raises(ClosureError) as info:
        load_mechanism(write_machine(tmp_path / "bad", "delta", urdf, sidecar))
    text = str(info.value)
    assert f"stays open (residual {said}" in text and "\n" not in text
    assert "ball ends can" in text
    quoted = re.findall(r"'(joint_(?:name|type): [^']*)'", text)
    assert yaml.safe_load(quoted[0])["joint_name"] == ELBOWS
    sidecar.update(yaml.safe_load("\n".join(quoted)))
    assert load_mechanism(write_machine(tmp_path / "good", "delta", urdf, sidecar)).mobility == 3

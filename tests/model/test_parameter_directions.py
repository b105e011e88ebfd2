"""Parameters described and chosen by their direction in the parent link's frame.

On the planar 3-RRR of tests/model/machines/rrr3, written with link directions in the
joint origins' rpy (base1 turned -90° about z, base2 +30°): ``base1.tx`` moves the joint
along the parent's -y, not x.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.errors import ParameterError
from pincal.model import direction_record, load_mechanism, parameters, parent_direction

RRR3 = Path(__file__).resolve().parent / "machines" / "rrr3"


@pytest.fixture(scope="module")
def rrr3():
    return load_mechanism(str(RRR3))


def test_direction_is_what_the_parameter_does_in_the_parent_frame(rrr3):
    """Displace each parameter by δ and see where the joint origin goes, in the parent."""
    params = parameters(rrr3, "full")
    delta = 1e-6
    for name in ("base1.tx", "base1.ty", "base2.tx", "base1.rx", "base1.offset", "elbow1.tx"):
        i = params.index(name)
        p = params.parameters[i]
        x = np.zeros(len(params))
        x[i] = delta
        moved = params.apply(rrr3, x).tree.joints[p.joint].origin
        before = rrr3.tree.joints[p.joint].origin
        kind, d = parent_direction(rrr3, p.joint, p.twist)
        if kind == "translation":
            observed = (moved.translation - before.translation) / delta
        else:
            observed = pin.log3(moved.rotation @ before.rotation.T) / delta
        assert np.allclose(observed, d, atol=1e-6), (name, observed, d)
    # the rpy of the file: base1 turned -90° about z, so its tx runs along parent -y
    assert np.allclose(parent_direction(rrr3, "base1", np.eye(6)[0])[1], [0, -1, 0], atol=1e-6)


def test_preset_entries_by_parent_direction(rrr3):
    assert parameters(rrr3, [{"joints": "base1", "along_parent": "y"}]).names == ("base1.tx",)
    assert parameters(rrr3, [{"joints": "base1", "about_parent": "z"}]).names == ("base1.offset",)
    oblique = [{"joints": "base2", "along_parent": [0.866025, 0.5, 0]}]
    assert parameters(rrr3, oblique).names == ("base2.tx",)
    # hold: leave out what the entry names from the parameters listed before it
    full = parameters(rrr3, [{"joints": "base*", "dofs": ["tx", "ty"]}])
    held = parameters(rrr3, [{"joints": "base*", "dofs": ["tx", "ty"]},
                             {"joints": "base1", "along_parent": "x", "hold": True}])  # fmt: skip
    assert set(full.names) - set(held.names) == {"base1.ty"}


def test_bad_direction_entries_are_named(rrr3):
    with pytest.raises(ParameterError, match=r"base2.*no translation along parent direction "
                       r"\[1, 0, 0\].*base2.tx \[0.866, 0.5, 0\]"):  # fmt: skip
        parameters(rrr3, [{"joints": "base2", "along_parent": "x"}])
    with pytest.raises(ParameterError, match="x, y, z or a non-zero direction"):
        parameters(rrr3, [{"joints": "base1", "along_parent": "w"}])
    with pytest.raises(ParameterError, match="none of which is listed before it"):
        parameters(rrr3, ["elbow1.tx", {"joints": "base1", "along_parent": "y", "hold": True}])
    with pytest.raises(ParameterError, match="one of 'dofs'"):
        parameters(rrr3, [{"joints": "base1", "dofs": ["tx"], "along_parent": "y"}])


def test_info_shows_each_parameter_in_the_parent_frame():
    r = CliRunner().invoke(main, ["info", str(RRR3), "--preset", "full"])
    assert r.exit_code == 0, r.output
    assert ("base1.tx = translation along origin x turned by the origin rpy [0, 0, -1.5708] "
            "→ along parent (world) direction [0, -1, 0]") in r.output  # fmt: skip
    r = CliRunner().invoke(main, ["info", str(RRR3), "--preset", "full", "--json"])
    rec = {d["name"]: d for d in json.loads(r.stdout)["presets"][0]["directions"]}
    assert rec["base1.offset"]["kind"] == "rotation" and rec["base1.offset"]["parent"] == "world"
    assert np.allclose(rec["base1.ty"]["parent_direction"], [1, 0, 0], atol=1e-6)


def test_a_joint_space_term_is_described_without_a_direction():
    mech = load_mechanism("ur5")
    params = parameters(mech, "full+gain")  # the model resolves full; base is sensitivity's
    p = next(q for q in params.parameters if q.dof == "gain")
    rec = direction_record(mech, p.name, p.joint, p.dof, p.twist)
    assert rec["kind"] == "joint term" and rec["parent_direction"] == [0.0, 0.0, 0.0]
    assert "joint-space term 'gain'" in rec["text"]

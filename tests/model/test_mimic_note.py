"""A ``<mimic>`` joint is built as an independent joint: pincal says so (note + warning)."""

from __future__ import annotations

import logging

from pincal.model import load_mechanism

URDF = """<robot name="mimic_pair">
  <link name="base"/><link name="a"/><link name="b"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="a"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="a"/><child link="b"/>
    <origin xyz="0.1 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/><mimic joint="j1" multiplier="2"/>
  </joint>
</robot>
"""


def test_mimic_joint_is_noted_and_warned_once(tmp_path, caplog):
    f = tmp_path / "mimic_pair.urdf"
    f.write_text(URDF)
    with caplog.at_level(logging.WARNING, logger="pincal.model.files._build"):
        mech = load_mechanism(f)
        load_mechanism(f)
    said = [r.getMessage() for r in caplog.records if "mimics" in r.getMessage()]
    assert len(said) == 1 and "'j2' mimics 'j1'" in said[0]
    assert "not modelled" in said[0]
    assert any("'j2' mimics 'j1'" in n for n in mech.notes)


def test_no_note_without_mimic(tmp_path):
    f = tmp_path / "plain.urdf"
    f.write_text(URDF.replace('<mimic joint="j1" multiplier="2"/>', ""))
    assert not any("mimic" in n for n in load_mechanism(f).notes)

"""Derived mechanisms equal the mechanism rebuilt from the moved URDF text.

``Mechanism.with_joint_origins`` writes moved joint origins into a copy of the Pinocchio
model (:mod:`pincal.model._placements`) instead of rebuilding it from text; here every
bundled machine, a serial arm, the test machines and the open-world roster (MJCF
imports, emulated ball and universal joints, locked joints, fixed-joint chains) are
moved by random errors on every origin parameter and compared with the model Pinocchio
builds from the written text: home, every frame placement at random configurations,
body inertias, and the text itself.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from pincal.errors import UnknownNameError
from pincal.model import Mechanism, load_mechanism, sample_actuators
from pincal.sensitivity import parameters
from tests.open_world.roster import ROSTER

BUNDLED = ["stewart_6ups", "hexaslide_6pus", "pkm5", "wedge3", "aacmm", "ur5"]


def _rebuilt(mech: Mechanism) -> Mechanism:
    """The mechanism built anew from the derived one's URDF text, closed from its home."""
    return Mechanism(
        mech.urdf_xml,
        mech.sidecar,
        name=mech.name,
        measured_frame=mech.measured_frame,
        q_guess=mech.q_home,
        options=mech.options,
    )


def _compare(derived: Mechanism, rng: np.random.Generator) -> None:
    rebuilt = _rebuilt(derived)
    a, b = derived.model, rebuilt.model
    assert [f.name for f in a.frames] == [f.name for f in b.frames]
    for k in range(a.njoints):
        assert np.allclose(a.jointPlacements[k].homogeneous, b.jointPlacements[k].homogeneous,
                           atol=1e-13), a.names[k]  # fmt: skip
        assert np.allclose(a.inertias[k].toDynamicParameters(),
                           b.inertias[k].toDynamicParameters(), atol=1e-12), a.names[k]  # fmt: skip
    for fa, fb in zip(a.frames, b.frames, strict=True):
        assert np.allclose(fa.placement.homogeneous, fb.placement.homogeneous, atol=1e-13), fa.name
    assert np.allclose(derived.q_home, rebuilt.q_home, atol=1e-12)
    assert derived.mobility == rebuilt.mobility and derived.home_branch == rebuilt.home_branch
    da, db = a.createData(), b.createData()
    for _ in range(3):
        q = pin.randomConfiguration(a, -np.ones(a.nq), np.ones(a.nq)) if a.nq else np.zeros(0)
        pin.framesForwardKinematics(a, da, q)
        pin.framesForwardKinematics(b, db, q)
        for i in range(a.nframes):
            assert np.allclose(da.oMf[i].homogeneous, db.oMf[i].homogeneous, atol=1e-12)
    q_act = sample_actuators(derived, 4, rng)
    qs = derived.configurations(q_act)
    assert np.allclose(qs, rebuilt.configurations(q_act), atol=1e-10)
    if derived.batch_model.supported:  # the batched kinematics take the moved placements
        ba, bb = derived.kinematics_batch(qs), rebuilt.kinematics_batch(qs)
        assert np.allclose(ba.translations, bb.translations, atol=1e-12)
        assert np.allclose(ba.jacobian, bb.jacobian, atol=1e-12)
        fids = np.arange(a.nframes)
        for x, y in zip(derived.batch_model.frame_placements(ba, fids),
                        rebuilt.batch_model.frame_placements(bb, fids), strict=True):  # fmt: skip
            assert np.allclose(x, y, atol=1e-12)


def _moved(
    mech: Mechanism, rng: np.random.Generator, size: float = 2e-3, preset: str = "full"
) -> Mechanism:
    ps = parameters(mech, preset)
    return ps.apply(mech, rng.uniform(-size, size, len(ps)))


@pytest.mark.parametrize("name", BUNDLED)
def test_a_derived_bundled_machine_is_the_one_built_from_its_text(name: str) -> None:
    rng = np.random.default_rng(7)
    nominal = load_mechanism(name)
    derived = _moved(nominal, rng)
    _compare(derived, rng)
    # derived twice: the second move starts from the first one's origins
    _compare(_moved(derived, rng), rng)
    assert nominal.urdf_xml != derived.urdf_xml


def test_a_derived_arm_with_fixed_joint_chains_is_the_one_built_from_its_text() -> None:
    """TIAGo: a mobile base and an arm behind chains of fixed joints carrying inertias."""
    rng = np.random.default_rng(3)
    _compare(_moved(load_mechanism("tiago", measured_frame="arm_7_link"), rng), rng)


@pytest.mark.parametrize("machine", [m for m in ROSTER if m.refused is None], ids=lambda m: m.name)
def test_a_derived_open_world_machine_is_the_one_built_from_its_text(
    machine, tmp_path: Path
) -> None:
    rng = np.random.default_rng(11)
    nominal = load_mechanism(machine.write(tmp_path))
    _compare(_moved(nominal, rng, 2e-4, "base"), rng)  # base: errors the loops can close


def test_moving_an_unknown_joint_names_the_joints() -> None:
    mech = load_mechanism("ur5")
    with pytest.raises(UnknownNameError, match="no_such_joint"):
        mech.with_joint_origins({"no_such_joint": pin.SE3.Identity()})


def test_the_nominal_mechanism_is_not_modified_by_a_derivation() -> None:
    mech = load_mechanism("stewart_6ups")
    before = [f.placement.homogeneous.copy() for f in mech.model.frames]
    text = mech.urdf_xml
    _moved(mech, np.random.default_rng(0))
    assert mech.urdf_xml == text
    for f, M in zip(mech.model.frames, before, strict=True):
        assert np.array_equal(f.placement.homogeneous, M)

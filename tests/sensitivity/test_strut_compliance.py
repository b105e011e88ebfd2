"""Axial compliance of a hexaslide's fixed-length struts under a payload."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from pincal.errors import ParameterError
from pincal.model import (
    Payload,
    actual_joint_values,
    joint_term_basis,
    load_mechanism,
    sample_actuators,
    strut_loads,
    struts,
    undeflected_commands,
    with_joint_terms,
    with_payload,
)
from pincal.model.params._term_compliance import gravity_model
from pincal.sensitivity import parameters

from .test_joint_terms import _fd_errors

MODELS = Path(__file__).parents[2] / "models"
SPINDLE = Payload(20.0, (0.05, -0.02, 0.10))  # [kg], [m] in the tool frame
STRUTS = tuple(f"leg{i}_tip_joint" for i in range(1, 7))


@pytest.fixture(scope="module")
def hexaslide():
    return load_mechanism(MODELS / "hexaslide_6pus")


@pytest.fixture(scope="module")
def loaded(hexaslide):
    return with_payload(hexaslide, SPINDLE)


def _potential(mech, row: np.ndarray) -> float:
    model = gravity_model(mech)
    return pin.computePotentialEnergy(model, model.createData(), mech.configurations(row[None])[0])


def test_struts_are_the_fixed_length_links(hexaslide, stewart):
    assert struts(hexaslide) == STRUTS
    params = with_joint_terms(hexaslide, parameters(hexaslide, "pus54"), ["strut-compliance"])
    terms = [params.names[k] for k in params.joint_terms]
    assert terms == [f"{s}.strut_compliance" for s in STRUTS]
    assert {params.units[k] for k in params.joint_terms} == {"m/N"}
    assert struts(stewart) == ()  # its legs are actuated: they take 'compliance'
    with pytest.raises(ParameterError, match="no fixed-length strut of 'stewart_6ups'"):
        with_joint_terms(stewart, parameters(stewart, "stewart42"), ["strut-compliance"])
    with pytest.raises(ParameterError, match="not one: its struts are"):
        parameters(hexaslide, ["platform_p1_joint.strut_compliance"])


@pytest.mark.parametrize("with_spindle", [False, True])
def test_strut_forces_are_the_virtual_work_of_the_load(hexaslide, loaded, with_spindle):
    """F_j = dV/dL_j along the closed configurations with the sliders held."""
    mech = loaded if with_spindle else hexaslide
    rows = sample_actuators(mech, 2, np.random.default_rng(3))
    F, _ = strut_loads(mech, rows)
    h = 1e-6  # [m]
    for j, strut in enumerate(STRUTS):
        p = parameters(mech, [f"{strut}.tz"])  # the hexaslide's struts lie along z
        longer, shorter = p.apply(mech, np.array([h])), p.apply(mech, np.array([-h]))
        for row, f in zip(rows, F[:, j], strict=True):
            fd = (_potential(longer, row) - _potential(shorter, row)) / (2 * h)
            assert f == pytest.approx(fd, rel=1e-5, abs=1e-5)
    if with_spindle:  # 20 kg more: the struts push up harder in total
        F0, _ = strut_loads(hexaslide, rows)
        assert np.all(F.sum(axis=1) - F0.sum(axis=1) > 20 * 9.81 * 0.5)


def test_basis_moves_the_platform_as_the_elongation(loaded):
    """The joint change c·F·e reaches the pose the strut elongated by c·F reaches."""
    rows = sample_actuators(loaded, 3, np.random.default_rng(5))
    params = parameters(loaded, [f"{s}.strut_compliance" for s in STRUTS])
    c = np.random.default_rng(6).normal(0.0, 1e-8, 6)  # [m/N]: µm-size elongations
    B = joint_term_basis(loaded, params, rows)
    F, _ = strut_loads(loaded, rows)
    lengths = parameters(loaded, [f"{s}.tz" for s in STRUTS])
    for row, b, f in zip(rows, B, F, strict=True):
        elongated = lengths.apply(loaded, c * f).forward(row)
        moved = loaded.forward(row + b @ c)
        rigid = loaded.forward(row)
        change = np.linalg.norm(pin.log6(rigid.inverse() * elongated).vector)
        miss = np.linalg.norm(pin.log6(moved.inverse() * elongated).vector)
        assert change > 1e-7 and miss < 1e-4 * change


def test_jacobian_matches_finite_differences(loaded):
    params = with_joint_terms(loaded, parameters(loaded, "pus54"), ["strut-compliance"])
    err = _fd_errors(loaded, params, 6, seed=2)
    assert err.max() < 1e-5, params.names[int(np.argmax(err))]


def test_without_link_masses_a_payload_is_needed(hexaslide):
    from pincal.model import Mechanism

    bare = Mechanism(
        hexaslide.urdf_xml.replace('<mass value="0.1"/>', '<mass value="0"/>'),
        hexaslide.sidecar,
        name="bare",
        measured_frame=hexaslide.measured_frame,
    )
    with pytest.raises(ParameterError, match="no link masses"):
        with_joint_terms(bare, parameters(bare, "pus54"), ["strut-compliance"])
    params = with_joint_terms(
        with_payload(bare, SPINDLE), parameters(bare, "pus54"), ["strut-compliance"]
    )
    assert params.joint_terms.size == 6


def _open_world(name: str, folder: Path):
    from tests.open_world import machines

    urdf, sidecar = getattr(machines, name)()
    return load_mechanism(machines.write_machine(folder, name, urdf, sidecar))


def test_struts_of_an_ankle(tmp_path):
    """A 2-RSU ankle (two actuators, 6-D measured): forces = virtual work, and the joint
    change reaches the elongated pose, along each rod's own direction."""
    mech = _open_world("ankle_2rsu", tmp_path)
    names = struts(mech)
    assert names == ("rod_end_l", "rod_end_r")
    rows = sample_actuators(mech, 2, np.random.default_rng(8))
    F, E = strut_loads(mech, rows)
    comps = [("x", "y", "z", "rx", "ry", "rz").index(c) for c in mech.measured_components]
    h = 1e-6  # [m]
    for j, strut in enumerate(names):
        origin = mech.tree.joints[strut].origin
        t = origin.translation / np.linalg.norm(origin.translation)  # the strut, parent frame
        shift = parameters(mech, [f"{strut}.{d}" for d in ("tx", "ty", "tz")])
        step = h * origin.rotation.T @ t  # the translation along t, in the origin's axes
        longer, shorter = shift.apply(mech, step), shift.apply(mech, -step)
        for row, f, e in zip(rows, F[:, j], E[:, j], strict=True):
            fd = (_potential(longer, row) - _potential(shorter, row)) / (2 * h)
            assert f == pytest.approx(fd, rel=1e-5, abs=1e-6)
            rigid = mech.forward(row)
            elongated = longer.forward(row)
            moved = mech.forward(row + h * e)
            d_el = np.concatenate(
                [
                    elongated.translation - rigid.translation,
                    pin.log3(rigid.rotation.T @ elongated.rotation),
                ]
            )[comps]
            d_mv = np.concatenate(
                [moved.translation - rigid.translation, pin.log3(rigid.rotation.T @ moved.rotation)]
            )[comps]
            assert np.linalg.norm(d_el) > 1e-3 * h
            assert np.linalg.norm(d_mv - d_el) < 1e-4 * np.linalg.norm(d_el)


def _check_exact_elongation(mech, params, values, rows) -> None:
    """pincal's deflection is the fixed point δL = c·F of the machine with its struts
    lengthened (built here through placement parameters, not pincal's solver), reached by
    the rigid machine's joints in the measured components; the commands invert it."""
    k = params.joint_terms
    names, c = tuple(params.parameters[i].joint for i in k), values[k]
    joints = actual_joint_values(mech, params, values, rows)
    assert np.max(np.abs(joints - rows)) > 1e-5  # [rad, m]
    shift = parameters(mech, [f"{s}.{d}" for s in names for d in ("tx", "ty", "tz")])
    origins = [mech.tree.joints[s].origin for s in names]
    comps = [("x", "y", "z", "rx", "ry", "rz").index(k) for k in mech.measured_components]
    for u, q in zip(rows, joints, strict=True):
        dL = np.zeros(len(names))
        for _ in range(40):
            step = np.concatenate(
                [d * o.rotation.T @ o.translation / np.linalg.norm(o.translation)
                 for d, o in zip(dL, origins, strict=True)]
            )  # fmt: skip
            longer = shift.apply(mech, step)
            dL = c * strut_loads(longer, u[None], names)[0][0]
        reached, rigid = longer.forward(u), mech.forward(q)
        diff = np.concatenate(
            [rigid.translation - reached.translation, pin.log3(reached.rotation.T @ rigid.rotation)]
        )[comps]
        assert np.max(np.abs(diff)) < 1e-10  # [m, rad]
    back = undeflected_commands(mech, params, values, joints)
    assert np.max(np.abs(back - rows)) < 1e-10  # [rad, m]


def test_an_ankles_struts_lengthen_under_their_own_machines_load(tmp_path):
    """A 2-RSU ankle, 6-D measured, 0.2 mm of sag."""
    mech = _open_world("ankle_2rsu", tmp_path)
    params = parameters(mech, [f"{s}.strut_compliance" for s in struts(mech)])
    rows = sample_actuators(mech, 3, np.random.default_rng(9))
    F0 = strut_loads(mech, rows)[0]
    c = -2e-4 / np.sqrt(np.mean(F0**2)) * np.array([0.7, 1.3])  # [m/N]
    _check_exact_elongation(mech, params, c, rows)


def test_parallelogram_bars_are_refused(tmp_path):
    """A delta's parallelogram bars close over-constrained loops: their force is open;
    its other struts take a compliance and deflect as on the ankle."""
    mech = _open_world("delta_4r", tmp_path)
    assert "wbar_b1" in struts(mech)
    with pytest.raises(ParameterError, match="over-constrained loop"):
        parameters(mech, ["wbar_b1.strut_compliance"])
    params = with_joint_terms(mech, parameters(mech, ["hinge1.offset"]), ["strut-compliance"])
    on = {params.parameters[k].joint for k in params.joint_terms}
    assert on and not on & {"wbar_b1", "wbar_b2", "wbar_b3"}  # the bars are left out
    # the struts left (the wrists' rods) deflect, measured in position only
    k = params.joint_terms
    rows = sample_actuators(mech, 3, np.random.default_rng(2))
    F0 = strut_loads(mech, rows, tuple(params.parameters[i].joint for i in k))[0]
    values = np.zeros(len(params))
    values[k] = -2e-4 / np.sqrt(np.mean(F0**2))  # [m/N]
    _check_exact_elongation(mech, params, values, rows)

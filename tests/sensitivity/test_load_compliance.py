"""Compliance under static load on closed loops (a Stewart platform's legs) and payloads."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from pincal.errors import ParameterError
from pincal.model import (
    Payload,
    joint_term_basis,
    load_mechanism,
    sample_actuators,
    with_joint_terms,
    with_payload,
)
from pincal.sensitivity import parameters

from .test_joint_terms import _fd_errors

MACHINES = Path(__file__).parents[1] / "model" / "machines"
SPINDLE = Payload(20.0, (0.05, -0.02, 0.10))  # [kg], [m] in the tool frame


@pytest.fixture(scope="module")
def loaded_stewart(stewart):
    return with_payload(stewart, SPINDLE)


def _potential_gradient(mech, row: np.ndarray, h: float = 1e-6) -> np.ndarray:
    """∂V/∂q_act along the closed configurations (virtual work: the held forces) [N]."""
    data = mech.model.createData()

    def V(r: np.ndarray) -> float:
        return pin.computePotentialEnergy(mech.model, data, mech.configurations(r[None])[0])

    eye = np.eye(len(row)) * h
    return np.array([(V(row + e) - V(row - e)) / (2 * h) for e in eye])


@pytest.mark.parametrize("loaded", [False, True])
def test_leg_forces_are_the_held_load(stewart, loaded_stewart, loaded):
    """The basis is the actuator force at equilibrium: the potential's gradient."""
    mech = loaded_stewart if loaded else stewart
    params = with_joint_terms(mech, parameters(mech, ["leg1_slide.offset"]), ["compliance"])
    rows = sample_actuators(mech, 3, np.random.default_rng(4))
    B = joint_term_basis(mech, params, rows)
    cols = [params.index(f"{a}.compliance") for a in mech.actuated]
    for row, b in zip(rows, B, strict=True):
        forces = b[np.arange(len(cols)), cols]
        assert forces == pytest.approx(_potential_gradient(mech, row), rel=1e-6, abs=1e-6)
    if loaded:  # 20 kg more on six legs
        unloaded = joint_term_basis(stewart, params, rows)
        extra = (B - unloaded)[:, np.arange(6), cols].sum(axis=1)
        assert np.all(extra > 0.8 * 20 * 9.81) and np.all(extra < 1.2 * 20 * 9.81)


def test_payload_is_a_point_mass_on_the_tool(stewart, loaded_stewart):
    """The payload adds m·g·z of its centre of mass (tool frame → world) to the potential."""
    q = loaded_stewart.configurations(sample_actuators(stewart, 1, np.random.default_rng(5)))[0]
    T = stewart.frame_placement(q)
    z = (T.act(np.array(SPINDLE.com)))[2]
    V = [
        pin.computePotentialEnergy(m.model, m.model.createData(), q)
        for m in (stewart, loaded_stewart)
    ]
    assert V[1] - V[0] == pytest.approx(SPINDLE.mass * 9.81 * z, rel=1e-9)
    assert np.allclose(loaded_stewart.frame_placement(q).homogeneous, T.homogeneous)


def test_jacobian_matches_finite_differences_stewart(loaded_stewart):
    params = with_joint_terms(
        loaded_stewart, parameters(loaded_stewart, "stewart42"), ["compliance"]
    )
    assert params.units[params.index("leg3_slide.compliance")] == "m/N"
    err = _fd_errors(loaded_stewart, params, 6, seed=2)
    assert err.max() < 1e-5, params.names[int(np.argmax(err))]


def test_other_machines_with_a_payload():
    """A 3-PRS without link masses takes a compliance once it carries a payload."""
    prs3 = load_mechanism(MACHINES / "prs3")
    with pytest.raises(ParameterError, match="no link masses"):
        with_joint_terms(prs3, parameters(prs3, "full"), ["compliance"])  # any set: no masses
    loaded = with_payload(prs3, Payload(2.0, (0.01, 0.0, 0.0)))
    params = with_joint_terms(loaded, parameters(loaded, "base"), ["compliance"])
    assert params.joint_terms.size == len(loaded.actuated)
    rows = sample_actuators(loaded, 4, np.random.default_rng(6))
    held = joint_term_basis(loaded, params, rows)[:, :, params.joint_terms]
    for row, b in zip(rows, held, strict=True):  # the sliders hold the 2 kg between them
        assert np.diag(b) == pytest.approx(_potential_gradient(loaded, row), rel=1e-6, abs=1e-6)
    err = _fd_errors(loaded, params, 6, seed=1)
    assert err.max() < 1e-5, params.names[int(np.argmax(err))]


def test_bad_payloads_are_specific(stewart, loaded_stewart):
    with pytest.raises(ParameterError, match="MASS,X,Y,Z"):
        Payload.parse("5,0,0")
    with pytest.raises(ParameterError, match="≥ 0"):
        Payload.parse("-1")
    assert Payload.parse("5,0,0,0.08") == Payload(5.0, (0.0, 0.0, 0.08))
    with pytest.raises(ParameterError, match="already has a link"):
        with_payload(loaded_stewart, SPINDLE)


@pytest.mark.parametrize("name", ["hexaslide_6pus", "wedge3"])
def test_held_forces_on_other_parallel_machines(name):
    """PUS sliders and the wedge's actuators: the basis is the potential's gradient too."""
    mech = load_mechanism(Path(__file__).parents[2] / "models" / name)
    params = parameters(mech, [f"{a}.compliance" for a in mech.actuated])
    rows = sample_actuators(mech, 2, np.random.default_rng(7))
    B = joint_term_basis(mech, params, rows)
    assert {params.units[k] for k in params.joint_terms} <= {"m/N", "rad/(N·m)"}
    for row, b in zip(rows, B, strict=True):
        grad = _potential_gradient(mech, row)
        assert np.max(np.abs(grad)) > 0.1  # [N]: a real load
        assert np.diag(b) == pytest.approx(grad, rel=1e-6, abs=1e-6)

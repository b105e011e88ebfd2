"""A new artefact kind is one class plus one registry line (issue 24).

The toy "nest" below (a ball on the flange seated in fixed nests whose centres are
known, e.g. measured by a CMM: three residuals per pose, the ball centre an unknown of
each file, optionally a height offset shared by every file of one fixture) lives only
in this file. Registered with the same ``add_instrument_kind`` as the scalar kinds,
it is fitted jointly by ``InstrumentProblem`` / ``identify_instruments`` with no change
to pincal's code: exact Jacobian, shared unknowns merged by name, simulated recovery.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest

from pincal.errors import MeasurementError
from pincal.identification import InstrumentProblem, identify_instruments
from pincal.measure import (
    Artefact,
    NoiseModel,
    SocketPlate,
    add_instrument_kind,
    artefact_class,
    artefact_kinds,
    instrument_kinds,
    simulate_measurements,
    simulate_sockets,
)
from pincal.model import load_mechanism, parameters, sample_actuators

STD = 5e-6  # seating 1σ per axis [m]
A = np.array([0.45, 0.10, 0.05])
NESTS = {"0": A, "1": A + np.array([0.1, 0.0, 0.0]), "2": A + np.array([0.0, -0.2, 0.05])}
HELD_OUT = {"0": A + np.array([0.05, 0.15, 0.0]), "1": A + np.array([-0.1, 0.0, 0.1])}
Z = np.array([0.0, 0.0, 1.0])


def _skew(t: np.ndarray) -> np.ndarray:
    return np.array([[0, -t[2], t[1]], [t[2], 0, -t[0]], [-t[1], t[0], 0]])


@dataclass(frozen=True, eq=False)
class Nest(Artefact):
    """Poses of a ball (centre t in the flange frame, unknown) seated in known nests.

    ``r = c_j + h·z − (p + R t)``; ``h`` the height offset of ``fixture`` when named (a
    shared unknown of every file of the fixture), else 0.
    """

    kind: ClassVar[str] = "nest"
    description: ClassVar[str] = "a ball seated in nests of known centre"
    dim: ClassVar[int] = 3
    q_act: np.ndarray
    nest: np.ndarray  # (m,) nest index per pose
    centres: np.ndarray  # (n_nests, 3) known centres [m]
    actuated: tuple[str, ...]
    frame: str
    std: float = STD
    fixture: str | None = None

    def __len__(self) -> int:
        return len(self.nest)

    @property
    def sigma(self):
        return np.full((len(self), 3), self.std)

    @property
    def parameter_names(self):
        return ("ball_x", "ball_y", "ball_z")

    @property
    def shared_names(self):
        return () if self.fixture is None else (f"{self.fixture}.dz",)

    def start(self, P, Rs):  # R_i t = c_j − p_i in the least-squares sense
        b = self.centres[self.nest] - P
        return np.linalg.lstsq(np.vstack(Rs), b.reshape(-1), rcond=None)[0]

    def residuals(self, P, Rs, theta, phi):
        m, R = len(self), np.asarray(Rs)
        h = phi[0] if self.fixture is not None else 0.0
        r = self.centres[self.nest] + h * Z - P - np.einsum("mij,j->mi", R, theta)
        dw = np.array([R[i] @ _skew(theta) for i in range(m)])
        dphi = np.tile(Z[:, None], (m, 1, len(phi)))
        return r, np.tile(-np.eye(3), (m, 1, 1)), dw, -R, dphi


@pytest.fixture(scope="module")
def nest_kind():
    return add_instrument_kind(Nest)  # the one registry line


@pytest.fixture(scope="module")
def ur5():
    mech = load_mechanism("ur5")
    params = parameters(mech, "full")
    bound = np.array([1e-3 if u == "m" else 1e-2 for u in params.units])
    values = np.random.default_rng(2).uniform(-bound, bound)
    return mech, params, params.apply(mech, values)


def _nests(actual, n, rng, ball, fixture=None, nests=NESTS, noise=True) -> Nest:
    """Poses of ``actual`` seating the ball in each nest (the sockets' simulation)."""
    seated = simulate_sockets(actual, SocketPlate("n", STD), nests, n, rng, ball=ball,
                              noise=noise)  # fmt: skip
    ids = np.array([int(s) for s in seated.socket])
    centres = np.array([nests[k] for k in sorted(nests, key=int)])
    return Nest(seated.q_act, ids, centres, seated.actuated, seated.frame, fixture=fixture)


def _fd(f, x, h=1e-7):
    cols = []
    for i in range(x.size):
        e = np.zeros_like(x)
        e[i] = h
        cols.append((f(x + e) - f(x - e)) / (2 * h))
    return np.stack(cols, axis=-1)


def test_the_kind_is_registered_beside_the_scalar_kinds(nest_kind):
    assert artefact_class("nest") is Nest
    assert artefact_kinds()[:3] == ("socket", "flush", "nest")  # built-in kinds first
    assert "nest" not in instrument_kinds() and "socket" not in instrument_kinds()
    with pytest.raises(MeasurementError, match="already Nest"):
        add_instrument_kind(type("Other", (Nest,), {}))


def test_nest_derivatives_are_exact(nest_kind):
    rng = np.random.default_rng(0)
    m = 4
    P = rng.normal(size=(m, 3))
    Rs = np.array([np.linalg.qr(rng.normal(size=(3, 3)))[0] for _ in range(m)])
    Rs *= np.sign(np.linalg.det(Rs))[:, None, None]
    theta, phi = rng.normal(size=3), np.array([0.01])
    d = Nest(np.zeros((m, 1)), np.arange(m) % 2, rng.normal(size=(2, 3)), ("j",), "f",
             fixture="fx")  # fmt: skip
    _, dp, dw, dth, dphi = d.residuals(P, Rs, theta, phi)
    for i in range(m):
        num_p = _fd(lambda p, i=i: d.residuals(np.r_[P[:i], p[None], P[i + 1 :]], Rs, theta,
                                               phi)[0][i], P[i])  # fmt: skip

        def rot(w, i=i):
            R = Rs.copy()
            R[i] = Rs[i] @ _exp(w)
            return d.residuals(P, R, theta, phi)[0][i]

        np.testing.assert_allclose(dp[i], num_p, atol=1e-7)
        np.testing.assert_allclose(dw[i], _fd(rot, np.zeros(3)), atol=1e-7)
    np.testing.assert_allclose(dth, _fd(lambda t: d.residuals(P, Rs, t, phi)[0], theta),
                               atol=1e-7)  # fmt: skip
    np.testing.assert_allclose(dphi, _fd(lambda f: d.residuals(P, Rs, theta, f)[0], phi),
                               atol=1e-7)  # fmt: skip


def _exp(w: np.ndarray) -> np.ndarray:
    """Rotation matrix of the rotation vector w (Rodrigues)."""
    a = float(np.linalg.norm(w))
    K = _skew(w / a) if a > 0 else np.zeros((3, 3))
    return np.eye(3) + np.sin(a) * K + (1 - np.cos(a)) * K @ K


def test_joint_jacobian_and_shared_unknowns(nest_kind, ur5):
    mech, params, actual = ur5
    rng = np.random.default_rng(4)
    ball = np.array([0.01, -0.02, 0.03])
    files = [_nests(actual, 2, rng, ball, fixture="table") for _ in range(2)]
    prob = InstrumentProblem(mech, params, files)
    n = len(params)
    # each file its own ball, one height offset for the fixture named by both
    assert prob.names[n:] == ("nest0.ball_x", "nest0.ball_y", "nest0.ball_z", "nest1.ball_x",
                              "nest1.ball_y", "nest1.ball_z", "table.dz")  # fmt: skip
    T = [mech.frame_placement(q) for q in mech.configurations(files[1].q_act)]
    t0 = files[1].start(np.array([f.translation for f in T]), np.array([f.rotation for f in T]))
    np.testing.assert_allclose(prob.x0[n + 3 : n + 6], t0, atol=1e-12)  # at nominal poses
    assert prob.x0[-1] == 0.0  # the default start of a shared unknown
    x = prob.x0 + np.random.default_rng(5).normal(0, 1e-3, prob.x0.size)
    r, J, _ = prob.evaluate(x)
    assert r.size == 3 * len(files[0]) + 3 * len(files[1])
    Jfd = _fd(lambda y: prob.evaluate(y, False)[0], x)
    assert np.abs(J - Jfd).max() < 1e-5 * np.abs(Jfd).max()
    assert prob.fixes_scale and prob.socket_centres(x) == {}


def test_simulated_recovery_through_the_joint_fit(nest_kind, ur5):
    mech, params, actual = ur5
    rng = np.random.default_rng(1)
    ball = np.array([0.0, 0.01, 0.04])
    data = _nests(actual, 25, rng, ball)
    out = identify_instruments(mech, params, [data], labels=["tool"])
    assert out.result.success and out.warnings == ()
    assert 0.5 < out.result.reduced_chi2 < 2.0
    assert out.result.after.rms_position < 2 * STD * np.sqrt(3) < out.result.before.rms_position
    # held out: ball centres at poses in other nests, as the calibrated model predicts
    # them (its ball, its flange) against the truth: known nests fix the absolute frame
    held = _nests(actual, 5, np.random.default_rng(7), ball, nests=HELD_OUT, noise=False)
    t = np.array([out.instrument_values()[f"tool.ball_{a}"] for a in "xyz"])

    def error(m, t):
        T = [m.frame_placement(q) for q in m.configurations(held.q_act)]
        B = np.array([f.translation + f.rotation @ t for f in T])
        return float(np.abs(B - held.centres[held.nest]).max())

    before = error(mech, np.zeros(3))
    after = error(out.result.calibrated_mechanism, t)
    assert after < 50e-6 < 1e-3 < before


def test_a_nest_file_beside_pose_measurements(nest_kind, ur5):
    mech, params, actual = ur5
    rng = np.random.default_rng(3)
    nests = _nests(actual, 3, rng, np.array([0.0, 0.0, 0.03]))
    rows = sample_actuators(mech, 5, rng)
    poses = simulate_measurements(actual, rows, NoiseModel(1e-5, 2e-5), rng)
    prob = InstrumentProblem(mech, params, [nests, poses])
    with pytest.raises(MeasurementError, match="declares no noise"):  # it would weigh nothing
        InstrumentProblem(mech, params, [nests, simulate_measurements(actual, rows)])
    assert prob.labels == ["nest0", "pose1"] and len(prob.blocks[0].sigma) == len(nests)


def test_an_unregistered_artefact_is_refused(nest_kind, ur5):
    mech, params, actual = ur5

    @dataclass(frozen=True, eq=False)
    class Loose(Nest):
        kind: ClassVar[str] = "loose"

    d = _nests(actual, 1, np.random.default_rng(2), None)
    loose = Loose(d.q_act, d.nest, d.centres, d.actuated, d.frame)
    with pytest.raises(MeasurementError, match="unknown artefact kind 'loose'"):
        InstrumentProblem(mech, params, [loose])

    @dataclass(frozen=True, eq=False)
    class Copy(Nest):  # the kind name of Nest, not its class
        pass

    copy = Copy(d.q_act, d.nest, d.centres, d.actuated, d.frame)
    with pytest.raises(MeasurementError, match="has the kind name 'nest' of Nest"):
        InstrumentProblem(mech, params, [copy])


def test_residuals_of_the_wrong_shape_are_refused(nest_kind, ur5):
    mech, params, actual = ur5

    @dataclass(frozen=True, eq=False)
    class Flat(Nest):
        kind: ClassVar[str] = "flat_nest"

        def residuals(self, P, Rs, theta, phi):
            r, dp, dw, dth, dphi = super().residuals(P, Rs, theta, phi)
            return r.reshape(-1), dp, dw, dth, dphi  # (3m,), not (m, 3)

    add_instrument_kind(Flat)
    d = _nests(actual, 1, np.random.default_rng(2), None)
    flat = Flat(d.q_act, d.nest, d.centres, d.actuated, d.frame)
    with pytest.raises(MeasurementError, match=r"'flat_nest': residuals\(\) returned r of shape"):
        InstrumentProblem(mech, params, [flat]).evaluate(np.zeros(len(params) + 3))

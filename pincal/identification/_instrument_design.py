"""What a scalar instrument can identify, in words, and where to measure with it.

:func:`instrument_identifiability` analyses the joint machine + instrument Jacobian
over random poses (:func:`pincal.sensitivity.analyse_jacobian`: rank, base set,
absorbed combinations) and describes its null directions physically: each null
direction moves the tool points by a field ``δp_i = J_p,i δx``; fields that are
rigid motions ``v + ω × p_i`` are named (translations along directions, rotations
about axes through a point), split into motions the instrument cannot see at all and
motions its own parameters absorb (e.g. a ballbar cannot see a rotation of the whole
machine about its pivot, and its pivot absorbs a translation).

:func:`instrument_candidates` gives candidate poses for an instrument (ballbar on a
sphere of bar length around the pivot, a probe grid on a reference sphere) as a
:class:`pincal.design.CandidateSet` whose Jacobian blocks are the joint scalar rows,
so :func:`pincal.design.select_poses` works unchanged;
:func:`instrument_cramer_rao` gives the Cramér–Rao covariance of the base set.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pincal.design import CandidateSet, crb_covariance
from pincal.errors import ConvergenceError, MeasurementError
from pincal.identification.problem import null_motions
from pincal.measure import Instrument, instrument_class
from pincal.model import Mechanism, ParameterSet, sample_actuators
from pincal.sensitivity import Identifiability, analyse_jacobian, pose_sensitivity
from pincal.sensitivity.kernels import jacobian_plan

__all__ = [
    "InstrumentIdentifiability",
    "default_instrument",
    "instrument_blocks",
    "instrument_candidates",
    "instrument_cramer_rao",
    "instrument_identifiability",
]


def instrument_blocks(
    mech: Mechanism,
    params: ParameterSet,
    instrument: Instrument,
    theta: np.ndarray,
    q_act_rows: np.ndarray,
    ids: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Joint Jacobian blocks of the readings at the nominal machine.

    Args:
        mech: nominal mechanism.
        params: its n parameters.
        instrument: the instrument whose readings are modelled.
        theta: (k,) instrument parameter values [m, rad] (see
            :attr:`Instrument.parameter_names`).
        q_act_rows: (m, n_act) actuator rows [m, rad].
        ids: (m,) ids of the kind's id column (e.g. plane ids; None for other kinds).

    Returns:
        J (m, 1, n + k) of dv/d[x; θ], tool positions P (m, 3) [m], position
        sensitivities Jp (m, 3, n).
    """
    rows = np.atleast_2d(np.asarray(q_act_rows, dtype=float))
    plan = jacobian_plan(mech, params)
    lin = params.linearise(None)
    sens = [pose_sensitivity(mech, params, q, lin, plan) for q in mech.configurations(rows)]
    P = np.array([s.position for s in sens])
    Jp = np.array([s.jacobian[:3] for s in sens])
    _, dv_dp, dv_dth = instrument.predict(P, theta, ids)
    J = np.concatenate([np.einsum("mi,min->mn", dv_dp, Jp), dv_dth], axis=1)[:, None, :]
    return J, P, Jp


def default_instrument(
    mech: Mechanism, kind: str, q_act_rows: np.ndarray, std: float = 1e-6
) -> tuple[Instrument, np.ndarray, np.ndarray | None]:
    """A typical set-up of ``kind`` beside the workspace of ``q_act_rows``.

    The kind's :meth:`pincal.measure.Instrument.typical` set-up at the nominal tool
    points (built-in kinds: ballbar pivot and probe sphere 0.1 m below the centre of
    the tool positions, sphere radius 0.02 m, one horizontal plane and a vertical one,
    a vertical gauge).

    Returns:
        (instrument, θ (k,), ids (m,) or None).

    Raises:
        MeasurementError: an unregistered kind.
    """
    cls = instrument_class(kind)
    rows = np.atleast_2d(np.asarray(q_act_rows, dtype=float))
    P = np.array([mech.frame_placement(q).translation for q in mech.configurations(rows)])
    return cls.typical(P, std)


@dataclass(frozen=True)
class InstrumentIdentifiability:
    """What one instrument identifies of a machine.

    Attributes:
        kind: instrument kind; names: machine then instrument parameter names.
        n_machine: number of machine parameters.
        identifiability: joint analysis (instrument parameters listed first).
        invisible: words for the null directions the instrument does not see at all.
        absorbed: words for the null directions its own parameters absorb.
        n_still: null directions that do not move the tool point at all.
    """

    kind: str
    names: tuple[str, ...]
    n_machine: int
    identifiability: Identifiability
    invisible: tuple[str, ...]
    absorbed: tuple[str, ...]
    n_still: int

    @property
    def rank(self) -> int:
        """Rank of the joint Jacobian (machine and instrument unknowns together)."""
        return self.identifiability.rank

    def lines(self) -> list[str]:
        """The statement in words."""
        ident, n = self.identifiability, len(self.names)
        k = n - self.n_machine
        out = [
            f"instrument {self.kind!r}: {self.n_machine} machine + {k} instrument parameters, "
            f"rank {ident.rank} ({n - ident.rank} not identifiable)",
        ]
        for w in self.invisible:
            out.append(f"  cannot see: {w}")
        for w in self.absorbed:
            out.append(f"  absorbed by the instrument parameters: {w}")
        if self.n_still:
            out.append(
                f"  cannot see: {self.n_still} direction(s) that do not move the tool point "
                "(tool orientation about the tool point)"
            )
        out.append("  base set and absorbed combinations:")
        out += [f"    {line}" for line in ident.describe()]
        return out


def instrument_identifiability(
    mech: Mechanism,
    params: ParameterSet,
    kind: str | Instrument,
    n_poses: int = 60,
    rng: np.random.Generator | int = 0,
    theta: np.ndarray | None = None,
) -> InstrumentIdentifiability:
    """Identifiability of ``params`` by one instrument over random poses, in words.

    Args:
        mech: nominal mechanism.
        params: its n parameters.
        kind: an instrument kind (a typical set-up, :func:`default_instrument`) or an
            :class:`Instrument` with ``theta``.
        n_poses: number of random workspace poses.
        rng: random generator or seed for the poses.
        theta: the instrument's parameter values (with an Instrument).

    Raises:
        MeasurementError: unknown kind, or an Instrument without theta.
    """
    gen = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    q = sample_actuators(mech, n_poses, gen)
    if isinstance(kind, Instrument):
        if theta is None:
            raise MeasurementError("give theta with an Instrument")
        inst, th = kind, np.asarray(theta, dtype=float)
        ids = np.arange(n_poses) % max(inst.n_ids, 1) if inst.id_column is not None else None
    else:
        inst, th, ids = default_instrument(mech, kind, q)
    J, P, Jp = instrument_blocks(mech, params, inst, th, q, ids)
    J = J[:, 0, :]
    n = len(params)
    names = (*params.names, *inst.parameter_names)
    order = np.r_[np.arange(n, len(names)), np.arange(n)]
    ident = analyse_jacobian(J[:, order], tuple(names[i] for i in order))
    motions = null_motions(J, Jp, P, n, ident, order, inst.parameter_names)
    return InstrumentIdentifiability(
        inst.kind, names, n, ident, motions.invisible, motions.absorbed, motions.n_still
    )


def instrument_candidates(
    mech: Mechanism,
    params: ParameterSet,
    instrument: Instrument,
    theta: np.ndarray,
    count: int = 200,
    rng: np.random.Generator | int = 0,
    max_tilt: float = 0.0,
) -> CandidateSet:
    """Candidate poses on the instrument's sphere (ballbar, probe on a sphere, …).

    Tool points on :meth:`pincal.measure.Instrument.candidate_sphere` (the ballbar: bar
    length ``|θ_c − home|`` around the pivot; the probe: the sphere's radius around its
    centre) in directions drawn uniformly, at the home
    orientation tilted by up to ``max_tilt`` [rad]; unreachable ones and those outside
    the sidecar's workspace joint ranges are dropped.

    Returns:
        CandidateSet with joint Jacobian blocks (N, 1, n + k), component ``"v"``.

    Raises:
        MeasurementError: a kind without a candidate sphere, or no reachable candidate.
    """
    home = mech.frame_placement(mech.q_home)
    sphere = instrument.candidate_sphere(np.asarray(theta, dtype=float), home.translation)
    if sphere is None:
        raise MeasurementError(
            f"instrument_candidates makes candidates on an instrument's sphere (ballbar, "
            f"sphere probe); the {instrument.kind!r} kind has none: use random workspace "
            "poses (pincal.model.sample_actuators)"
        )
    gen = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    c, radius = sphere
    # the sidecar's workspace joint ranges, where given, bound the candidates too
    limits = [
        (k, mech.workspace.joints[a])
        for k, a in enumerate(mech.actuated)
        if a in mech.workspace.joints
    ]
    rows: list[np.ndarray] = []
    tried = 0
    while len(rows) < count and tried < 20 * count:
        tried += 1
        u = gen.normal(size=3)
        u /= np.linalg.norm(u)
        R = home.rotation @ pin.exp3(gen.uniform(-max_tilt, max_tilt, 3))
        try:
            q = mech.inverse(pin.SE3(R, c + radius * u))
        except ConvergenceError:
            continue
        if all(lo <= q[k] <= hi for k, (lo, hi) in limits):
            rows.append(q)
    if not rows:
        raise MeasurementError("no candidate pose is reachable; move the pivot / sphere")
    q = np.array(rows)
    J, P, _ = instrument_blocks(mech, params, instrument, theta, q)
    Rs = np.array([mech.frame_placement(x).rotation for x in mech.configurations(q)])
    names = (*params.names, *instrument.parameter_names)
    return CandidateSet(
        q, P, Rs, J, ("v",), mech.actuated, names, f"{instrument.kind}:{count}", tried,
        {"unreachable": tried - len(rows)},
    )  # fmt: skip


def instrument_cramer_rao(J_blocks: np.ndarray, std: float, base: np.ndarray) -> np.ndarray:
    """Cramér–Rao covariance (b, b) of the base parameters ``base``.

    ``base`` indexes the n + k columns of the joint reading blocks (m, 1, n + k);
    ``std`` is the reading noise [m].
    """
    J = np.asarray(J_blocks, dtype=float).reshape(len(J_blocks), -1)[:, base] / std
    return crb_covariance(J)

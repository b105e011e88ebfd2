"""Seed-001 study: the 6-PUS simulation check and the laser-tracker experiment replica.

Part 1 (:func:`simulation_check`): the paper's assumed errors (1 mm on every
coordinate, 1 mm on L, 0.01 rad on θ and ψ) define the actual machine; it is
measured noise-free at the paper's 5 simulation poses plus the extra poses full
identifiability needs, and identification must recover the errors.

Part 2 (:func:`experiment_replica`): the paper's *identified* table is the actual
machine; a simulated laser tracker (AT960 noise, base registration, SMR targets on
the platform, per-pose fit covariance as weights) measures the paper's 8
experiment poses plus D-optimal extra poses; identification starts from the
nominal table; compensation (calibrated IK) is evaluated on validation poses.
"One direction" is the largest single-axis error (|Δx|, |Δy|, |Δz| or |Δα|, …),
"three directions" the largest error norm — the reading that reproduces the
paper's numbers from its Table 6 (max |Δy| = 0.0301 mm; ‖Δp‖ = 0.046 mm at pose 5).

The Cramér–Rao prediction of the validation error is
``sqrt(tr(J_val Cov J_valᵀ) / rows)`` with ``Cov = (Jᵀ W J)⁻¹`` the identified
parameters' covariance and ``J_val`` the pose sensitivity at the compensated
commands, separately for position rows [m] and rotation rows [rad].

Errors are evaluated in the *registered* base frame (the frame the tracker's
base registration defines and in which every measurement, including the paper's
validation, is expressed). The registration's own error is a rigid transform of
the base that the pus54 parameters absorb exactly (b_i, θ_i, ψ_i), so it does not
limit compensation in that frame; its size is reported separately.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pincal.compensation import compensate
from pincal.errors import ConvergenceError
from pincal.identification import (
    GaussNewtonOptions,
    IdentificationResult,
    identify,
)
from pincal.machines import (
    LegGeometry,
    leg_geometry,
    legs_from_table,
    pus54_values,
)
from pincal.measure import (
    LaserTracker,
    Measurements,
    TrackerNoise,
    simulate_measurements,
)
from pincal.model import Mechanism, ParameterSet, sample_pose
from pincal.sensitivity import identification_jacobian

__all__ = [
    "ReplicaResult",
    "SimulationCheck",
    "TrialResult",
    "ValidationErrors",
    "d_optimal_extra",
    "experiment_replica",
    "paper_pose",
    "simulation_check",
]

#: Paper Table 3 rows in our order (field of LegGeometry, component, assumed delta, SI).
ASSUMED_ERRORS: tuple[tuple[str, str, int | None, float], ...] = (
    ("delta_a_x", "a", 0, 1e-3),
    ("delta_a_y", "a", 1, -1e-3),
    ("delta_a_z", "a", 2, 1e-3),
    ("delta_b_x", "b", 0, 1e-3),
    ("delta_b_y", "b", 1, -1e-3),
    ("delta_b_z", "b", 2, 1e-3),
    ("delta_theta", "theta", None, 0.01),
    ("delta_psi", "psi", None, 0.01),
    ("delta_L", "L", None, 1e-3),
)


def paper_pose(pose: Sequence[float]) -> pin.SE3:
    """Paper pose (x, y, z [mm], α, β, γ [rad]) with R = Rz(γ)·Ry(β)·Rx(α)."""
    x, y, z, al, be, ga = (float(v) for v in pose)
    return pin.SE3(pin.rpy.rpyToMatrix(al, be, ga), np.array([x, y, z]) * 1e-3)


def _field(leg: LegGeometry, name: str, k: int | None) -> float:
    v = getattr(leg, name)
    return float(v[k]) if k is not None else float(v)


def _perturbed_legs(legs: Sequence[LegGeometry]) -> list[LegGeometry]:
    out = []
    for leg in legs:
        da = np.array([ASSUMED_ERRORS[i][3] for i in range(3)])
        db = np.array([ASSUMED_ERRORS[i][3] for i in range(3, 6)])
        out.append(
            LegGeometry(
                a=leg.a + da,
                b=leg.b + db,
                theta=leg.theta + ASSUMED_ERRORS[6][3],
                psi=leg.psi + ASSUMED_ERRORS[7][3],
                L=leg.L + ASSUMED_ERRORS[8][3],
            )
        )
    return out


def _whitened_blocks(
    mech: Mechanism, params: ParameterSet, q_act_rows: np.ndarray, sigma: np.ndarray
) -> np.ndarray:
    """(m, 6, n) pose Jacobians divided by per-component σ (6,)."""
    J = identification_jacobian(mech, params, q_act_rows)
    return J.reshape(len(q_act_rows), 6, len(params)) / sigma[None, :, None]


def d_optimal_extra(
    mech: Mechanism,
    params: ParameterSet,
    fixed_rows: np.ndarray,
    candidates: np.ndarray,
    n_extra: int | None,
    sigma: np.ndarray,
) -> np.ndarray:
    """Greedy D-optimal choice of extra poses among candidate actuator rows.

    Args:
        fixed_rows: (m0, n_act) poses that are measured anyway.
        candidates: (c, n_act) candidate actuator rows.
        n_extra: number to add; None = add until the information matrix has full rank.
        sigma: (6,) per-component noise σ used to weight rows [m, rad].

    Returns:
        (n_extra, n_act) the chosen rows, in the order chosen.
    """
    n = len(params)
    Jc = _whitened_blocks(mech, params, candidates, sigma)
    info = np.zeros((n, n))
    if len(fixed_rows):
        Jf = _whitened_blocks(mech, params, fixed_rows, sigma).reshape(-1, n)
        info = Jf.T @ Jf
    scale = np.sqrt(np.maximum(np.einsum("ckn,ckn->n", Jc, Jc) / len(candidates), 1e-300))
    D = np.diag(1.0 / scale)
    eps = 1e-9
    chosen: list[int] = []
    while True:
        A = D @ info @ D
        s = np.linalg.svd(A, compute_uv=False)
        if n_extra is None and s[-1] > 1e-8 * s[0]:
            break
        if n_extra is not None and len(chosen) == n_extra:
            break
        if len(chosen) == len(candidates):
            break
        best, best_val = -1, -np.inf
        A_reg = A + eps * np.trace(A) / n * np.eye(n) + 1e-300 * np.eye(n)
        L = np.linalg.cholesky(A_reg)
        for c in range(len(candidates)):
            if c in chosen:
                continue
            B = Jc[c] @ D  # (6, n)
            # det(A + Bᵀ B) / det(A) = det(I + B A⁻¹ Bᵀ)  (matrix determinant lemma)
            X = np.linalg.solve(L, B.T)
            val = np.linalg.slogdet(np.eye(6) + X.T @ X)[1]
            if val > best_val:
                best, best_val = c, val
        chosen.append(best)
        info = info + Jc[best].T @ Jc[best]
    return candidates[chosen]


def _candidates(mech: Mechanism, n: int, rng: np.random.Generator) -> np.ndarray:
    rows = []
    while len(rows) < n:
        try:
            rows.append(mech.inverse(sample_pose(mech, rng)))
        except ConvergenceError:
            continue
    return np.array(rows)


# ----------------------------------------------------------------------------- part 1
@dataclass(frozen=True)
class SimulationCheck:
    """Outcome of the noise-free seed-001 simulation check.

    Attributes:
        n_paper_poses, n_extra_poses: poses used.
        rows: per Table-3 row: (name, assumed [mm|rad], paper identified, paper
            difference, our identified (mean over legs), our max |difference| over legs).
        max_value_error: max |identified − true| over the 54 pus54 values [m, rad].
        rank: identifiable parameters at the chosen poses.
        result: the identification result.
    """

    n_paper_poses: int
    n_extra_poses: int
    rows: tuple[tuple[str, float, float, float, float, float], ...]
    max_value_error: float
    rank: int
    result: IdentificationResult


def simulation_check(
    mech: Mechanism,
    params: ParameterSet,
    paper: Mapping,
    rng: np.random.Generator,
    n_candidates: int = 60,
) -> SimulationCheck:
    """Noise-free identification of the paper's assumed errors (part 1)."""
    nominal_legs = legs_from_table(paper["nominal"])
    true_legs = _perturbed_legs(nominal_legs)
    true_values = pus54_values(mech, params, true_legs)
    actual = params.apply(mech, true_values)
    paper_rows = np.array([mech.inverse(paper_pose(p)) for p in paper["simulation_poses"]])
    extra = d_optimal_extra(
        mech, params, paper_rows, _candidates(mech, n_candidates, rng), None, np.ones(6)
    )
    rows = np.vstack([paper_rows, extra])
    meas = simulate_measurements(actual, rows, None, rng)
    result = identify(mech, params, meas, options=GaussNewtonOptions(max_iterations=30, xtol=1e-14))
    ident_legs = leg_geometry(result.calibrated)
    table = []
    for name, fld, k, _ in ASSUMED_ERRORS:
        assumed, paper_ident, paper_diff = paper["simulation_errors"][name]
        unit = 1.0 if fld in ("theta", "psi") else 1e3
        ours = np.array(
            [
                _field(i, fld, k) - _field(n, fld, k)
                for i, n in zip(ident_legs, nominal_legs, strict=True)
            ]
        )
        truth = np.array(
            [
                _field(t, fld, k) - _field(n, fld, k)
                for t, n in zip(true_legs, nominal_legs, strict=True)
            ]
        )
        table.append(
            (
                name,
                float(assumed),
                float(paper_ident),
                float(paper_diff),
                float(np.mean(ours) * unit),
                float(np.abs(ours - truth).max() * unit),
            )
        )
    full = np.zeros(len(params))
    idx = [params.index(nm) for nm in result.params.names]
    full[idx] = result.values
    return SimulationCheck(
        n_paper_poses=len(paper_rows),
        n_extra_poses=len(extra),
        rows=tuple(table),
        max_value_error=float(np.abs(full - true_values).max()),
        rank=result.identifiability.rank,
        result=result,
    )


# ----------------------------------------------------------------------------- part 2
@dataclass(frozen=True)
class ValidationErrors:
    """Pose errors at validation targets, registered base frame.

    Attributes:
        position: (m, 3) reached − target [m].
        orientation: (m, 3) log3(R_targetᵀ R_reached) [rad].
    """

    position: np.ndarray
    orientation: np.ndarray

    def max_one_direction(self) -> tuple[float, float]:
        """(max single-axis position error [m], max single-axis angle error [rad])."""
        return float(np.abs(self.position).max()), float(np.abs(self.orientation).max())

    def max_three_directions(self) -> tuple[float, float]:
        """(max position error norm [m], max angle error norm [rad])."""
        return (
            float(np.linalg.norm(self.position, axis=1).max()),
            float(np.linalg.norm(self.orientation, axis=1).max()),
        )

    def rms(self) -> tuple[float, float]:
        """Per-component RMS (position [m], orientation [rad])."""
        return float(np.sqrt(np.mean(self.position**2))), float(
            np.sqrt(np.mean(self.orientation**2))
        )


@dataclass(frozen=True)
class TrialResult:
    """One replica run (one noise realisation).

    Attributes:
        result: identification result.
        before, after: validation errors with nominal and with compensated commands.
        predicted_rms: Cramér–Rao predicted per-component RMS (position [m], angle [rad]).
        registration_error: (translation [m], rotation [rad]) of the base registration.
    """

    result: IdentificationResult
    before: ValidationErrors
    after: ValidationErrors
    predicted_rms: tuple[float, float]
    registration_error: tuple[float, float]


@dataclass(frozen=True)
class ReplicaResult:
    """Outcome of :func:`experiment_replica` over several noise realisations.

    Attributes:
        trials: per-trial results.
        n_paper_poses, n_extra_poses, n_validation: pose counts.
        efficiency: (position, orientation) ratio of the measured validation RMS (pooled
            over trials) to the Cramér–Rao predicted RMS (pooled); 1 = efficient.
        unreachable: validation targets the calibrated model could not reach (indices).
    """

    trials: tuple[TrialResult, ...]
    n_paper_poses: int
    n_extra_poses: int
    n_validation: int
    efficiency: tuple[float, float]
    unreachable: tuple[int, ...]


def default_tracker(rng: np.random.Generator | None = None) -> LaserTracker:
    """A tracker 2.5 m from the base centre, 0.6 m up, looking at the machine."""
    yaw = 0.4
    R = pin.rpy.rpyToMatrix(0.0, 0.0, yaw)
    p_tracker_in_base = np.array([2.3, 0.9, 0.6])
    T_base_tracker = pin.SE3(R, p_tracker_in_base)
    return LaserTracker(T_base_tracker.inverse(), TrackerNoise())


#: SMR targets on the base (base frame) and on the platform (platform frame) [m].
BASE_TARGETS = np.array(
    [[0.45, 0.0, 0.0], [-0.3, 0.4, 0.0], [-0.3, -0.4, 0.0], [0.2, 0.3, 0.12], [0.2, -0.3, 0.12]]
)
PLATFORM_TARGETS = np.array(
    [
        [0.12, 0.0, 0.0],
        [-0.12, 0.0, 0.0],
        [0.0, 0.12, 0.0],
        [0.0, -0.12, 0.0],
        [0.0, 0.0, 0.06],
        [0.0, 0.0, -0.06],
    ]
)


def tracker_measurements(
    actual: Mechanism,
    q_act_rows: np.ndarray,
    tracker: LaserTracker,
    rng: np.random.Generator,
    targets_platform: np.ndarray = PLATFORM_TARGETS,
) -> Measurements:
    """Platform poses measured through targets, with per-pose std from the fit covariance.

    Position std is of the world-frame position (the identification's position rows),
    rotation std of the local rotation vector.
    """
    qs = actual.configurations(q_act_rows)
    m = len(q_act_rows)
    pos, rot, std = np.empty((m, 3)), np.empty((m, 3, 3)), np.empty((m, 6))
    for i, q in enumerate(qs):
        T_true = actual.frame_placement(q)
        pm = tracker.measure_pose(T_true, targets_platform, rng)
        T = pm.T_base_body
        pos[i], rot[i] = T.translation, T.rotation
        C = pm.covariance
        std[i, :3] = np.sqrt(np.diag(T.rotation @ C[:3, :3] @ T.rotation.T))
        std[i, 3:] = np.sqrt(np.diag(C[3:, 3:]))
    return Measurements(
        np.array(q_act_rows, dtype=float),
        pos,
        rot,
        ("x", "y", "z", "rx", "ry", "rz"),
        actual.measured_frame,
        actual.actuated,
        None,
        std,
    )


def _reached(actual: Mechanism, X: pin.SE3, q_rows: np.ndarray) -> list[pin.SE3]:
    qs = actual.configurations(q_rows)
    out = []
    for q in qs:
        out.append(X * actual.frame_placement(q))
    return out


def _errors(targets: Sequence[pin.SE3], reached: Sequence[pin.SE3]) -> ValidationErrors:
    pos = np.array([r.translation - t.translation for t, r in zip(targets, reached, strict=True)])
    ori = np.array(
        [pin.log3(t.rotation.T @ r.rotation) for t, r in zip(targets, reached, strict=True)]
    )
    return ValidationErrors(pos, ori)


def experiment_replica(
    mech: Mechanism,
    params: ParameterSet,
    paper: Mapping,
    rng: np.random.Generator,
    n_extra: int = 32,
    n_validation: int = 24,
    n_trials: int = 10,
    n_candidates: int = 200,
    progress: Callable[[str], None] | None = None,
) -> ReplicaResult:
    """The seed-001 experiment replica (part 2), repeated over ``n_trials`` noise draws.

    Pose design and validation targets are drawn once; each trial re-registers the
    tracker and re-measures with fresh noise.
    """
    say = progress or (lambda _msg: None)
    actual = params.apply(mech, pus54_values(mech, params, legs_from_table(paper["identified"])))
    paper_rows = np.array([mech.inverse(paper_pose(p)) for p in paper["experiment_poses"]])
    tracker = default_tracker()
    # typical per-pose σ at the machine centre, for the pose design
    tracker.register_base(BASE_TARGETS, np.random.default_rng(0))
    probe = tracker_measurements(mech, paper_rows[4:5], tracker, np.random.default_rng(0))
    sigma = probe.std[0]
    say(f"choosing {n_extra} D-optimal extra poses among {n_candidates} candidates")
    extra = d_optimal_extra(
        mech, params, paper_rows, _candidates(mech, n_candidates, rng), n_extra, sigma
    )
    rows = np.vstack([paper_rows, extra])
    targets = [sample_pose(mech, rng) for _ in range(n_validation)]
    trials = []
    unreachable: set[int] = set()
    ms_meas = np.zeros(2)
    ms_pred = np.zeros(2)
    for t in range(n_trials):
        say(f"trial {t + 1}/{n_trials}: register, measure {len(rows)} poses, identify")
        fit = tracker.register_base(BASE_TARGETS, rng)
        X = fit.T.inverse() * tracker.T_tracker_base  # true base in the registered frame
        reg_err = (
            float(np.linalg.norm(X.translation)),
            float(np.linalg.norm(pin.log3(X.rotation))),
        )
        meas = tracker_measurements(actual, rows, tracker, rng)
        result = identify(mech, params, meas)
        # before: the controller's nominal IK; after: compensated commands
        q_before = np.array([mech.inverse(T, check_limits=False) for T in targets])
        comp = compensate(result.calibrated, targets, check_limits=False)
        unreachable.update(comp.unreachable)
        ok = [i for i in range(n_validation) if comp.reachable[i]]
        before = _errors(targets, _reached(actual, X, q_before))
        after = _errors([targets[i] for i in ok], _reached(actual, X, comp.q_act[ok]))
        J = identification_jacobian(mech, result.params, comp.q_act[ok], values=result.values)
        J = J.reshape(len(ok), 6, -1)
        Jp, Jr = J[:, :3].reshape(-1, J.shape[2]), J[:, 3:].reshape(-1, J.shape[2])
        cov = result.covariance
        pred = np.array(
            [np.trace(Jp @ cov @ Jp.T) / Jp.shape[0], np.trace(Jr @ cov @ Jr.T) / Jr.shape[0]]
        )
        rms_after = np.array(after.rms())
        ms_meas += rms_after**2
        ms_pred += pred
        trials.append(
            TrialResult(result, before, after, tuple(np.sqrt(pred)), reg_err)  # type: ignore[arg-type]
        )
    eff = np.sqrt(ms_meas / ms_pred)
    return ReplicaResult(
        trials=tuple(trials),
        n_paper_poses=len(paper_rows),
        n_extra_poses=len(extra),
        n_validation=n_validation,
        efficiency=(float(eff[0]), float(eff[1])),
        unreachable=tuple(sorted(unreachable)),
    )

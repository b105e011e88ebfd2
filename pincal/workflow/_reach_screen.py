"""The reach screen of ``pincal poses``: a candidate must compensate on a displaced model.

The executable-pose screens are :func:`pincal.design.screen_candidates`; their
compensation test needs stage 6 (compensation) and so cannot live in the design stage.
:func:`compensation_test` compensates every surviving candidate's nominal pose on the
nominal model displaced by random errors of the preset's parameters (uniform within
the given mm / mrad bounds, as ``pincal simulate --error-size`` draws them, none a built
machine cannot have; :data:`DRAWS` draws seeded by the seed), from the candidate's own
command, limits checked, branch changes refused — what ``pincal compensate`` does with
a calibration of that size, imposing the components the machine controls
(:func:`controlled_components`). A few random draws seldom reach the errors that hurt a
pose most, and the designs that maximise observability favour poses at the edge of the
workspace and near singularities, where such errors make a pose unreachable or throw its
wrist onto another branch. So each candidate is also compensated, to first order, on
the two *critical* draws of its own (:func:`critical_shifts`): the pose change
δ = ±``CRITICAL_SIGMA`` · C u / √(uᵀCu) (that many σ of the change the errors cause
along u, σ_u = √(uᵀCu), with the most likely change elsewhere), u the direction the
actuators move the measured frame least (the last left singular vector of the scaled
actuator Jacobian, :func:`pincal.design.scaled_actuator_jacobians`), C = K Σ Kᵀ the
covariance of the pose change for the uniform errors (Σ = diag(bound²/3), K the
identification Jacobian; the displaced model reaching a target is the nominal reaching
it moved by −Kδp). A candidate is kept when it compensates on every draw — unless the
critical draws would leave candidates that cannot identify the parameters the random
draws' survivors can (a small machine under large error bounds: a finger linkage kept 47
of 265): then they are not applied, and a note says so.
When the measured components do not fix the commands (a two-motor neck measured by
one angle) no target fixes a command, the screen is off and :func:`unfixed_commands`
says which components to measure; a redundant arm measured in full pose is screened
(a Panda's designed poses failed 37 of 1 200 further compensations unscreened, 1
screened).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pinocchio as pin

from pincal.compensation import compensate
from pincal.design import CandidateSet, scaled_actuator_jacobians
from pincal.errors import PincalError
from pincal.model import (
    COMPONENTS,
    Mechanism,
    ParameterSet,
    actuator_jacobian,
    fixing_components,
    sample_actuators,
)
from pincal.sensitivity import identification_jacobian, jacobian_rank
from pincal.workflow._buildable import buildable_mask

__all__ = [
    "CRITICAL_SIGMA",
    "DRAWS",
    "compensation_test",
    "controlled_components",
    "critical_shifts",
    "unfixed_commands",
]

#: random error draws each candidate must compensate on
DRAWS = 3
#: size of a candidate's critical draws, in σ of the pose change along its critical direction
CRITICAL_SIGMA = 3.0


def compensation_test(
    mech: Mechanism,
    params: ParameterSet,
    errors: tuple[float, float],
    seed: int,
    say: Callable[[str], None] | None = None,
) -> Callable[[CandidateSet], np.ndarray] | None:
    """The ``compensable`` test of :func:`pincal.design.screen_candidates`.

    Args:
        mech: the nominal mechanism.
        params: the preset's parameter set (the errors are drawn on it, before any
            reduction to a base set, as ``pincal simulate`` draws them: none on
            parameters a built machine cannot have, :func:`buildable_mask`).
        errors: uniform error bounds (mm for lengths, mrad for angles).
        seed: random seed of the errors.
        say: given a note (one line) when some error draws do not assemble, or when
            the screen is off (:func:`unfixed_commands`).

    Returns:
        candidates (M) → (M,) bool, whether each compensates on every draw; None (no
        screen) when the measured components do not fix the commands.
    """
    unfixed = unfixed_commands(mech)
    if unfixed:
        if say is not None:
            say(f"  reach screen off: {unfixed}")
        return None
    rng = np.random.default_rng([seed, 37])
    bound = np.array([errors[0] * 1e-3 if u == "m" else errors[1] * 1e-3 for u in params.units])
    bound *= buildable_mask(mech, params, sample_actuators(mech, 10, np.random.default_rng(seed)))
    comps = controlled_components(mech)
    displaced, failed = [], []
    for _ in range(DRAWS):
        try:
            displaced.append(params.apply(mech, rng.uniform(-bound, bound)))
        except PincalError as exc:  # the displaced geometry does not assemble
            failed.append(str(exc).split(":")[0])
    if failed and say is not None:
        say(
            f"  reach screen: {len(failed)} of {DRAWS} error draws of ±{errors[0]:g} mm / "
            f"±{errors[1]:g} mrad do not assemble ({failed[0]}); "
            + ("screened on the others" if displaced else "not screened")
            + " (smaller --reach-errors, or none)"
        )

    def test(cands: CandidateSet) -> np.ndarray:
        ok = np.ones(len(cands), dtype=bool)
        targets = [pin.SE3(R, p) for R, p in zip(cands.rotations, cands.positions, strict=True)]

        def compensates(model: Mechanism, moved: list[pin.SE3]) -> None:
            idx = np.flatnonzero(ok)
            if idx.size:
                result = compensate(model, [moved[i] for i in idx], starts=cands.q_act[idx],
                                    components=comps)  # fmt: skip
                ok[idx] = np.asarray(result.reachable, dtype=bool)

        for model in displaced:
            compensates(model, targets)
        if not ok.any():
            return ok
        random_ok = ok.copy()
        shift = np.zeros((len(cands), 6))
        shift[ok] = critical_shifts(mech, params, cands.q_act[ok], bound / np.sqrt(3.0))
        for sign in (1.0, -1.0):
            compensates(mech, [_moved(T, sign * d) for T, d in zip(targets, shift, strict=True)])
        before, after = _rank(cands, random_ok), _rank(cands, ok)
        if after < before:  # the design would fail: the random draws' verdict stands
            if say is not None:
                say(
                    f"  reach screen: the critical draws would leave {ok.sum()} candidates "
                    f"of rank {after} < {before}: not applied; designed poses near the edge "
                    "of the reach may not compensate under errors of this size (smaller "
                    "--reach-errors if the calibration's will be smaller)"
                )
            return random_ok
        return ok

    return test


def critical_shifts(
    mech: Mechanism, params: ParameterSet, q_act: np.ndarray, std: np.ndarray
) -> np.ndarray:
    """Each row's critical pose change δ (N, 6) [m, rad] (module doc; zero where undefined).

    Args:
        mech: the nominal mechanism.
        params: the parameter set the errors are drawn on (n).
        q_act: (N, n_act) actuator rows [m, rad].
        std: (n,) the errors' σ [m, rad] (0: no error).

    Returns:
        δ in x y z [m, world axes] rx ry rz [rad, measured frame]; the components not
        measured, and rows whose kinematics fail, are zero.
    """
    G, scale, _ = scaled_actuator_jacobians(mech, q_act)
    comps = [COMPONENTS.index(c) for c in mech.measured_components]
    K = identification_jacobian(mech, params, q_act).reshape(len(q_act), len(comps), -1)
    out = np.zeros((len(q_act), 6))
    for i in range(len(q_act)):
        if not (np.all(np.isfinite(G[i])) and np.all(np.isfinite(K[i]))):
            continue
        u = np.linalg.svd(G[i], full_matrices=False)[0][:, -1]
        Ks = scale[:, None] * K[i] * std[None, :]  # scaled pose change per unit σ of each error
        C_u = Ks @ (Ks.T @ u)  # C u, C = Ks Ksᵀ
        var = float(u @ C_u)
        if var > 0.0:
            out[i, comps] = CRITICAL_SIGMA * C_u / np.sqrt(var) / scale
    return out


def _rank(cands: CandidateSet, keep: np.ndarray) -> int:
    """The identification rank of the candidates ``keep`` (the design's rank rule)."""
    J = cands.jacobians[keep]
    return jacobian_rank(J.reshape(-1, J.shape[-1])) if len(J) else 0


def _moved(T: pin.SE3, d: np.ndarray) -> pin.SE3:
    """``T`` moved by d (6,): position + d[:3] (world axes), rotation R·exp(d[3:])."""
    return pin.SE3(T.rotation @ pin.exp3(d[3:]), T.translation + d[:3])


def controlled_components(mech: Mechanism) -> tuple[str, ...]:
    """The measured components a target of the reach screen imposes.

    All of them when the machine moves as many; else, positions first, each component
    whose row of the actuator Jacobian at home [m or rad per m or rad] adds to the rank
    of those kept, up to the mobility (a planar five-bar measuring x y rz is screened on
    x y). Returns component names in x y z rx ry rz order.
    """
    comps = tuple(mech.measured_components)
    if len(comps) <= mech.mobility:
        return comps
    G = actuator_jacobian(mech, mech.q_home)  # (components, actuators)
    # rounding of the loop closure leaves ~1e-15 in a row the actuators do not move (a
    # planar machine's z); numpy's default tolerance (~1e-16 · σ_max) would count it
    tol = 1e-9 * float(np.abs(G).max())
    order = sorted(range(len(comps)), key=lambda k: comps[k].startswith("r"))
    keep: list[int] = []
    for k in order:
        if len(keep) < mech.mobility and np.linalg.matrix_rank(G[[*keep, k]], tol) > len(keep):
            keep.append(k)
    return tuple(comps[k] for k in sorted(keep))


def unfixed_commands(mech: Mechanism) -> str:
    """Why no target of the measured components fixes the commands ("" when they do).

    The measured components fix the n actuators when their actuator Jacobian at home
    (:func:`actuator_jacobian`) has rank n (the mobility, when the actuation is
    redundant), and as far as anything can when it has the rank of all six components'
    rows: a 7-joint arm measured in full pose (its self-motion no measurement fixes;
    compensation keeps it near the start, minimum-norm). Otherwise the note names
    components that, measured, would (:func:`fixing_components`).
    """
    n = mech.n_actuated
    comps = tuple(mech.measured_components)
    G = actuator_jacobian(mech, mech.q_home, components=COMPONENTS)  # (6, n)
    rank, measure = fixing_components(G, comps)
    if rank >= min(n, mech.mobility):  # redundant actuators: the mobility's rank fixes them
        return ""
    if rank >= np.linalg.matrix_rank(G, 1e-9 * max(float(np.abs(G).max()), 1e-300)):
        return ""  # every component the actuators move is measured: a redundant chain
    return (
        f"the measured components [{', '.join(comps)}] fix only {rank} of the {n} commands "
        f"{list(mech.actuated)} at home (no target fixes a command); measure "
        + (
            f"[{', '.join(measure)}] (sidecar 'measured') to screen reach"
            if measure
            else f"more of the pose (the actuators move fewer than {n} of its six "
            "components at home)"
        )
    )

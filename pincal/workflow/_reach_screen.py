"""The reach screen of ``pincal poses``: a candidate must compensate on a displaced model.

The executable-pose screens are :func:`pincal.design.screen_candidates`; their
compensation test needs stage 6 (compensation) and so cannot live in the design stage.
:func:`compensation_test` compensates every surviving candidate's nominal pose on the
nominal model displaced by random errors of the preset's parameters (uniform within
the given mm / mrad bounds, as ``pincal simulate --error-size`` draws them, none a built
machine cannot have; :data:`DRAWS` draws seeded by the seed), from the candidate's own
command, limits checked, branch changes refused — what ``pincal compensate`` does with
a calibration of that size, imposing the components the machine controls
(:func:`controlled_components`). A candidate is kept when it compensates on every draw.
When the measured components do not fix the commands (a two-motor neck measured by
one angle) no target fixes a command, the screen is off and :func:`unfixed_commands`
says which components to measure.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pinocchio as pin

from pincal.compensation import compensate
from pincal.design import CandidateSet
from pincal.errors import PincalError
from pincal.model import (
    COMPONENTS,
    Mechanism,
    ParameterSet,
    actuator_jacobian,
    fixing_components,
    sample_actuators,
)
from pincal.workflow._buildable import buildable_mask

__all__ = ["DRAWS", "compensation_test", "controlled_components", "unfixed_commands"]

#: error draws each candidate must compensate on
DRAWS = 3


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
        for model in displaced:
            if not ok.any():
                break
            idx = np.flatnonzero(ok)
            result = compensate(
                model, [targets[i] for i in idx], starts=cands.q_act[idx], components=comps
            )
            ok[idx] = np.asarray(result.reachable, dtype=bool)
        return ok

    return test


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
    redundant); otherwise the note names components that,
    measured, would (:func:`fixing_components`).
    """
    n = mech.n_actuated
    comps = tuple(mech.measured_components)
    G = actuator_jacobian(mech, mech.q_home, components=COMPONENTS)  # (6, n)
    rank, measure = fixing_components(G, comps)
    if rank >= min(n, mech.mobility):  # redundant actuators: the mobility's rank fixes them
        return ""
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

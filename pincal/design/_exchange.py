"""Measurement-pose design: orthogonal arrays and observability-maximising selection.

A candidate set is an array ``J_cand`` of shape (N, k, n): the scaled
identification-Jacobian block of each of N candidate poses (k measurement rows
per pose, n parameters). Selection returns the indices of m candidates whose
stacked Jacobian maximises one observability index (:mod:`pincal.design._indices`).

Algorithms:

- :func:`exchange` — add/remove exchange of seed 000 after Daney et al.: from m
  random poses, add the candidate that maximises the index, remove the pose whose
  removal costs least, stop when the added pose is the removed one; optional
  tabu list.
- :func:`detmax` — Mitchell's DETMAX: excursions that add and remove several
  poses at once, accepted only if the m-pose design improves.
- :func:`greedy` — sequential construction, one best pose at a time.

Speed. Every step scores all candidates with the D-criterion
log det(δI + JᵀJ) (O1 = det(JᵀJ)^(1/2L)/√m) using the matrix determinant lemma
det(A + UᵀU) = det(A)·det(I + U A⁻¹ Uᵀ) for each candidate block U (k, n): one
(N, k, k) batch per step, with A⁻¹ kept up to date by the Woodbury identity.
Other indices are evaluated exactly (batched SVD of [R; U] where R is the
triangular factor of the current design's Jacobian, which has the same
singular values as the stacked Jacobian) on the ``prune`` best candidates by the
D-criterion, or on all of them with ``prune=None``. ``fast=False`` recomputes the
exact index (SVD of the stacked Jacobian) of every candidate design from
scratch; it is the reference for tests and benchmarks.

The small ridge δ = ``ridge``·(mean diagonal of one candidate's JᵀJ) keeps A
invertible while a design is still rank-deficient (greedy start, DETMAX
excursions); there it acts as a tie-breaker, since every exact index is 0.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pincal.design._arrays import bose_array, map_to_ranges, orthogonal_array
from pincal.design._scoring import ScoringProblem, ScoringState
from pincal.errors import PincalError

__all__ = [
    "PoseSelection",
    "bose_array",
    "detmax",
    "exchange",
    "greedy",
    "map_to_ranges",
    "orthogonal_array",
]

_log = logging.getLogger(__name__)

_REL_TOL = 1e-12  # strict-improvement threshold (relative) for accepting a move


@dataclass(frozen=True, eq=False)
class PoseSelection:
    """Result of a pose selection.

    Attributes:
        indices: selected candidate indices, sorted, shape (m,).
        index_name: the maximised index ("O1".."O5", "A").
        value: exact index of the selected design (SVD of its stacked Jacobian).
        history: index value after each iteration (exchange: after each accepted
            exchange, starting with the initial design; DETMAX: after each excursion
            round; greedy: after each addition). Non-decreasing for exchange/DETMAX.
        iterations: add/remove rounds (exchange), excursion rounds (DETMAX) or
            additions (greedy) performed.
        method: "exchange", "detmax" or "greedy".
        converged: True if the method's own stopping rule ended it (not max_iter).
    """

    indices: NDArray[np.int_]
    index_name: str
    value: float
    history: tuple[float, ...]
    iterations: int
    method: str
    converged: bool = True


def _rng(rng: np.random.Generator | int | None) -> np.random.Generator:
    return rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)


def _result(
    problem: ScoringProblem, state: ScoringState, value: float, history: list[float],
    iterations: int, method: str, converged: bool,
) -> PoseSelection:  # fmt: skip
    return PoseSelection(
        indices=np.sort(np.asarray(state.members, dtype=int)),
        index_name=problem.index,
        value=float(value),
        history=tuple(float(h) for h in history),
        iterations=int(iterations),
        method=method,
        converged=converged,
    )


# ----------------------------------------------------------------------------- selection


def exchange(
    J_cand: ArrayLike,
    m: int,
    index: str = "O1",
    rng: np.random.Generator | int | None = None,
    start: ArrayLike | None = None,
    tabu: int = 0,
    *,
    max_iter: int = 1000,
    patience: int = 20,
    fast: bool = True,
    prune: int | None = 64,
    ridge: float = 1e-9,
) -> PoseSelection:
    r"""Add/remove exchange selection of m poses (seed 000, after Daney et al.).

    Seed 000 (its Fig. 4): (1) candidates Ω0; (2) m random poses of Ω0 form Ω1;
    (3) add the pose T+ of Ω0 \ Ω1 that maximises the index of Ω1 ∪ {T+};
    (4) remove the pose T− of Ω1 ∪ {T+} whose removal leaves the largest index;
    (5) repeat (3)–(4) until the added pose T+ is the removed pose T−. Here the
    loop also stops if an exchange does not strictly increase the exact index,
    so the history never decreases.

    With ``tabu > 0`` (tabu search, Daney et al.): a removed pose may not be
    added back for ``tabu`` iterations, and when T+ = T− the best other pose is
    removed anyway (a possibly worsening move). The best design seen is
    returned; the search stops after ``patience`` iterations without
    improvement. ``history`` then holds the best value per iteration.

    Args:
        J_cand: candidate Jacobian blocks (N, k, n), already scaled.
        m: number of poses to select, m·k ≥ n.
        index: criterion to maximise, one of "O1".."O5", "A".
        rng: generator or seed for the random start.
        start: initial design, m distinct candidate indices (default random).
        tabu: tabu tenure in iterations (0: plain exchange).
        max_iter: maximum number of add/remove rounds.
        patience: tabu search only: rounds without improvement before stopping.
        fast: rank-k updates (True) or exact recomputation of every candidate
            design from scratch (False, slow reference).
        prune: for indices other than O1, number of best candidates by the
            D-criterion evaluated exactly (None: all).
        ridge: relative ridge δ for the D-criterion (see module docstring).

    Returns:
        The selection; ``value`` is the exact index of the returned design.

    Raises:
        TooFewPosesError: m·k < n.
    """
    problem = ScoringProblem(J_cand, index, fast, prune, ridge)
    m = problem.check_m(m)
    if m >= problem.N:
        raise PincalError(f"exchange needs more candidates ({problem.N}) than poses ({m})")
    if start is None:
        members = [int(i) for i in _rng(rng).choice(problem.N, size=m, replace=False)]
    else:
        members = problem.check_start(start, m, exact_len=True)
    state = ScoringState(problem, members)
    value = problem.exact(state.members)
    history = [value]
    best_state, best_value = state.copy(), value
    tabu_until = np.zeros(problem.N, dtype=int)
    stall = 0
    converged = False
    it = 0
    for it in range(1, max_iter + 1):
        allowed = ~state.mask & (tabu_until < it)
        if not np.any(allowed):
            converged = True
            break
        c_plus = problem.best_add(state, allowed)
        state.add(c_plus)
        c_minus = problem.best_remove(state, state.members)
        if c_minus == c_plus:
            if tabu == 0:
                state.remove(c_plus)
                converged = True
                break
            c_minus = problem.best_remove(state, [c for c in state.members if c != c_plus])
        state.remove(c_minus)
        new_value = problem.exact(state.members)
        if tabu == 0:
            if not new_value > value + _REL_TOL * abs(value):
                state.add(c_minus)
                state.remove(c_plus)
                converged = True
                break
            value = new_value
            history.append(value)
            best_state, best_value = state, value
            continue
        tabu_until[c_minus] = it + tabu
        if new_value > best_value + _REL_TOL * abs(best_value):
            best_state, best_value, stall = state.copy(), new_value, 0
        else:
            stall += 1
        history.append(best_value)
        if stall >= patience:
            converged = True
            break
    _log.debug("exchange %s: %d iterations, value %.6g", index, it, best_value)
    return _result(problem, best_state, best_value, history, it, "exchange", converged)


def greedy(
    J_cand: ArrayLike,
    m: int,
    index: str = "O1",
    start: ArrayLike | None = None,
    *,
    fast: bool = True,
    prune: int | None = 64,
    ridge: float = 1e-9,
) -> PoseSelection:
    """Greedy sequential selection: add the best pose until m are selected.

    While the design is still rank-deficient every exact index is 0 and the
    ridge D-criterion log det(δI + JᵀJ) decides. ``history`` holds the exact
    index after each addition (it can decrease for O1, whose 1/√m factor grows).

    Args:
        J_cand: candidate Jacobian blocks (N, k, n).
        m: number of poses, m·k ≥ n.
        index: "O1".."O5" or "A".
        start: poses that are always included (at most m distinct indices).
        fast: rank-k updates (True) or exact recomputation of every candidate
            design from scratch (False, slow reference).
        prune: for indices other than O1, number of best candidates by the
            D-criterion evaluated exactly (None: all).
        ridge: relative ridge δ for the D-criterion (see module docstring).
    """
    problem = ScoringProblem(J_cand, index, fast, prune, ridge)
    m = problem.check_m(m)
    members = [] if start is None else problem.check_start(start, m, exact_len=False)
    state = ScoringState(problem, members)
    history: list[float] = []
    additions = 0
    while len(state.members) < m:
        state.add(problem.best_add(state, ~state.mask))
        additions += 1
        history.append(problem.exact(state.members))
    value = problem.exact(state.members)
    return _result(problem, state, value, history or [value], additions, "greedy", True)


def detmax(
    J_cand: ArrayLike,
    m: int,
    index: str = "O1",
    rng: np.random.Generator | int | None = None,
    start: ArrayLike | None = None,
    *,
    max_depth: int = 3,
    max_iter: int = 200,
    fast: bool = True,
    prune: int | None = 64,
    ridge: float = 1e-9,
) -> PoseSelection:
    """Mitchell's DETMAX: improve an m-pose design by excursions.

    An excursion of depth d leaves the best m-pose design and comes back to m
    poses: either "up" (add the d best poses one at a time, then remove the d
    least useful) or "down" (remove the d least useful, then add the d best
    among the others). The first excursion, by increasing depth 1..max_depth,
    that strictly increases the exact index is accepted and the depth resets
    to 1; the search ends when no excursion up to ``max_depth`` improves.
    (Mitchell's failure set, which steers repeated excursions, is replaced here
    by this systematic depth schedule.) Depth 1 "up" is one exchange step.

    Args:
        J_cand: candidate Jacobian blocks (N, k, n).
        m: number of poses, m·k ≥ n.
        index: "O1".."O5" or "A".
        rng: generator or seed for the random start.
        start: initial design, m distinct indices (default random).
        max_depth: deepest excursion tried.
        max_iter: maximum number of accepted excursions.
        fast: rank-k updates (True) or exact recomputation of every candidate
            design from scratch (False, slow reference).
        prune: for indices other than O1, number of best candidates by the
            D-criterion evaluated exactly (None: all).
        ridge: relative ridge δ for the D-criterion (see module docstring).
    """
    problem = ScoringProblem(J_cand, index, fast, prune, ridge)
    m = problem.check_m(m)
    if max_depth < 1:
        raise PincalError(f"max_depth must be >= 1; got {max_depth}")
    if start is None:
        members = [int(i) for i in _rng(rng).choice(problem.N, size=m, replace=False)]
    else:
        members = problem.check_start(start, m, exact_len=True)
    best = ScoringState(problem, members)
    best_value = problem.exact(best.members)
    history = [best_value]
    rounds = 0
    converged = False
    while rounds < max_iter:
        rounds += 1
        accepted = False
        for depth in range(1, max_depth + 1):
            for direction in ("up", "down"):
                trial = best.copy()
                if direction == "up":
                    if m + depth > problem.N:
                        continue
                    for _ in range(depth):
                        trial.add(problem.best_add(trial, ~trial.mask))
                    for _ in range(depth):
                        trial.remove(problem.best_remove(trial, trial.members))
                else:
                    if m - depth < 1 or problem.N - m < depth:
                        continue
                    removed: list[int] = []
                    for _ in range(depth):
                        c = problem.best_remove(trial, trial.members)
                        trial.remove(c)
                        removed.append(c)
                    allowed_extra = np.ones(problem.N, dtype=bool)
                    allowed_extra[removed] = False
                    for _ in range(depth):
                        trial.add(problem.best_add(trial, ~trial.mask & allowed_extra))
                value = problem.exact(trial.members)
                if value > best_value + _REL_TOL * abs(best_value):
                    trial.refresh()
                    best, best_value, accepted = trial, value, True
                    break
            if accepted:
                break
        history.append(best_value)
        if not accepted:
            converged = True
            break
    return _result(problem, best, best_value, history, rounds, "detmax", converged)

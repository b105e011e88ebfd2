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
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pincal.design._indices import _check_index_name
from pincal.errors import PincalError, TooFewPosesError

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
_REFRESH_EVERY = 16  # Woodbury updates between exact refactorisations of A
_M_REFRESH_EVERY = 64  # rank-k updates between exact recomputations of U_c A⁻¹ U_cᵀ


# ----------------------------------------------------------------------------- arrays


def _is_prime(p: int) -> bool:
    if p < 2:
        return False
    return all(p % d for d in range(2, int(p**0.5) + 1))


def bose_array(p: int) -> NDArray[np.int_]:
    """Bose's strength-2 orthogonal array L_{p²}(p^{p+1}) over GF(p).

    Run r = (i, j) ∈ GF(p)² (r = i·p + j) gets the levels
    (i, j, j + i, j + 2i, …, j + (p−1)i) mod p. Any two columns form every
    level pair exactly once: column i with column j + s·i fixes (i, j), and two
    columns j + s·i, j + t·i (s ≠ t) fix i = (a − b)/(s − t) because p is prime.

    Args:
        p: prime number of levels.

    Returns:
        Array (p², p + 1) of levels 0..p−1.
    """
    if not isinstance(p, (int, np.integer)) or not _is_prime(int(p)):
        raise PincalError(f"Bose construction needs a prime number of levels; got {p!r}")
    p = int(p)
    i = np.repeat(np.arange(p), p)
    j = np.tile(np.arange(p), p)
    cols = [i] + [(j + s * i) % p for s in range(p)]
    return np.stack(cols, axis=1)


def orthogonal_array(levels: int, factors: int) -> NDArray[np.int_]:
    """Smallest Bose array with at least ``levels`` levels and ``factors`` columns.

    Picks the smallest prime p ≥ levels with p + 1 ≥ factors and returns the
    first ``factors`` columns of L_{p²}(p^{p+1}) (a column subset of an
    orthogonal array is one). Examples: (5, 6) → L25(5⁶), (7, 8) → L49(7⁸),
    (3, 6) → p = 5.

    Args:
        levels: minimum number of levels per factor, ≥ 2.
        factors: number of factors (columns), ≥ 1.

    Returns:
        Array (p², factors) of levels 0..p−1; p = ``table.max() + 1``.
    """
    if levels < 2 or factors < 1:
        raise PincalError(
            f"need levels >= 2 and factors >= 1; got levels={levels}, factors={factors}"
        )
    p = max(int(levels), int(factors) - 1, 2)
    while not _is_prime(p):
        p += 1
    return bose_array(p)[:, :factors]


def map_to_ranges(table: ArrayLike, lower: ArrayLike, upper: ArrayLike) -> NDArray[np.float64]:
    """Map an orthogonal array onto workspace factor ranges.

    Level l of a p-level column becomes lower + (upper − lower)·l/(p − 1): the p
    levels are evenly spaced and include both ends of each range.

    Args:
        table: integer array (runs, factors) with levels 0..p−1.
        lower: lower bound of each factor, shape (factors,) [m or rad].
        upper: upper bound of each factor, shape (factors,).

    Returns:
        Factor values (runs, factors), e.g. workspace poses (x, y, z, rx, ry, rz).
    """
    t = np.asarray(table)
    lo = np.asarray(lower, dtype=float).reshape(-1)
    hi = np.asarray(upper, dtype=float).reshape(-1)
    if t.ndim != 2 or not np.issubdtype(t.dtype, np.integer) or t.min(initial=0) < 0:
        raise PincalError(
            f"table must be a non-negative integer array (runs, factors); got {t.shape}"
        )
    if lo.shape != (t.shape[1],) or hi.shape != (t.shape[1],):
        raise PincalError(
            f"lower and upper need one bound per factor ({t.shape[1]}); got {lo.shape}, {hi.shape}"
        )
    p = int(t.max()) + 1
    if p < 2:
        raise PincalError("table must have at least two levels")
    return lo + (hi - lo) * (t / (p - 1))


# ----------------------------------------------------------------------------- results


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


# ----------------------------------------------------------------------------- scoring


def _batch_index(s: NDArray[np.float64], rows: int, m: int, name: str) -> NDArray[np.float64]:
    """Index of each design from its singular values s (B, min(rows, n)) → (B,)."""
    n_sv = s.shape[1]
    eps = np.finfo(float).eps
    s1 = s[:, 0]
    sL = s[:, -1]
    full = (sL > s1 * max(rows, n_sv) * eps) & (s1 > 0.0)
    out = np.zeros(s.shape[0])
    if not np.any(full):
        return out
    sf = s[full]
    s1f, sLf = s1[full], sL[full]
    if name == "O1":
        val = np.exp(np.mean(np.log(sf), axis=1)) / np.sqrt(m)
    elif name == "O2":
        val = sLf / s1f
    elif name == "O3":
        val = sLf
    elif name == "O4":
        val = sLf * sLf / s1f
    elif name == "O5":
        val = 1.0 / np.sum(1.0 / sf, axis=1)
    else:  # "A"
        val = 1.0 / np.sum(sf**-2, axis=1)
    out[full] = val
    return out


class _Problem:
    """Candidate blocks, criterion and scoring (fast rank-k or from scratch)."""

    def __init__(
        self, J_cand: ArrayLike, index: str, fast: bool, prune: int | None, ridge: float
    ) -> None:
        J = np.ascontiguousarray(J_cand, dtype=float)
        if J.ndim != 3 or min(J.shape) == 0:
            raise PincalError(
                f"J_cand must have shape (N_candidates, k, n) with all sizes >= 1; got {J.shape}"
            )
        if not np.all(np.isfinite(J)):
            raise PincalError("J_cand contains NaN or infinite entries")
        self.J = J
        self.N, self.k, self.n = J.shape
        self.index = _check_index_name(index)
        self.fast = bool(fast)
        if prune is not None and prune < 1:
            raise PincalError(f"prune must be None or >= 1; got {prune}")
        self.prune = prune
        if not ridge > 0.0:
            raise PincalError(f"ridge must be > 0; got {ridge}")
        mean_diag = float(np.einsum("ikj,ikj->", J, J)) / (self.N * self.n)
        if mean_diag == 0.0:
            raise PincalError("all candidate Jacobian blocks are zero")
        self.delta = ridge * mean_diag
        self.stacked = J.reshape(self.N * self.k, self.n)
        self.JT = np.ascontiguousarray(J.transpose(0, 2, 1))

    def check_m(self, m: int, min_m: int = 1) -> int:
        if not isinstance(m, (int, np.integer)) or not min_m <= m <= self.N:
            raise PincalError(f"m must be an integer in [{min_m}, {self.N}]; got {m!r}")
        if m * self.k < self.n:
            raise TooFewPosesError(
                f"{m} poses × {self.k} rows < {self.n} parameters; need at least "
                f"{-(-self.n // self.k)} poses"
            )
        return int(m)

    def check_start(self, start: ArrayLike, max_len: int, exact_len: bool) -> list[int]:
        s = np.asarray(start).reshape(-1)
        ok = s.size == 0 or (
            np.issubdtype(s.dtype, np.integer) and s.min() >= 0 and s.max() < self.N
        )
        if (
            not ok
            or np.unique(s).size != s.size
            or (s.size != max_len if exact_len else s.size > max_len)
        ):
            size = f"exactly {max_len}" if exact_len else f"at most {max_len}"
            raise PincalError(
                f"start must hold {size} distinct candidate indices in [0, {self.N}); got {s!r}"
            )
        return [int(i) for i in s]

    # --- exact evaluation -------------------------------------------------------------

    def exact(self, members: Sequence[int]) -> float:
        """Exact index of one design (SVD of its stacked Jacobian)."""
        if len(members) == 0:
            return 0.0
        Js = self.J[np.asarray(members)].reshape(-1, self.n)
        s = np.linalg.svd(Js, compute_uv=False)
        return float(self._index_from_sv(s[None, :], Js.shape[0], len(members))[0])

    def _index_from_sv(self, s: NDArray[np.float64], rows: int, m: int) -> NDArray[np.float64]:
        if s.shape[1] < self.n:  # fewer rows than parameters: rank-deficient
            return np.zeros(s.shape[0])
        return _batch_index(s, rows, m, self.index)

    def scratch_keys(
        self, sets: NDArray[np.int_], chunk: int = 256
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """(exact index, ridge log det) of each design in ``sets`` (B, size), from scratch."""
        B, size = sets.shape
        rows = size * self.k
        exact = np.empty(B)
        logdet = np.empty(B)
        eye = self.delta * np.eye(self.n)
        for lo in range(0, B, chunk):
            Js = self.J[sets[lo : lo + chunk]].reshape(-1, rows, self.n)
            s = np.linalg.svd(Js, compute_uv=False)
            exact[lo : lo + chunk] = self._index_from_sv(s, rows, size)
            G = np.matmul(Js.transpose(0, 2, 1), Js) + eye
            sign, ld = np.linalg.slogdet(G)
            logdet[lo : lo + chunk] = np.where(sign > 0, ld, -np.inf)
        return exact, logdet

    # --- rank-k scoring -------------------------------------------------------------

    def add_logdets(self, state: _State) -> NDArray[np.float64]:
        """log det(A + UᵀU) for every candidate U by the determinant lemma, (N,).

        Uses M_c = U_c A⁻¹ U_cᵀ (N, k, k), which the state keeps up to date with
        rank-k updates (O(N·k²·n) per pose change instead of O(N·k·n²)).
        """
        if state.M is None:
            W = (self.stacked @ state.Ainv).reshape(self.N, self.k, self.n)
            state.M = np.matmul(W, self.JT)
        sign, ld = np.linalg.slogdet(state.M + np.eye(self.k))
        return np.where(sign > 0, state.logdet + ld, -np.inf)

    def remove_logdets(self, state: _State, members: NDArray[np.int_]) -> NDArray[np.float64]:
        """log det(A − UᵀU) for removing each of ``members``, (len(members),)."""
        U = self.J[members]
        W = np.matmul(U, state.Ainv)
        C = np.eye(self.k) - np.matmul(W, U.transpose(0, 2, 1))
        sign, ld = np.linalg.slogdet(C)
        return np.where(sign > 0, state.logdet + ld, -np.inf)

    # --- choices ---------------------------------------------------------------------

    def best_add(self, state: _State, allowed: NDArray[np.bool_]) -> int:
        """Candidate (among ``allowed``) whose addition maximises the index."""
        cand = np.flatnonzero(allowed)
        if not self.fast:
            base = np.asarray(state.members, dtype=int)
            sets = np.concatenate([np.broadcast_to(base, (cand.size, base.size)), cand[:, None]], 1)
            exact, ld = self.scratch_keys(sets)
            return int(cand[np.lexsort((ld, exact))[-1]])
        ld_all = self.add_logdets(state)[cand]
        if self.index == "O1":
            return int(cand[np.argmax(ld_all)])
        if self.prune is not None and self.prune < cand.size:
            keep = np.argpartition(ld_all, -self.prune)[-self.prune :]
            cand, ld_all = cand[keep], ld_all[keep]
        size = len(state.members) + 1
        if state.members:
            R = np.linalg.qr(self.J[np.asarray(state.members)].reshape(-1, self.n), mode="r")
        else:
            R = np.zeros((0, self.n))
        stacked = np.concatenate([np.broadcast_to(R, (cand.size, *R.shape)), self.J[cand]], 1)
        s = np.linalg.svd(stacked, compute_uv=False)
        exact = self._index_from_sv(s, size * self.k, size)
        return int(cand[np.lexsort((ld_all, exact))[-1]])

    def best_remove(self, state: _State, removable: Sequence[int]) -> int:
        """Member (among ``removable``) whose removal keeps the index highest."""
        rem = np.asarray(removable, dtype=int)
        members = np.asarray(state.members, dtype=int)
        if not self.fast or self.index != "O1":
            sets = np.stack([members[members != r] for r in rem])
            if self.fast:
                exact, _ = self.scratch_keys(sets)
                ld = self.remove_logdets(state, rem)
            else:
                exact, ld = self.scratch_keys(sets)
            return int(rem[np.lexsort((ld, exact))[-1]])
        return int(rem[np.argmax(self.remove_logdets(state, rem))])


class _State:
    """A design: members, A = δI + Σ UᵀU, A⁻¹ (Woodbury-updated), log det A.

    ``M`` (N, k, k), when not None, holds U_c A⁻¹ U_cᵀ for every candidate c and is
    updated together with A⁻¹: if A⁻¹ ← A⁻¹ ∓ Wᵀ C⁻¹ W then
    M_c ← M_c ∓ (U_c Wᵀ) C⁻¹ (U_c Wᵀ)ᵀ.
    """

    def __init__(self, problem: _Problem, members: Sequence[int]) -> None:
        self.p = problem
        self.members: list[int] = list(members)
        self.mask = np.zeros(problem.N, dtype=bool)
        self.mask[self.members] = True
        self.refresh()

    def copy(self) -> _State:
        new = object.__new__(_State)
        new.p = self.p
        new.members = list(self.members)
        new.mask = self.mask.copy()
        new.A, new.Ainv, new.logdet = self.A.copy(), self.Ainv.copy(), self.logdet
        new._updates, new._m_updates = self._updates, self._m_updates
        new.M = None if self.M is None else self.M.copy()
        return new

    def refresh(self, reset_m: bool = True) -> None:
        """Recompute A, A⁻¹ and log det A from the members (removes drift).

        With ``reset_m`` the candidate products M are dropped too (recomputed in
        full by the next scoring); otherwise they keep being rank-k updated.
        """
        p = self.p
        A = p.delta * np.eye(p.n)
        if self.members:
            Js = p.J[np.asarray(self.members)].reshape(-1, p.n)
            A += Js.T @ Js
        L = np.linalg.cholesky(A)
        Linv = np.linalg.inv(L)
        self.A = A
        self.Ainv = Linv.T @ Linv
        self.logdet = 2.0 * float(np.sum(np.log(np.diag(L))))
        self._updates = 0
        if reset_m:
            self.M: NDArray[np.float64] | None = None
            self._m_updates = 0

    def _update(self, c: int, sign: float) -> None:
        U = self.p.J[c]
        W = U @ self.Ainv  # (k, n)
        C = np.eye(self.p.k) + sign * (W @ U.T)
        s, ld = np.linalg.slogdet(C)
        self.A += sign * (U.T @ U)
        if s <= 0 or np.linalg.cond(C) > 1e8:  # ill-conditioned update: start afresh
            self.refresh()
            return
        # Woodbury: (A ± UᵀU)⁻¹ = A⁻¹ ∓ Wᵀ (I ± W Uᵀ)⁻¹ W
        Cinv = np.linalg.inv(C)
        self.Ainv -= sign * (W.T @ Cinv @ W)
        self.Ainv = 0.5 * (self.Ainv + self.Ainv.T)
        self.logdet += ld
        if self.M is not None:
            p = self.p
            P = (p.stacked @ W.T).reshape(p.N, p.k, p.k)  # U_c Wᵀ
            self.M -= sign * np.matmul(P @ Cinv, P.transpose(0, 2, 1))
            self._m_updates += 1
        self._updates += 1
        if self._updates >= _REFRESH_EVERY:
            self.refresh(reset_m=self._m_updates >= _M_REFRESH_EVERY)

    def add(self, c: int) -> None:
        self.members.append(int(c))
        self.mask[c] = True
        self._update(c, +1.0)

    def remove(self, c: int) -> None:
        self.members.remove(int(c))
        self.mask[c] = False
        self._update(c, -1.0)


def _rng(rng: np.random.Generator | int | None) -> np.random.Generator:
    return rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)


def _result(
    problem: _Problem, state: _State, value: float, history: list[float], iterations: int,
    method: str, converged: bool,
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
    """Add/remove exchange selection of m poses (seed 000, after Daney et al.).

    Seed 000 (its Fig. 4): (1) candidates Ω0; (2) m random poses of Ω0 form Ω1;
    (3) add the pose T+ of Ω0 \\ Ω1 that maximises the index of Ω1 ∪ {T+};
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
    problem = _Problem(J_cand, index, fast, prune, ridge)
    m = problem.check_m(m)
    if m >= problem.N:
        raise PincalError(f"exchange needs more candidates ({problem.N}) than poses ({m})")
    if start is None:
        members = [int(i) for i in _rng(rng).choice(problem.N, size=m, replace=False)]
    else:
        members = problem.check_start(start, m, exact_len=True)
    state = _State(problem, members)
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
        fast, prune, ridge: as in :func:`exchange`.
    """
    problem = _Problem(J_cand, index, fast, prune, ridge)
    m = problem.check_m(m)
    members = [] if start is None else problem.check_start(start, m, exact_len=False)
    state = _State(problem, members)
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
        fast, prune, ridge: as in :func:`exchange`.
    """
    problem = _Problem(J_cand, index, fast, prune, ridge)
    m = problem.check_m(m)
    if max_depth < 1:
        raise PincalError(f"max_depth must be >= 1; got {max_depth}")
    if start is None:
        members = [int(i) for i in _rng(rng).choice(problem.N, size=m, replace=False)]
    else:
        members = problem.check_start(start, m, exact_len=True)
    best = _State(problem, members)
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

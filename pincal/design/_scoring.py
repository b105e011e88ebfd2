"""Scoring machinery of the pose-selection algorithms (:mod:`pincal.design._exchange`).

:class:`ScoringProblem` holds the candidate blocks (N, k, n) and scores candidate designs:
exactly (singular values → :func:`pincal.design._indices.batch_indices`, the one
implementation of the index formulas) and by the ridge D-criterion
log det(δI + JᵀJ) with rank-k determinant-lemma updates. :class:`ScoringState` is one
design with A = δI + Σ UᵀU, A⁻¹ kept by Woodbury updates and the candidate products
U_c A⁻¹ U_cᵀ kept by rank-k updates.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pincal.design._indices import batch_indices, check_index_name
from pincal.errors import PincalError, TooFewPosesError
from pincal.sensitivity import full_jacobian_ranks

__all__: list[str] = []

_REFRESH_EVERY = 16  # Woodbury updates between exact refactorisations of A
_M_REFRESH_EVERY = 64  # rank-k updates between exact recomputations of U_c A⁻¹ U_cᵀ


class ScoringProblem:
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
        self.index = check_index_name(index)
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
        """``m`` if it is a number of poses this problem can select, else a PincalError."""
        if not isinstance(m, (int, np.integer)) or not min_m <= m <= self.N:
            raise PincalError(
                f"the number of poses to select must be an integer in [{min_m}, {self.N}] "
                f"(at most the {self.N} candidate poses); got {m!r}"
            )
        if m * self.k < self.n:
            raise TooFewPosesError(
                f"{m} poses × {self.k} rows < {self.n} parameters; need at least "
                f"{-(-self.n // self.k)} poses"
            )
        return int(m)

    def check_start(self, start: ArrayLike, max_len: int, exact_len: bool) -> list[int]:
        """The start selection as candidate indices, checked (distinct, in range, length)."""
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
        return float(self._index_from_sv(s[None, :], len(members), Js[None])[0])

    def _index_from_sv(
        self, s: NDArray[np.float64], m: int, Js: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """Exact index of each design from its singular values s (B, min(rows, n)) → (B,).

        ``Js`` (B, rows, n): the designs' stacked Jacobians (or any with the same column
        norms and singular values, e.g. [R; U] of a QR); whether a design has full rank
        is :func:`pincal.sensitivity.full_jacobian_ranks` (unit columns), the rule of
        ``info``, the presets and identification, whatever the row scaling.
        """
        if s.shape[1] < self.n:  # fewer rows than parameters: rank-deficient
            return np.zeros(s.shape[0])
        full = full_jacobian_ranks(Js, s)
        return batch_indices(s, m, (self.index,), full=full)[self.index]

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
            exact[lo : lo + chunk] = self._index_from_sv(s, size, Js)
            G = np.matmul(Js.transpose(0, 2, 1), Js) + eye
            sign, ld = np.linalg.slogdet(G)
            logdet[lo : lo + chunk] = np.where(sign > 0, ld, -np.inf)
        return exact, logdet

    # --- rank-k scoring -------------------------------------------------------------

    def add_logdets(self, state: ScoringState) -> NDArray[np.float64]:
        """Log det(A + UᵀU) for every candidate U by the determinant lemma, (N,).

        Uses M_c = U_c A⁻¹ U_cᵀ (N, k, k), which the state keeps up to date with
        rank-k updates (O(N·k²·n) per pose change instead of O(N·k·n²)).
        """
        if state.M is None:
            W = (self.stacked @ state.Ainv).reshape(self.N, self.k, self.n)
            state.M = np.matmul(W, self.JT)
        sign, ld = np.linalg.slogdet(state.M + np.eye(self.k))
        return np.where(sign > 0, state.logdet + ld, -np.inf)

    def remove_logdets(self, state: ScoringState, members: NDArray[np.int_]) -> NDArray[np.float64]:
        """Log det(A − UᵀU) for removing each of ``members``, (len(members),)."""
        U = self.J[members]
        W = np.matmul(U, state.Ainv)
        C = np.eye(self.k) - np.matmul(W, U.transpose(0, 2, 1))
        sign, ld = np.linalg.slogdet(C)
        return np.where(sign > 0, state.logdet + ld, -np.inf)

    # --- choices ---------------------------------------------------------------------

    def best_add(self, state: ScoringState, allowed: NDArray[np.bool_]) -> int:
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
            members = self.J[np.asarray(state.members)].reshape(-1, self.n)
            R: NDArray[np.float64] = np.asarray(np.linalg.qr(members, mode="r"))
        else:
            R = np.zeros((0, self.n))
        stacked = np.concatenate([np.broadcast_to(R, (cand.size, *R.shape)), self.J[cand]], 1)
        s = np.linalg.svd(stacked, compute_uv=False)
        exact = self._index_from_sv(s, size, stacked)
        return int(cand[np.lexsort((ld_all, exact))[-1]])

    def best_remove(self, state: ScoringState, removable: Sequence[int]) -> int:
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


class ScoringState:
    """A design: members, A = δI + Σ UᵀU, A⁻¹ (Woodbury-updated), log det A.

    ``M`` (N, k, k), when not None, holds U_c A⁻¹ U_cᵀ for every candidate c and is
    updated together with A⁻¹: if A⁻¹ ← A⁻¹ ∓ Wᵀ C⁻¹ W then
    M_c ← M_c ∓ (U_c Wᵀ) C⁻¹ (U_c Wᵀ)ᵀ.
    """

    def __init__(self, problem: ScoringProblem, members: Sequence[int]) -> None:
        self.p = problem
        self.members: list[int] = list(members)
        self.mask = np.zeros(problem.N, dtype=bool)
        self.mask[self.members] = True
        self.refresh()

    def copy(self) -> ScoringState:
        """An independent copy (information matrix and inverse included)."""
        new = object.__new__(ScoringState)
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
        """Add candidate ``c`` (rank-k update of the information matrix and its inverse)."""
        self.members.append(int(c))
        self.mask[c] = True
        self._update(c, +1.0)

    def remove(self, c: int) -> None:
        """Remove candidate ``c`` (rank-k downdate)."""
        self.members.remove(int(c))
        self.mask[c] = False
        self._update(c, -1.0)

"""Square passive closure systems of N poses, solved through their block structure.

The passive closure Jacobian ``Jf`` (k × k) of a parallel machine is mostly zeros: the
passive joints of one leg (a U joint, the P of a PRS leg, the elbow of a planar
chain) appear only in the rows of that leg's closure, and only a few columns (those
of the moving platform) appear in several. With the rows of closure c and its
*private* columns as block ``B_c`` (m_c × p_c) and the *shared* columns as ``S_c``
(m_c × s), ``Jf x = b`` splits into

* a reduced s × s system ``(N_cᵀ S_c)_c · x_s = (N_cᵀ b_c)_c``, with ``N_c`` an
  orthonormal basis of the left null space of ``B_c`` (``N_cᵀ B_c = 0``);
* per closure, ``[B_c N_c] [x_c; z] = b_c − S_c x_s`` (square m_c × m_c; z = 0).

For a Stewart platform that is one 6 × 6 system and six 3 × 3 ones instead of an
18 × 18 system: numpy's batched LAPACK calls on many tiny matrices cost per matrix,
so the blocks make the solve, the inverse (for the condition check and the
sensitivities) and the determinant sign (for the assembly branch) several times
cheaper. The structure comes from which joints move which closure frames (exact
zeros); where no column is private the caller keeps the dense solve.

The sign of det ``Jf`` follows from the factorisation: with ``T = diag([B_c N_c])``,
``Tᵀ·(row and column permutation of Jf)`` is block upper triangular with diagonal
blocks ``B_cᵀ B_c`` (positive determinants) and the reduced matrix, so
``sign det Jf = σ · sign det S_red · Π sign det [B_c N_c]`` with σ a constant of the
structure (the signs of the permutations).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pincal.model.batch._batch_ops import cross3
from pincal.model.batch._range_factor import RangeFactor

__all__ = ["BlockFactor", "BlockSolver", "DenseFactor", "PassiveFactor"]


@dataclass(frozen=True)
class _Group:
    """Closures of one shape (m rows, p private columns), computed together.

    Attributes:
        m, p: rows per closure and private columns per closure.
        rows: (G, m) row indices of the G closures in ``Jf``.
        cols: (G, p) their private column indices.
        red: (G, m − p) their rows in the reduced system.
    """

    m: int
    p: int
    rows: np.ndarray
    cols: np.ndarray
    red: np.ndarray


def _permutation_sign(order: Sequence[int]) -> float:
    """Sign (+1/−1) of the permutation listing ``order`` (a rearrangement of 0 … n−1)."""
    seen, sign = [False] * len(order), 1.0
    for start in range(len(order)):
        length, i = 0, start
        while not seen[i]:
            seen[i], i, length = True, order[i], length + 1
        if length and length % 2 == 0:
            sign = -sign
    return sign


class BlockSolver:
    """The block structure of a square passive closure Jacobian (built once per mechanism).

    Use :meth:`build`; :meth:`factor` then factors the Jacobians of N poses.
    """

    def __init__(self, groups: tuple[_Group, ...], shared: np.ndarray, k: int, sign: float):
        self.groups, self.shared, self.k, self._sign = groups, shared, k, sign

    @classmethod
    def build(cls, blocks: Sequence[np.ndarray], support: np.ndarray) -> BlockSolver | None:
        """The solver of a structure, or None when the blocks do not reduce it.

        Args:
            blocks: row indices of each closure in ``Jf`` (together 0 … k−1).
            support: (k, k) True where an entry of ``Jf`` can be non-zero (rows by
                closure rows, columns by passive dofs); a superset of the true pattern
                is safe (a column private in truth but marked shared is only slower).

        Returns:
            None when ``Jf`` is not square, no column is private to one closure, no
            column is shared (one closure, or independent ones: nothing to reduce), or
            a closure has more private columns than rows (singular by structure).
        """
        support = np.asarray(support, dtype=bool)
        k = support.shape[1]
        if support.shape[0] != k or sum(len(b) for b in blocks) != k:
            return None
        owner = np.full(k, -1)
        for c, rows in enumerate(blocks):
            touched = support[np.asarray(rows)].any(axis=0)
            elsewhere = np.delete(support, np.asarray(rows), axis=0).any(axis=0)
            owner[touched & ~elsewhere] = c
        shared = np.nonzero(owner < 0)[0]
        private = [np.nonzero(owner == c)[0] for c in range(len(blocks))]
        # no shared column (one closure, or independent ones): the dense solve
        too_many = any(len(p) > len(b) for p, b in zip(private, blocks, strict=True))
        if shared.size in (0, k) or too_many:
            return None
        # reduced rows in closure order; the sign constant σ of the permutations
        red, r0 = [], 0
        for rows, cols in zip(blocks, private, strict=True):
            red.append(np.arange(r0, r0 + len(rows) - len(cols)))
            r0 += len(rows) - len(cols)
        if r0 != shared.size:  # pragma: no cover - implied by the checks above
            return None
        row_order = np.concatenate([np.asarray(b) for b in blocks])
        col_order = np.concatenate([*private, shared])
        b_rows: list[int] = []
        n_rows: list[int] = []
        start = 0
        for rows, cols in zip(blocks, private, strict=True):
            b_rows += range(start, start + len(cols))
            n_rows += range(start + len(cols), start + len(rows))
            start += len(rows)
        sign = (
            _permutation_sign(list(row_order))
            * _permutation_sign(list(col_order))
            * _permutation_sign(b_rows + n_rows)
        )
        shapes: dict[tuple[int, int], list[int]] = {}
        for c, (rows, cols) in enumerate(zip(blocks, private, strict=True)):
            shapes.setdefault((len(rows), len(cols)), []).append(c)
        groups = tuple(
            _Group(
                m,
                p,
                np.array([np.asarray(blocks[c]) for c in cs]).reshape(len(cs), m),
                np.array([private[c] for c in cs], dtype=int).reshape(len(cs), p),
                np.array([red[c] for c in cs], dtype=int).reshape(len(cs), m - p),
            )
            for (m, p), cs in sorted(shapes.items())
        )
        return cls(groups, shared, k, sign)

    def factor(self, Jf: np.ndarray) -> BlockFactor:
        """Factor the passive closure Jacobians ``Jf`` (N, k, k) of N poses.

        Poses whose blocks are exactly singular (or not finite) are flagged in
        :attr:`BlockFactor.singular` and factored as identities (their solutions are
        meaningless; callers treat them as failed).
        """
        N = Jf.shape[0]
        s = self.shared.size
        singular = ~np.all(np.isfinite(Jf), axis=(1, 2))
        parts = []
        Sred = np.empty((N, s, s))
        sign = np.full(N, self._sign)
        for g in self.groups:
            B = Jf[:, g.rows[:, :, None], g.cols[:, None, :]]  # (N, G, m, p)
            S = Jf[:, g.rows[:, :, None], self.shared]  # (N, G, m, s)
            Nul, Tinv, det = _null_and_inverse(B, g.m, g.p)
            bad = ~np.isfinite(det) | (det == 0.0)
            singular |= bad.any(axis=1)
            sign *= np.prod(np.sign(np.where(bad, 1.0, det)), axis=1)
            red = _apply(np.swapaxes(Nul, 2, 3), S)
            Sred[:, g.red.ravel()] = red.reshape(N, -1, s)
            parts.append(_Part(Nul, Tinv, S))
        Sred[singular] = np.eye(s)
        return BlockFactor(self, tuple(parts), Sred, sign, singular)


def _null_and_inverse(B: np.ndarray, m: int, p: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Left null bases N (…, m, m−p), inverses of T = [B N] (…, m, m) and det T (…).

    N is orthonormal and orthogonal to the range of B, so the first p rows of T⁻¹ are
    the pseudo-inverse B⁺ and the last m − p rows are Nᵀ.
    """
    lead = B.shape[:-2]
    if p == 0:
        eye = np.broadcast_to(np.eye(m), (*lead, m, m))
        return eye, eye, np.ones(lead)
    if (m, p) == (3, 2):
        b1, b2 = B[..., 0], B[..., 1]
        n = cross3(b1, b2)
        det = np.sqrt(np.sum(n * n, axis=-1))  # det [b1 b2 n/|n|] = |b1 × b2|
        d = np.where(det > 0.0, det, 1.0)[..., None]
        n = n / d
        Tinv = np.stack([cross3(b2, n) / d, cross3(n, b1) / d, n], axis=-2)
        return n[..., None], Tinv, det
    if (m, p) == (2, 1):
        b = B[..., 0]
        det = np.hypot(b[..., 0], b[..., 1])  # det [b n] = |b| with n = perp(b)/|b|
        d = np.where(det > 0.0, det, 1.0)
        n = np.stack([-b[..., 1], b[..., 0]], axis=-1) / d[..., None]
        Tinv = np.stack([b / d[..., None] ** 2, n], axis=-2)
        return n[..., None], Tinv, det
    if p == m:
        Nul = np.zeros((*lead, m, 0))
        T = B
    else:
        Q = np.linalg.qr(B, mode="complete")[0]
        Nul = Q[..., p:]
        T = np.concatenate([B, Nul], axis=-1)
    det = np.linalg.det(T)
    T = np.where(((det == 0.0) | ~np.isfinite(det))[..., None, None], np.eye(m), T)
    return Nul, np.linalg.inv(T), det


def _apply(A: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Stacked products ``A @ x`` of (…, a, b) by (…, b, r).

    With one row or one right-hand side the product is written as b broadcast terms:
    numpy's stacked matmul costs per tiny matrix.
    """
    a, b = A.shape[-2:]
    if a == 1 or x.shape[-1] == 1:
        out = A[..., :, 0:1] * x[..., 0:1, :]
        for j in range(1, b):
            out = out + A[..., :, j : j + 1] * x[..., j : j + 1, :]
        return out
    return A @ x


@dataclass(frozen=True)
class _Part:
    """One group's factors: null bases (N, G, m, m−p), [B N]⁻¹ (N, G, m, m), S (N, G, m, s)."""

    null: np.ndarray
    tinv: np.ndarray
    shared: np.ndarray


@dataclass(frozen=True)
class BlockFactor:
    """The factors of N passive closure Jacobians (from :meth:`BlockSolver.factor`).

    Attributes:
        solver: the structure.
        parts: per closure group, its factors.
        reduced: (N, s, s) reduced matrices ``(N_cᵀ S_c)_c``.
        block_sign: (N,) product of the signs of det ``[B_c N_c]`` times σ.
        singular: (N,) True where a block is exactly singular.
    """

    solver: BlockSolver
    parts: tuple[_Part, ...]
    reduced: np.ndarray
    block_sign: np.ndarray
    singular: np.ndarray

    def take(self, rows: slice | np.ndarray) -> BlockFactor:
        """The factors of poses ``rows``."""
        parts = tuple(_Part(p.null[rows], p.tinv[rows], p.shared[rows]) for p in self.parts)
        return BlockFactor(
            self.solver, parts, self.reduced[rows], self.block_sign[rows], self.singular[rows]
        )

    def sign(self) -> np.ndarray:
        """(N,) sign of det ``Jf`` (0 where singular)."""
        det_sign = np.linalg.slogdet(self.reduced)[0]
        return np.where(self.singular, 0.0, self.block_sign * det_sign)

    def solve(self, b: np.ndarray) -> np.ndarray:
        """Solutions x (N, k, r) of ``Jf x = b`` for right-hand sides b (N or 1, k, r).

        Raises:
            numpy.linalg.LinAlgError: a reduced matrix is exactly singular.
        """
        sv = self.solver
        N, r = self.reduced.shape[0], b.shape[2]
        rhs = np.empty((N, sv.shared.size, r))
        for g, part in zip(sv.groups, self.parts, strict=True):
            rhs[:, g.red.ravel()] = _apply(np.swapaxes(part.null, 2, 3), b[:, g.rows]).reshape(
                N, -1, r
            )
        xs = np.linalg.solve(self.reduced, rhs)
        x = np.empty((N, sv.k, r))
        x[:, sv.shared] = xs
        for g, part in zip(sv.groups, self.parts, strict=True):
            rest = b[:, g.rows] - _apply(part.shared, xs[:, None])
            x[:, g.cols.ravel()] = _apply(part.tinv[..., : g.p, :], rest).reshape(N, -1, r)
        return x

    def solve_transposed(self, g_rhs: np.ndarray) -> np.ndarray:
        """Solutions y (N, k, r) of ``Jfᵀ y = g`` for right-hand sides g (N, k, r).

        ``y_c = B_c⁺ᵀ g_c + N_c z_c`` solves the private rows; the shared rows give
        ``S_redᵀ z = g_s − Σ_c S_cᵀ B_c⁺ᵀ g_c``.

        Raises:
            numpy.linalg.LinAlgError: a reduced matrix is exactly singular.
        """
        sv = self.solver
        N, r = g_rhs.shape[0], g_rhs.shape[2]
        rhs = np.array(g_rhs[:, sv.shared])
        heads: list[np.ndarray | None] = []
        for g, part in zip(sv.groups, self.parts, strict=True):
            gc = g_rhs[:, g.cols]
            if g.p == 0 or not gc.any():  # e.g. a measured frame on the shared body
                heads.append(None)
                continue
            head = _apply(np.swapaxes(part.tinv[..., : g.p, :], 2, 3), gc)  # (N, G, m, r)
            rhs -= np.sum(_apply(np.swapaxes(part.shared, 2, 3), head), axis=1)
            heads.append(head)
        z = np.linalg.solve(np.swapaxes(self.reduced, 1, 2), rhs)
        y = np.empty((N, sv.k, r))
        for g, part, h in zip(sv.groups, self.parts, heads, strict=True):
            yc = _apply(part.null, z[:, g.red])
            y[:, g.rows.ravel()] = (yc if h is None else h + yc).reshape(N, -1, r)
        return y

    def inverse_norm_bound(self) -> np.ndarray:
        """(N,) an upper bound of ‖Jf⁻¹‖₂ (Frobenius norms of the factors).

        ``x_s = S_red⁻¹ Nᵀ b`` and ``x_c = B_c⁺ (b_c − S_c x_s)`` give
        ``‖Jf⁻¹‖² ≤ ‖S_red⁻¹‖² + Σ_c ‖B_c⁺‖² (1 + ‖S_c‖ ‖S_red⁻¹‖)²``.
        """
        with np.errstate(all="ignore"):
            inv = np.linalg.inv(self.reduced)
        si = np.sqrt(np.sum(inv * inv, axis=(1, 2)))
        total = si * si
        for g, part in zip(self.solver.groups, self.parts, strict=True):
            bp = np.sum(part.tinv[..., : g.p, :] ** 2, axis=(2, 3))  # (N, G)
            sn = np.sqrt(np.sum(part.shared**2, axis=(2, 3)))
            total = total + np.sum(bp * (1.0 + sn * si[:, None]) ** 2, axis=1)
        return np.sqrt(total)


@dataclass(frozen=True)
class DenseFactor:
    """:class:`BlockFactor`'s interface for Jacobians without a block structure (LAPACK).

    Attributes:
        jacobian: (N, k, k) the Jacobians (rows not finite replaced by identities).
        singular: (N,) True where the Jacobian was not finite.
    """

    jacobian: np.ndarray
    singular: np.ndarray

    @classmethod
    def of(cls, Jf: np.ndarray) -> DenseFactor:
        """The factor of Jacobians ``Jf`` (N, k, k)."""
        singular = ~np.all(np.isfinite(Jf), axis=(1, 2))
        J = np.array(Jf)
        J[singular] = np.eye(J.shape[1])
        return cls(J, singular)

    def take(self, rows: slice | np.ndarray) -> DenseFactor:
        """The factors of poses ``rows``."""
        return DenseFactor(self.jacobian[rows], self.singular[rows])

    def sign(self) -> np.ndarray:
        """(N,) sign of det ``Jf`` (0 where singular)."""
        return np.where(self.singular, 0.0, np.linalg.slogdet(self.jacobian)[0])

    def solve(self, b: np.ndarray) -> np.ndarray:
        """Solutions x (N, k, r) of ``Jf x = b`` (raises LinAlgError when exactly singular)."""
        return np.linalg.solve(
            self.jacobian, np.broadcast_to(b, (len(self.jacobian), *b.shape[1:]))
        )

    def solve_transposed(self, g_rhs: np.ndarray) -> np.ndarray:
        """Solutions y (N, k, r) of ``Jfᵀ y = g``."""
        return np.linalg.solve(np.swapaxes(self.jacobian, 1, 2), g_rhs)

    def inverse_norm_bound(self) -> np.ndarray:
        """(N,) ‖Jf⁻¹‖_F, an upper bound of ‖Jf⁻¹‖₂."""
        with np.errstate(all="ignore"):
            inv = np.linalg.inv(self.jacobian)
        return np.sqrt(np.sum(inv * inv, axis=(1, 2)))


#: the factor of passive closure Jacobians: block-structured, dense, or non-square
PassiveFactor = BlockFactor | DenseFactor | RangeFactor

"""Non-square passive closure systems of N poses: minimum-norm least squares by QR.

The passive closure Jacobian ``Jf`` (m × k) of a mechanism is not square when its
loops carry redundant rows (a ``6d`` closure of a planar loop, the two cuts of a
parallelogram: m > k) or idle passive motion (the spin of a rod between two ball
joints: m < k). Where its rank is min(m, k) at home — the closures the loader
accepts as regular — the pose-by-pose solver's truncated SVD keeps every singular
value away from singular poses, and its minimum-norm least-squares solution equals
the one of a thin QR factorisation of the tall orientation:

* m > k: ``Jf = Q R`` gives ``Jf⁺ = R⁻¹ Qᵀ`` and ``(Jfᵀ)⁺ = Q R⁻ᵀ``;
* m < k: ``Jfᵀ = Q R`` gives ``Jf⁺ = Q R⁻ᵀ`` and ``(Jfᵀ)⁺ = R⁻¹ Qᵀ``.

The singular values of R are those of ``Jf``, so ``‖R⁻¹‖_F`` bounds ``1/σ_min`` for
the condition check, and the assembly branch is the sign of det of the square block
of independent rows and non-idle columns chosen at home (``Mechanism`` docs). numpy
factors the N matrices in one call each (QR, inverse, determinant).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["RangeFactor"]


@dataclass(frozen=True)
class RangeFactor:
    """Thin QR factors of N non-square passive closure Jacobians of full rank min(m, k).

    Attributes:
        q: (N, max(m, k), r) orthonormal basis of the range of the tall orientation
            (``Jf`` when m > k, ``Jfᵀ`` when m < k), r = min(m, k).
        rinv: (N, r, r) inverse of its triangular factor R.
        tall: whether ``Jf`` itself is the tall orientation (m > k).
        block_sign: (N,) sign of det of the branch block of ``Jf``.
        singular: (N,) True where ``Jf`` was not finite or R exactly singular.
    """

    q: np.ndarray
    rinv: np.ndarray
    tall: bool
    block_sign: np.ndarray
    singular: np.ndarray

    @classmethod
    def of(cls, Jf: np.ndarray, block: tuple[np.ndarray, np.ndarray] | None) -> RangeFactor:
        """Factor Jacobians ``Jf`` (N, m, k), m ≠ k.

        Args:
            Jf: the passive closure Jacobians.
            block: (rows, cols) of the square branch block (None: no branch, sign 0).
        """
        N, m, k = Jf.shape
        tall = m > k
        singular = ~np.all(np.isfinite(Jf), axis=(1, 2))
        J = np.where(singular[:, None, None], np.eye(m, k), Jf)
        Q, R = np.linalg.qr(J if tall else np.swapaxes(J, 1, 2))
        diag = np.abs(np.diagonal(R, axis1=1, axis2=2))
        singular |= ~np.all(diag > 0.0, axis=1)
        R[singular] = np.eye(R.shape[1])
        if block is None:
            sign = np.zeros(N)
        else:
            rows, cols = block
            sign = np.linalg.slogdet(J[:, rows[:, None], cols])[0]
        return cls(Q, np.linalg.inv(R), tall, sign, singular)

    def take(self, rows: slice | np.ndarray) -> RangeFactor:
        """The factors of poses ``rows``."""
        return RangeFactor(
            self.q[rows], self.rinv[rows], self.tall, self.block_sign[rows], self.singular[rows]
        )

    def sign(self) -> np.ndarray:
        """(N,) sign of det of the branch block (0 where singular)."""
        return np.where(self.singular, 0.0, self.block_sign)

    def _pinv_tall(self, b: np.ndarray) -> np.ndarray:
        """``T⁺ b = R⁻¹ Qᵀ b`` of the tall orientation T, b (N, max(m, k), r)."""
        return self.rinv @ (np.swapaxes(self.q, 1, 2) @ b)

    def _pinv_wide(self, b: np.ndarray) -> np.ndarray:
        """``(Tᵀ)⁺ b = Q R⁻ᵀ b`` of the tall orientation T, b (N, min(m, k), r)."""
        return self.q @ (np.swapaxes(self.rinv, 1, 2) @ b)

    def solve(self, b: np.ndarray) -> np.ndarray:
        """Minimum-norm least-squares solutions x (N, k, r) of ``Jf x = b`` (b (N, m, r))."""
        b = np.broadcast_to(b, (self.q.shape[0], *b.shape[1:]))
        return self._pinv_tall(b) if self.tall else self._pinv_wide(b)

    def solve_transposed(self, g_rhs: np.ndarray) -> np.ndarray:
        """Minimum-norm least-squares solutions y (N, m, r) of ``Jfᵀ y = g`` (g (N, k, r))."""
        return self._pinv_wide(g_rhs) if self.tall else self._pinv_tall(g_rhs)

    def inverse_norm_bound(self) -> np.ndarray:
        """(N,) ``‖R⁻¹‖_F``, an upper bound of 1/σ_min(Jf) (σ_min: the r-th value)."""
        return np.sqrt(np.sum(self.rinv * self.rinv, axis=(1, 2)))

    def out_of_range(self, B: np.ndarray) -> np.ndarray:
        """(N, n) norm of each column of B (N, m, n) outside the range of ``Jf``.

        Zero when ``Jf`` has full row rank (m < k): every column is in its range.
        """
        if not self.tall:
            return np.zeros((B.shape[0], B.shape[2]))
        rest = B - self.q @ (np.swapaxes(self.q, 1, 2) @ B)
        return np.sqrt(np.sum(rest * rest, axis=1))

"""How the residuals were weighted: declared or estimated noise, and robust weights.

:class:`Weighting` is what an :class:`pincal.identification.IdentificationResult`
reports about its weights: where the noise standard deviations came from (declared by
the instrument / the caller, per-pose values of the file, or estimated from the
residuals by variance-component estimation), the robust loss and the poses it
down-weighted. The helpers here compute the redundancy shares and robust weights.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "DOWNWEIGHT_LIMIT",
    "INLIER_LIMIT",
    "ROBUST_F_SCALE",
    "Weighting",
    "data_leverage",
    "data_rows_loss",
    "hat_diagonal",
    "loss_derivatives",
    "loss_terms",
    "robust_cost",
    "robust_weights",
]

#: a pose is reported as down-weighted by a robust loss below this weight
DOWNWEIGHT_LIMIT = 0.5
#: |whitened residual| above this is an outlier (and left out of a robust noise estimate)
INLIER_LIMIT = 3.0
#: default f_scale [σ] per robust loss: the weight ρ'(z) falls to 0.5 at 3σ
ROBUST_F_SCALE = {
    "huber": 1.5,  # weight f/|r|: 0.5 at 2f
    "soft_l1": math.sqrt(3.0),  # (1 + (r/f)²)^-½: 0.5 at √3 f
    "cauchy": 3.0,  # 1 / (1 + (r/f)²): 0.5 at f
    "arctan": 3.0,  # 1 / (1 + (r/f)⁴): 0.5 at f
}
#: variance of a standard normal truncated to |z| ≤ INLIER_LIMIT (robust-estimate correction)
# P(|z| ≤ c) = erf(c/√2) and φ(c) = exp(-c²/2)/√(2π): no scipy.stats import (0.5 s)
_C = INLIER_LIMIT
_INSIDE = math.erf(_C / math.sqrt(2.0))
TRUNCATED_VARIANCE = (_INSIDE - 2 * _C * math.exp(-_C * _C / 2) / math.sqrt(2 * math.pi)) / _INSIDE


@dataclass(frozen=True)
class Weighting:
    """The weights of an identification.

    Attributes:
        source: ``"declared"`` (noise model of the file or the ``noise=`` argument),
            ``"per-pose"`` (per-value standard deviations of the file) or
            ``"estimated"`` (variance-component estimation from the residuals).
        position_std: noise σ per position coordinate [m] (NaN: not measured, or
            per-pose values).
        orientation_std: noise σ per rotation component [rad] (NaN likewise).
        rounds: re-weighted fits of the estimation (0 when declared).
        converged: whether the estimated σ changed by less than the tolerance in the
            last round (True when declared).
        redundancy: {block: n_b − tr(H_bb)} at the solution (block = ``position`` /
            ``orientation``): the equations of the block not used up by the fit.
        loss: the loss of the fit (``"linear"`` = least squares).
        f_scale: the robust loss' soft margin [σ of the whitened residuals] (NaN when
            linear).
        pose_weights: (m,) smallest robust weight ρ' of each pose's residuals (1 when
            linear).
        whitened: (m, k) residuals divided by their σ at the solution.
    """

    source: str
    position_std: float = float("nan")
    orientation_std: float = float("nan")
    rounds: int = 0
    converged: bool = True
    redundancy: dict[str, float] = field(default_factory=dict)
    loss: str = "linear"
    f_scale: float = float("nan")
    pose_weights: np.ndarray = field(default_factory=lambda: np.zeros(0))
    whitened: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))

    @property
    def downweighted(self) -> tuple[int, ...]:
        """Indices of the poses the robust loss gave a weight below 0.5."""
        return tuple(int(i) for i in np.flatnonzero(self.pose_weights < DOWNWEIGHT_LIMIT))

    @property
    def outliers(self) -> tuple[int, ...]:
        """Indices of the poses with a whitened residual beyond ±3."""
        if self.whitened.size == 0:
            return ()
        bad = np.any(np.abs(self.whitened) > INLIER_LIMIT, axis=1)
        return tuple(int(i) for i in np.flatnonzero(bad))

    def to_dict(self) -> dict:
        """JSON-ready form (SI; NaN written as null)."""

        def num(v: float) -> float | None:
            return float(v) if math.isfinite(float(v)) else None

        return {
            "source": self.source,
            "position_std": num(self.position_std),
            "orientation_std": num(self.orientation_std),
            "rounds": int(self.rounds),
            "converged": bool(self.converged),
            "redundancy": {k: float(v) for k, v in self.redundancy.items()},
            "loss": self.loss,
            "f_scale": num(self.f_scale),
            "pose_weights": np.asarray(self.pose_weights, dtype=float).tolist(),
            "downweighted": list(self.downweighted),
            "outliers": list(self.outliers),
            "whitened": np.asarray(self.whitened, dtype=float).tolist(),
        }

    @classmethod
    def from_dict(cls, d: dict) -> Weighting:
        """Read :meth:`to_dict`'s form (raises KeyError / TypeError / ValueError)."""

        def num(v: object) -> float:
            return float("nan") if v is None else float(v)  # type: ignore[arg-type]

        whitened = np.array(d.get("whitened", []), dtype=float)
        return cls(
            source=str(d["source"]),
            position_std=num(d.get("position_std")),
            orientation_std=num(d.get("orientation_std")),
            rounds=int(d.get("rounds", 0)),
            converged=bool(d.get("converged", True)),
            redundancy={str(k): float(v) for k, v in dict(d.get("redundancy", {})).items()},
            loss=str(d.get("loss", "linear")),
            f_scale=num(d.get("f_scale")),
            pose_weights=np.array(d.get("pose_weights", []), dtype=float),
            whitened=whitened.reshape(len(whitened), -1) if whitened.size else whitened,
        )


def loss_terms(loss: str, z: np.ndarray) -> np.ndarray:
    """ρ(z), ρ'(z), ρ''(z) of scipy's losses, z = (r/f)² (any shape) → (3, *z.shape)."""
    z = np.asarray(z, dtype=float)
    if loss == "linear":
        return np.stack([z, np.ones_like(z), np.zeros_like(z)])
    if loss == "huber":
        far = z > 1.0
        root = np.sqrt(np.where(far, z, 1.0))
        return np.stack([np.where(far, 2.0 * root - 1.0, z), np.where(far, 1.0 / root, 1.0),
                         np.where(far, -0.5 / root**3, 0.0)])  # fmt: skip
    if loss == "soft_l1":
        t = 1.0 + z
        return np.stack([2.0 * (np.sqrt(t) - 1.0), t**-0.5, -0.5 * t**-1.5])
    if loss == "cauchy":
        return np.stack([np.log1p(z), 1.0 / (1.0 + z), -1.0 / (1.0 + z) ** 2])
    if loss == "arctan":
        t = 1.0 + z**2
        return np.stack([np.arctan(z), 1.0 / t, -2.0 * z / t**2])
    raise ValueError(f"unknown loss {loss!r}")


def robust_weights(loss: str, r_w: np.ndarray, f_scale: float) -> np.ndarray:
    """IRLS weights ρ'((r/f)²) of scipy's losses for whitened residuals ``r_w`` (any shape).

    Args:
        loss: ``linear``, ``huber``, ``soft_l1``, ``cauchy`` or ``arctan``.
        r_w: whitened residuals [σ] (any shape).
        f_scale: the loss' soft margin [σ].
    """
    if loss == "linear":
        return np.ones_like(np.asarray(r_w, dtype=float))
    return loss_terms(loss, (np.asarray(r_w, dtype=float) / f_scale) ** 2)[1]


def robust_cost(loss: str, r_w: np.ndarray, f_scale: float) -> float:
    """The robust cost ``½ f² Σ ρ((r/f)²)`` of scipy's losses for whitened residuals [σ²]."""
    r = np.asarray(r_w, dtype=float).ravel()
    if loss == "linear":
        return 0.5 * float(r @ r)
    return 0.5 * f_scale**2 * float(np.sum(loss_terms(loss, (r / f_scale) ** 2)[0]))


def loss_derivatives(loss: str, r_w: np.ndarray, f_scale: float) -> tuple[np.ndarray, np.ndarray]:
    """Slope ρ' and curvature scale √(ρ' + 2zρ'') of a robust loss per whitened residual.

    The cost ``½ f² ρ((r/f)²)`` of one residual has the derivative ρ'·r and the second
    derivative ρ' + 2zρ'' (z = (r/f)²) in r. A Gauss–Newton model of the robust cost
    scales each Jacobian row by the square root of the latter, floored at machine
    precision as scipy's ``least_squares`` does (it is zero beyond Huber's margin and
    negative for Cauchy's and arctan's far residuals), and each residual by ρ'/that.

    Args:
        loss: ``linear``, ``huber``, ``soft_l1``, ``cauchy`` or ``arctan``.
        r_w: (N,) whitened residuals [σ].
        f_scale: the loss' soft margin [σ].

    Returns:
        (ρ' (N,), √max(ρ' + 2zρ'', ε) (N,)).
    """
    z = (np.asarray(r_w, dtype=float) / f_scale) ** 2
    _, slope, second = loss_terms(loss, z)
    return slope, np.sqrt(np.maximum(slope + 2.0 * z * second, np.finfo(float).eps))


def data_rows_loss(loss: str, n_data: int) -> Callable[[np.ndarray], np.ndarray]:
    """The ``loss`` callable of scipy's ``least_squares`` for the first ``n_data`` rows only.

    The rows after them (a Gaussian prior's) stay least squares.
    """

    def rho(z: np.ndarray) -> np.ndarray:
        out = loss_terms("linear", z)
        out[:, :n_data] = loss_terms(loss, z[:n_data])
        return out

    return rho


def hat_diagonal(J_w: np.ndarray, rtol: float = 1e-10) -> np.ndarray:
    """Diagonal (N,) of the hat matrix ``J (JᵀJ)⁺ Jᵀ`` of a whitened Jacobian (N, p).

    ``1 − h_ii`` is the redundancy share of equation i; the diagonal sums to rank(J).
    """
    U, s, _ = np.linalg.svd(J_w, full_matrices=False)
    keep = s > rtol * (s[0] if s.size else 0.0)
    return np.einsum("ij,ij->i", U[:, keep], U[:, keep])


def data_leverage(J_w: np.ndarray, prior: np.ndarray | None = None) -> np.ndarray:
    """(N,) leverages h_ii of the data rows of a whitened Jacobian (N, p).

    With a prior of weights 1/σ (p,) (0: none), of the regularised fit: the data rows'
    diagonal of the hat matrix of ``[J_w; diag(prior)]``, ``J (JᵀJ + diag(prior)²)⁻¹ Jᵀ``
    — what the prior holds uses up no equation.
    """
    if prior is None:
        return hat_diagonal(J_w)
    return hat_diagonal(np.vstack([J_w, np.diag(prior)]))[: J_w.shape[0]]

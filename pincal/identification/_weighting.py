"""How the residuals were weighted: declared or estimated noise, and robust weights.

:class:`Weighting` is what an :class:`pincal.identification.IdentificationResult`
reports about its weights: where the noise standard deviations came from (declared by
the instrument / the caller, per-pose values of the file, or estimated from the
residuals by variance-component estimation), the robust loss and the poses it
down-weighted. The helpers here compute the redundancy shares and robust weights.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "DOWNWEIGHT_LIMIT",
    "INLIER_LIMIT",
    "ROBUST_F_SCALE",
    "Weighting",
    "data_leverage",
    "hat_diagonal",
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


def robust_weights(loss: str, r_w: np.ndarray, f_scale: float) -> np.ndarray:
    """IRLS weights ρ'((r/f)²) of scipy's losses for whitened residuals ``r_w`` (any shape).

    Args:
        loss: ``linear``, ``huber``, ``soft_l1``, ``cauchy`` or ``arctan``.
        r_w: whitened residuals [σ] (any shape).
        f_scale: the loss' soft margin [σ].
    """
    z = (np.asarray(r_w, dtype=float) / f_scale) ** 2 if loss != "linear" else None
    if z is None:
        return np.ones_like(np.asarray(r_w, dtype=float))
    if loss == "huber":
        return np.where(z <= 1.0, 1.0, 1.0 / np.sqrt(np.maximum(z, 1.0)))
    if loss == "soft_l1":
        return 1.0 / np.sqrt(1.0 + z)
    if loss == "cauchy":
        return 1.0 / (1.0 + z)
    if loss == "arctan":
        return 1.0 / (1.0 + z**2)
    raise ValueError(f"unknown loss {loss!r}")


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

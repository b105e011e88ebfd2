"""Observability indices, Jacobian scaling and Cramér–Rao limits.

Everything here works on plain numpy arrays: an identification Jacobian is either
a stacked 2-D array ``(rows, n)`` or a block array ``(m, k, n)`` holding the ``k``
measurement rows of each of ``m`` poses for ``n`` parameters.

Observability indices (seed 000, eqs. 11–15, after Menq & Borm, Driels & Pathre,
Nahvi & Hollerbach, Sun & Hollerbach), from the singular values
σ1 ≥ … ≥ σL of the (scaled) Jacobian with L = n parameters and m poses:

=====  ==============================  ===========================================
name   definition                      meaning
=====  ==============================  ===========================================
O1     (σ1⋯σL)^(1/L) / √m              geometric mean; volume of the error ellipsoid
O2     σL / σ1                         inverse condition number
O3     σL                              smallest semi-axis
O4     σL² / σ1                        noise amplification index
O5     1 / Σ 1/σi                      harmonic mean divided by L
A      1 / Σ σi⁻²                      A-optimality: 1 / tr((JᵀJ)⁻¹)
=====  ==============================  ===========================================

All indices are "larger is better". O1 equals det(JᵀJ)^(1/(2L))/√m, so maximising
O1 for a fixed m is D-optimal design.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pincal.errors import PincalError, UnidentifiableError, UnknownNameError

__all__ = [
    "COLUMN_SCALINGS",
    "INDEX_NAMES",
    "ROW_SCALINGS",
    "DesignScaling",
    "JacobianScaling",
    "ObservabilityIndices",
    "characteristic_length",
    "crb_covariance",
    "dimensionless_rows",
    "indices_from_singular_values",
    "numerical_rank",
    "observability",
    "predicted_std",
    "predicted_validation_rms",
    "scale_columns",
    "weight_rows",
]

_log = logging.getLogger(__name__)

INDEX_NAMES: tuple[str, ...] = ("O1", "O2", "O3", "O4", "O5", "A")
"""Names accepted by :meth:`ObservabilityIndices.get` and the selection functions."""


def _check_index_name(name: str) -> str:
    if name not in INDEX_NAMES:
        raise UnknownNameError("observability index name", name, INDEX_NAMES)
    return name


def _as_stacked(J: ArrayLike, what: str = "J") -> NDArray[np.float64]:
    """Return J as a finite 2-D float array (rows, n); (m, k, n) blocks are stacked."""
    arr = np.asarray(J, dtype=float)
    if arr.ndim == 3:
        arr = arr.reshape(-1, arr.shape[-1])
    if arr.ndim != 2 or arr.shape[1] == 0:
        raise PincalError(
            f"{what} must have shape (rows, n) or (m, k, n) with n >= 1; got {np.shape(J)}"
        )
    if not np.all(np.isfinite(arr)):
        raise PincalError(f"{what} contains NaN or infinite entries")
    return arr


def numerical_rank(sigma: NDArray[np.float64], shape: tuple[int, int]) -> int:
    """Rank from singular values with the LAPACK/NumPy default tolerance.

    Args:
        sigma: singular values, descending, shape (n,) (zeros padded when rows < n).
        shape: (rows, n) of the matrix they came from.
    """
    if sigma.size == 0 or sigma[0] <= 0.0:
        return 0
    tol = sigma[0] * max(shape) * np.finfo(float).eps
    return int(np.count_nonzero(sigma > tol))


@dataclass(frozen=True, eq=False)
class ObservabilityIndices:
    """Observability indices of one stacked identification Jacobian.

    Attributes:
        O1: (σ1⋯σL)^(1/L)/√m (0 if rank-deficient).
        O2: σL/σ1 (0 if rank-deficient).
        O3: σL (0 if rank-deficient).
        O4: σL²/σ1 (0 if rank-deficient).
        O5: 1/Σ(1/σi) (0 if rank-deficient).
        a_optimality: 1/Σσi⁻² = 1/tr((JᵀJ)⁻¹) (0 if rank-deficient).
        singular_values: all L = n singular values, descending, shape (n,); when
            the Jacobian has fewer rows than columns the missing ones are 0.
        rank: numerical rank of J.
        m: number of poses used for O1.
    """

    O1: float
    O2: float
    O3: float
    O4: float
    O5: float
    a_optimality: float
    singular_values: NDArray[np.float64]
    rank: int
    m: int

    @property
    def full_rank(self) -> bool:
        """True when every parameter is observable (rank == n)."""
        return self.rank == self.singular_values.size

    @property
    def condition_number(self) -> float:
        """σ1/σL (inf if rank-deficient)."""
        return float("inf") if self.O2 == 0.0 else 1.0 / self.O2

    def get(self, name: str) -> float:
        """Index by name: one of "O1".."O5", "A"."""
        _check_index_name(name)
        return self.a_optimality if name == "A" else float(getattr(self, name))

    def as_dict(self) -> dict[str, float]:
        """All indices by name."""
        return {name: self.get(name) for name in INDEX_NAMES}


def indices_from_singular_values(
    sigma: ArrayLike, m: int, rank: int | None = None
) -> ObservabilityIndices:
    """Observability indices from the singular values of a stacked Jacobian.

    Args:
        sigma: singular values, shape (n,), descending (zeros allowed).
        m: number of poses (enters O1 only).
        rank: numerical rank; default: count of σi > σ1·n·eps.
    """
    s = np.sort(np.asarray(sigma, dtype=float))[::-1]
    n = s.size
    if rank is None:
        rank = numerical_rank(s, (n, n))
    if m < 1:
        raise PincalError(f"number of poses m must be >= 1; got {m}")
    if rank < n or n == 0:
        zero = 0.0
        return ObservabilityIndices(zero, zero, zero, zero, zero, zero, s, rank, m)
    s1, sL = float(s[0]), float(s[-1])
    o1 = float(np.exp(np.mean(np.log(s))) / np.sqrt(m))
    return ObservabilityIndices(
        O1=o1,
        O2=sL / s1,
        O3=sL,
        O4=sL * sL / s1,
        O5=float(1.0 / np.sum(1.0 / s)),
        a_optimality=float(1.0 / np.sum(s**-2)),
        singular_values=s,
        rank=rank,
        m=m,
    )


def observability(J: ArrayLike, m: int | None = None) -> ObservabilityIndices:
    """Observability indices O1..O5 and A-optimality of an identification Jacobian.

    Args:
        J: scaled identification Jacobian, stacked (rows, n) or blocks (m, k, n).
        m: number of poses. Default: ``J.shape[0]`` for blocks; for a 2-D J every
            row counts as its own pose (m = rows), so pass m explicitly when a
            stacked Jacobian has several rows per pose.

    Returns:
        The indices. L = n: all n singular values count. If J is rank-deficient
        (rank < n, which includes rows < n), σL = 0 and every index that contains
        σL — O1 (product), O2, O3, O4, O5 and A (sums of 1/σi) — is reported as 0.
    """
    arr_in = np.asarray(J, dtype=float)
    if m is None:
        m = arr_in.shape[0] if arr_in.ndim >= 2 else 1
    arr = _as_stacked(arr_in)
    rows, n = arr.shape
    s = np.linalg.svd(arr, compute_uv=False)
    if s.size < n:
        s = np.concatenate([s, np.zeros(n - s.size)])
    return indices_from_singular_values(s, int(m), numerical_rank(s, (rows, n)))


# ----------------------------------------------------------------------------- scaling


@dataclass(frozen=True, eq=False)
class JacobianScaling:
    """A scaled Jacobian and the factors that undo the scaling.

    ``J = row_scale[..., None] * J_original * col_scale`` (broadcast over the last
    axis), so for the scaled unknowns x_s: physical parameters x = col_scale · x_s,
    scaled residual rows r_s = row_scale · r.

    Attributes:
        J: scaled Jacobian, same shape as the input.
        row_scale: factor of each row, shape ``J.shape[:-1]``.
        col_scale: factor of each parameter column, shape (n,).
    """

    J: NDArray[np.float64]
    row_scale: NDArray[np.float64]
    col_scale: NDArray[np.float64]
    description: str = ""

    def params_to_physical(self, x_scaled: ArrayLike) -> NDArray[np.float64]:
        """Scaled parameter vector (n,) → physical units (SI)."""
        return np.asarray(x_scaled, dtype=float) * self.col_scale

    def params_to_scaled(self, x: ArrayLike) -> NDArray[np.float64]:
        """Physical parameter vector (n,) → scaled unknowns."""
        return np.asarray(x, dtype=float) / self.col_scale

    def covariance_to_physical(self, cov_scaled: ArrayLike) -> NDArray[np.float64]:
        """Covariance (n, n) of the scaled unknowns → covariance in SI units."""
        c = self.col_scale
        return np.asarray(cov_scaled, dtype=float) * np.outer(c, c)

    def scale_residuals(self, r: ArrayLike) -> NDArray[np.float64]:
        """Residuals with shape ``J.shape[:-1]`` (SI) → scaled residual rows."""
        return np.asarray(r, dtype=float) * self.row_scale


def dimensionless_rows(J_pose_blocks: ArrayLike, K: float) -> JacobianScaling:
    """Make pose-error rows commensurable with a characteristic length K (seed 000).

    Seed 000 splits the single-pose error model dT = J·de (eq. 16) into the
    position-error transfer matrix Jp (the first 3 rows of J, position error
    [m]) and the orientation-error transfer matrix Jθ (the last 3 rows,
    orientation error [rad]); for m poses Jpm ∈ R^(3m×n) and Jθm ∈ R^(3m×n)
    make up Jz. Because the position entries are much larger than the
    orientation entries, Jz is made dimensionless (eq. 17) with a characteristic
    length K before the observability indices are computed; the result is Jzg
    (their Stewart platform: K = 600 mm = 0.6 m; the text of eq. 17 itself is
    lost in the source). Here

        Jzg = [ Jpm / K ;  Jθm ],

    i.e. each position row is divided by K and each orientation row kept, so
    both row blocks have the same unit (1/m for length parameters; combine with
    :func:`scale_columns` for fully dimensionless entries). Multiplying the
    orientation rows by K instead gives K·Jzg: every index is then multiplied
    by K (O4 too, O2 unchanged) and any pose selection is identical.

    Args:
        J_pose_blocks: Jacobian blocks (m, 6, n), or stacked (6m, n), rows per pose
            ordered (x, y, z, rx, ry, rz) as in log6 (linear first).
        K: characteristic length [m], > 0.

    Returns:
        The scaled Jacobian (same shape as the input) with row factors 1/K for
        position rows and 1 for orientation rows, and unit column factors.
    """
    arr = np.asarray(J_pose_blocks, dtype=float)
    if not np.isfinite(K) or K <= 0.0:
        raise PincalError(f"characteristic length K must be a positive length [m]; got {K}")
    if arr.ndim == 2 and arr.shape[0] % 6 == 0:
        blocks = arr.reshape(-1, 6, arr.shape[1])
    elif arr.ndim == 3 and arr.shape[1] == 6:
        blocks = arr
    else:
        raise PincalError(
            "J_pose_blocks must have shape (m, 6, n) or (6m, n) with rows "
            f"(x, y, z, rx, ry, rz) per pose; got {arr.shape}"
        )
    factors = np.array([1.0 / K] * 3 + [1.0] * 3)
    row_scale = np.broadcast_to(factors, blocks.shape[:-1]).copy()
    scaled = blocks * row_scale[..., None]
    return JacobianScaling(
        J=scaled.reshape(arr.shape),
        row_scale=row_scale.reshape(arr.shape[:-1]),
        col_scale=np.ones(arr.shape[-1]),
    )


def scale_columns(J: ArrayLike, std: ArrayLike | None = None) -> JacobianScaling:
    """Scale parameter columns so that every unknown is of order one.

    Args:
        J: Jacobian (rows, n) or (m, k, n).
        std: a-priori standard deviation of each parameter, shape (n,) [m or rad];
            column j is multiplied by std[j], so the unknowns become δ_j/std_j.
            Default: divide each column by its Euclidean norm (zero columns keep
            factor 1, they stay unidentifiable).

    Returns:
        Scaled Jacobian with ``col_scale`` (n,) such that x = col_scale · x_scaled.
    """
    arr = np.asarray(J, dtype=float)
    stacked = _as_stacked(arr)
    n = stacked.shape[1]
    if std is None:
        norms = np.linalg.norm(stacked, axis=0)
        col = np.where(norms > 0.0, 1.0 / np.where(norms > 0.0, norms, 1.0), 1.0)
    else:
        col = np.asarray(std, dtype=float).reshape(-1)
        if col.shape != (n,) or not np.all(np.isfinite(col)) or np.any(col <= 0.0):
            raise PincalError(
                f"std must be {n} positive finite a-priori parameter deviations; got shape "
                f"{np.shape(std)}"
            )
    return JacobianScaling(J=arr * col, row_scale=np.ones(arr.shape[:-1]), col_scale=col)


def weight_rows(J: ArrayLike, noise_std: ArrayLike) -> JacobianScaling:
    """Weight measurement rows by the inverse noise standard deviation.

    Args:
        J: Jacobian (rows, n) or blocks (m, k, n).
        noise_std: measurement noise σ [m or rad]: a scalar, one value per
            component (k,) for blocks, or one per row (shape ``J.shape[:-1]``).

    Returns:
        Whitened Jacobian (rows divided by σ), ``row_scale = 1/σ``.
    """
    arr = np.asarray(J, dtype=float)
    _as_stacked(arr)
    sigma = np.asarray(noise_std, dtype=float)
    try:
        sigma_rows = np.broadcast_to(sigma, arr.shape[:-1])
    except ValueError:
        raise PincalError(
            f"noise_std of shape {sigma.shape} does not match the rows {arr.shape[:-1]} of J"
        ) from None
    if not np.all(np.isfinite(sigma_rows)) or np.any(sigma_rows <= 0.0):
        raise PincalError("noise_std must be positive and finite")
    row_scale = 1.0 / sigma_rows
    return JacobianScaling(
        J=arr * row_scale[..., None], row_scale=row_scale.copy(), col_scale=np.ones(arr.shape[-1])
    )


ROW_SCALINGS: tuple[str, ...] = ("none", "noise", "K")
"""Row scalings of :class:`DesignScaling`."""
COLUMN_SCALINGS: tuple[str, ...] = ("none", "norm", "std")
"""Column scalings of :class:`DesignScaling`."""


@dataclass(frozen=True)
class DesignScaling:
    """The stated scaling on which observability indices are computed.

    Rows (one per measured component of each pose):

    - ``"none"``: SI units as they are (position rows [m], rotation rows [rad]);
    - ``"noise"``: each row divided by its measurement noise σ (whitening; the
      indices then describe the Cramér–Rao bound of the actual instrument);
    - ``"K"``: seed 000's Jzg — position rows divided by the characteristic
      length ``K`` [m], rotation rows unchanged. ``K = 0.001`` (1 mm) gives the
      seed's *unscaled* Jz, whose entries are in mm/mm and rad/mm.

    Columns (one per parameter):

    - ``"none"``; ``"norm"``: each column divided by its Euclidean norm over the
      whole candidate set (so every design is scaled alike); ``"std"``: each
      column multiplied by the parameter's a-priori standard deviation.

    Column scaling changes neither the selection by O1 (it multiplies det JᵀJ by
    a constant) nor the CRB in physical units; it does change O2–O5 and A.

    Attributes:
        rows: one of :data:`ROW_SCALINGS`.
        K: characteristic length [m] for ``rows="K"``.
        position_std: position noise σ [m] for ``rows="noise"``.
        orientation_std: orientation noise σ [rad] for ``rows="noise"``.
        columns: one of :data:`COLUMN_SCALINGS`.
        column_std: a-priori parameter std (n,) [m or rad] for ``columns="std"``.
    """

    rows: str = "noise"
    K: float | None = None
    position_std: float | None = None
    orientation_std: float | None = None
    columns: str = "none"
    column_std: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        if self.rows not in ROW_SCALINGS:
            raise UnknownNameError("row scaling", self.rows, ROW_SCALINGS)
        if self.columns not in COLUMN_SCALINGS:
            raise UnknownNameError("column scaling", self.columns, COLUMN_SCALINGS)
        if self.rows == "K" and (self.K is None or not np.isfinite(self.K) or self.K <= 0):
            raise PincalError(f"row scaling 'K' needs a positive length K [m]; got {self.K}")
        if self.rows == "noise":
            for name in ("position_std", "orientation_std"):
                v = getattr(self, name)
                if v is not None and (not np.isfinite(v) or v <= 0):
                    raise PincalError(f"{name} must be a positive noise std; got {v}")
        if self.columns == "std" and self.column_std is None:
            raise PincalError("column scaling 'std' needs column_std (a-priori parameter std)")

    def describe(self) -> str:
        """The scaling in words, e.g. ``"rows: Jzg, position rows / K (K = 600 mm)"``."""
        if self.rows == "none":
            rows = "rows: unscaled SI (m, rad)"
        elif self.rows == "K":
            rows = f"rows: Jzg, position rows / K (K = {self.K * 1e3:g} mm), rotation rows as is"
        else:
            parts = []
            if self.position_std is not None:
                parts.append(f"position / {self.position_std * 1e3:g} mm")
            if self.orientation_std is not None:
                parts.append(f"rotation / {self.orientation_std * 1e3:g} mrad")
            rows = "rows: whitened by the noise (" + ", ".join(parts) + ")"
        cols = {
            "none": "columns: unscaled",
            "norm": "columns: unit norm over the candidate set",
            "std": "columns: × a-priori parameter std",
        }[self.columns]
        return f"{rows}; {cols}"

    def apply(self, J_blocks: ArrayLike, components: Sequence[str]) -> JacobianScaling:
        """Scale Jacobian blocks (N, k, n) whose k rows are ``components``.

        Args:
            J_blocks: unscaled blocks (N, k, n) (or one block (k, n)).
            components: the k row names, from x y z rx ry rz.

        Returns:
            The scaled blocks with row factors (N, k) and column factors (n,);
            ``description`` is :meth:`describe`.
        """
        arr = np.asarray(J_blocks, dtype=float)
        single = arr.ndim == 2
        blocks = arr[None] if single else arr
        if blocks.ndim != 3 or blocks.shape[1] != len(components):
            raise PincalError(
                f"J_blocks must have shape (N, {len(components)}, n) for components "
                f"{tuple(components)}; got {arr.shape}"
            )
        is_pos = np.array([c in ("x", "y", "z") for c in components])
        if self.rows == "none":
            factors = np.ones(len(components))
        elif self.rows == "K":
            factors = np.where(is_pos, 1.0 / float(self.K), 1.0)
        else:
            need = []
            if np.any(is_pos) and self.position_std is None:
                need.append("position_std")
            if np.any(~is_pos) and self.orientation_std is None:
                need.append("orientation_std")
            if need:
                raise PincalError(f"row scaling 'noise' needs {' and '.join(need)}")
            sp = self.position_std if self.position_std is not None else 1.0
            so = self.orientation_std if self.orientation_std is not None else 1.0
            factors = np.where(is_pos, 1.0 / sp, 1.0 / so)
        row_scale = np.broadcast_to(factors, blocks.shape[:-1]).copy()
        scaled = blocks * row_scale[..., None]
        n = blocks.shape[-1]
        if self.columns == "none":
            col = np.ones(n)
        elif self.columns == "norm":
            norms = np.linalg.norm(scaled.reshape(-1, n), axis=0)
            col = np.where(norms > 0.0, 1.0 / np.where(norms > 0.0, norms, 1.0), 1.0)
        else:
            col = np.asarray(self.column_std, dtype=float).reshape(-1)
            if col.shape != (n,) or not np.all(np.isfinite(col)) or np.any(col <= 0):
                raise PincalError(f"column_std must be {n} positive values; got {col.shape}")
        scaled = scaled * col
        if single:
            scaled, row_scale = scaled[0], row_scale[0]
        return JacobianScaling(scaled, row_scale, col, self.describe())


def characteristic_length(J_blocks: ArrayLike, components: Sequence[str]) -> float:
    """K [m] that balances position and rotation rows: RMS(position rows)/RMS(rotation rows).

    With this K the two row blocks of Jzg have equal RMS entries (the seed's aim:
    "make the elements of Jpm and Jθm of the same order of magnitude").

    Args:
        J_blocks: unscaled blocks (N, k, n) over a candidate set.
        components: the k row names; must include position and rotation rows.
    """
    arr = np.asarray(J_blocks, dtype=float)
    is_pos = np.array([c in ("x", "y", "z") for c in components])
    if arr.ndim != 3 or arr.shape[1] != is_pos.size or is_pos.all() or not is_pos.any():
        raise PincalError(
            "characteristic_length needs blocks (N, k, n) with both position and rotation rows"
        )
    rms_p = float(np.sqrt(np.mean(arr[:, is_pos] ** 2)))
    rms_r = float(np.sqrt(np.mean(arr[:, ~is_pos] ** 2)))
    if rms_r == 0.0:
        raise PincalError("rotation rows are all zero; K is undefined")
    return rms_p / rms_r


# ----------------------------------------------------------------------------- CRB


def crb_covariance(
    J_weighted: ArrayLike,
    *,
    allow_rank_deficient: bool = False,
    names: Sequence[str] | None = None,
) -> NDArray[np.float64]:
    """Cramér–Rao bound (JᵀJ)⁻¹ of a noise-whitened identification Jacobian.

    For unbiased estimation with rows whitened by the measurement noise
    (:func:`weight_rows`), every estimator has Cov ⪰ (JᵀΣ⁻¹J)⁻¹.

    Args:
        J_weighted: whitened Jacobian (rows, n) or (m, k, n).
        allow_rank_deficient: if True a rank-deficient J gives the pseudo-inverse
            (the bound for the estimable combinations only); else it is an error.
        names: parameter names (n,) for the error message.

    Returns:
        Covariance (n, n) in the (scaled) units of the columns of J.

    Raises:
        UnidentifiableError: J has rank < n and ``allow_rank_deficient`` is False.
    """
    arr = _as_stacked(J_weighted, "J_weighted")
    rows, n = arr.shape
    _, s, vt = np.linalg.svd(arr, full_matrices=True)
    s_full = np.concatenate([s, np.zeros(n - s.size)]) if s.size < n else s
    rank = numerical_rank(s_full, (rows, n))
    if rank < n:
        null = vt[rank:]
        involved = np.flatnonzero(np.max(np.abs(null), axis=0) > 1e-8)
        labels = [names[i] for i in involved] if names is not None else [str(i) for i in involved]
        if not allow_rank_deficient:
            raise UnidentifiableError(
                f"Jacobian has rank {rank} < {n} parameters; the unobservable directions involve "
                f"parameters {', '.join(labels)}",
                names=labels,
            )
        _log.warning("CRB of a rank-deficient Jacobian (rank %d < %d): pseudo-inverse", rank, n)
    v = vt[:rank].T
    return (v / s_full[:rank] ** 2) @ v.T


def predicted_std(cov: ArrayLike) -> NDArray[np.float64]:
    """Standard deviations sqrt(diag(cov)), shape (n,)."""
    c = np.asarray(cov, dtype=float)
    if c.ndim != 2 or c.shape[0] != c.shape[1]:
        raise PincalError(f"covariance must be square (n, n); got {c.shape}")
    return np.sqrt(np.clip(np.diag(c), 0.0, None))


def predicted_validation_rms(J_val: ArrayLike, cov: ArrayLike) -> float:
    """Expected RMS of the prediction error over validation rows.

    If the identified parameters have covariance ``cov``, the error they cause
    at validation rows with Jacobian J_val has expected mean square
    tr(J_val · cov · J_valᵀ)/rows; this returns its square root (in the units
    of the rows of J_val).

    Args:
        J_val: validation Jacobian (rows, n) or (m, k, n), unweighted.
        cov: parameter covariance (n, n).
    """
    jv = _as_stacked(J_val, "J_val")
    c = np.asarray(cov, dtype=float)
    if c.shape != (jv.shape[1], jv.shape[1]):
        raise PincalError(f"cov must be ({jv.shape[1]}, {jv.shape[1]}); got {c.shape}")
    mean_square = np.einsum("ij,jk,ik->", jv, c, jv) / jv.shape[0]
    return float(np.sqrt(max(mean_square, 0.0)))

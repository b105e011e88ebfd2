"""Jacobian scalings of the rows and the columns, each written once.

Rows: noise whitening, or seed 000's Jzg with a characteristic length K. Columns: unit
norm, or the a-priori parameter std.

``J_scaled = row_scale[..., None] * J * col_scale``: the row factors come from
:func:`weight_rows` (1/σ) or :func:`dimensionless_rows` (1/K on position rows), the
column factors from :func:`scale_columns`; :class:`DesignScaling` states a choice of
both and applies it through those same functions.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pincal.design._indices import as_stacked
from pincal.errors import PincalError, UnknownNameError
from pincal.model import COMPONENTS

__all__ = [
    "COLUMN_SCALINGS",
    "ROW_SCALINGS",
    "DesignScaling",
    "JacobianScaling",
    "characteristic_length",
    "dimensionless_rows",
    "scale_columns",
    "weight_rows",
]


def position_rows(components: Sequence[str]) -> NDArray[np.bool_]:
    """(k,) True for the position components (x, y, z) among ``components``."""
    return np.array([c in ("x", "y", "z") for c in components], dtype=bool)


def _check_K(K: float | None) -> float:
    if K is None or not np.isfinite(K) or K <= 0.0:
        raise PincalError(f"characteristic length K must be a positive length [m]; got {K}")
    return float(K)


def _k_factors(components: Sequence[str], K: float) -> NDArray[np.float64]:
    """Row factors of Jzg: 1/K on position rows, 1 on rotation rows, shape (k,)."""
    return np.where(position_rows(components), 1.0 / _check_K(K), 1.0)


def _scale_rows(arr: NDArray[np.float64], factors: ArrayLike) -> JacobianScaling:
    """Multiply the rows of J (…, n) by ``factors`` broadcast to ``J.shape[:-1]``."""
    row_scale = np.broadcast_to(np.asarray(factors, dtype=float), arr.shape[:-1]).copy()
    return JacobianScaling(
        J=arr * row_scale[..., None], row_scale=row_scale, col_scale=np.ones(arr.shape[-1])
    )


def _column_factors(stacked: NDArray[np.float64], std: ArrayLike | None) -> NDArray[np.float64]:
    """Column factors (n,): 1/column norm (zero columns 1), or the a-priori std."""
    n = stacked.shape[1]
    if std is None:
        norms = np.linalg.norm(stacked, axis=0)
        return np.where(norms > 0.0, 1.0 / np.where(norms > 0.0, norms, 1.0), 1.0)
    col = np.asarray(std, dtype=float).reshape(-1)
    if col.shape != (n,) or not np.all(np.isfinite(col)) or np.any(col <= 0.0):
        raise PincalError(
            f"std must be {n} positive finite a-priori parameter deviations; got shape "
            f"{np.shape(std)}"
        )
    return col


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
    _check_K(K)
    if arr.ndim == 2 and arr.shape[0] % 6 == 0:
        blocks = arr.reshape(-1, 6, arr.shape[1])
    elif arr.ndim == 3 and arr.shape[1] == 6:
        blocks = arr
    else:
        raise PincalError(
            "J_pose_blocks must have shape (m, 6, n) or (6m, n) with rows "
            f"(x, y, z, rx, ry, rz) per pose; got {arr.shape}"
        )
    scaled = _scale_rows(blocks, _k_factors(COMPONENTS, K))
    return JacobianScaling(
        J=scaled.J.reshape(arr.shape),
        row_scale=scaled.row_scale.reshape(arr.shape[:-1]),
        col_scale=scaled.col_scale,
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
    col = _column_factors(as_stacked(arr), std)
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
    as_stacked(arr)
    sigma = np.asarray(noise_std, dtype=float)
    try:
        sigma_rows = np.broadcast_to(sigma, arr.shape[:-1])
    except ValueError:
        raise PincalError(
            f"noise_std of shape {sigma.shape} does not match the rows {arr.shape[:-1]} of J"
        ) from None
    if not np.all(np.isfinite(sigma_rows)) or np.any(sigma_rows <= 0.0):
        raise PincalError("noise_std must be positive and finite")
    return _scale_rows(arr, 1.0 / sigma_rows)


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
            K_mm = float(self.K or 0.0) * 1e3
            rows = f"rows: Jzg, position rows / K (K = {K_mm:g} mm), rotation rows as is"
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
        is_pos = position_rows(components)
        if self.rows == "none":
            factors = np.ones(len(components))
        elif self.rows == "K":
            factors = _k_factors(components, float(self.K))  # type: ignore[arg-type]
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
        rows = _scale_rows(blocks, factors)
        if self.columns == "none":
            cols = scale_columns(rows.J, np.ones(blocks.shape[-1]))
        elif self.columns == "norm":
            cols = scale_columns(rows.J)
        else:
            cols = scale_columns(rows.J, self.column_std)
        scaled, row_scale = cols.J, rows.row_scale
        if single:
            scaled, row_scale = scaled[0], row_scale[0]
        return JacobianScaling(scaled, row_scale, cols.col_scale, self.describe())


def characteristic_length(J_blocks: ArrayLike, components: Sequence[str]) -> float:
    """K [m] that balances position and rotation rows: RMS(position rows)/RMS(rotation rows).

    With this K the two row blocks of Jzg have equal RMS entries (the seed's aim:
    "make the elements of Jpm and Jθm of the same order of magnitude").

    Args:
        J_blocks: unscaled blocks (N, k, n) over a candidate set.
        components: the k row names; must include position and rotation rows.
    """
    arr = np.asarray(J_blocks, dtype=float)
    is_pos = position_rows(components)
    if arr.ndim != 3 or arr.shape[1] != is_pos.size or is_pos.all() or not is_pos.any():
        raise PincalError(
            "characteristic_length needs blocks (N, k, n) with both position and rotation rows"
        )
    rms_p = float(np.sqrt(np.mean(arr[:, is_pos] ** 2)))
    rms_r = float(np.sqrt(np.mean(arr[:, ~is_pos] ** 2)))
    if rms_r == 0.0:
        raise PincalError("rotation rows are all zero; K is undefined")
    return rms_p / rms_r

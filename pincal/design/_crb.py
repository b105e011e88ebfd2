"""Cramér–Rao reports: accuracy predicted before measuring, efficiency after.

For measurements with independent Gaussian noise (position σp, orientation σθ)
every unbiased estimator of the parameters has covariance
``Cov ⪰ F⁻¹``, ``F = JᵀΣ⁻¹J`` (Fisher information of the stacked
identification Jacobian J of the measurement poses). Before any measurement
this gives

- the predicted standard deviation of every parameter, sqrt(diag F⁻¹);
- the predicted validation error: a parameter error δx with covariance F⁻¹
  moves the measured frame at a validation pose by J_v δx, so the expected
  mean square position error over validation poses is
  tr(J_{v,p} F⁻¹ J_{v,p}ᵀ)/m_v (and likewise for orientation).

After identification (e.g. Monte-Carlo repetitions of a simulation), the
*efficiency* compares the achieved parameter error with the bound. Three forms:

- whitened (Mahalanobis, unit-free): η_w = n / E[(x̂ − x)ᵀ F (x̂ − x)], n the rank
  of F⁻¹; every parameter counts in units of its own bound, so lengths and angles
  never add;
- per unit class u ("m", "rad"): η_u = tr(F⁻¹_uu) / E‖x̂_u − x_u‖²;
- trace form η = tr(F⁻¹) / E‖x̂ − x‖², defined only when all parameters share one
  unit (it would add m² and rad² otherwise).

Each is ≈ 1 for an efficient estimator (Gauss–Newton at small noise) and < 1 when
the estimator wastes information or is biased.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from pincal.design._bounds import crb_covariance
from pincal.design._scaling import weight_rows
from pincal.errors import PincalError
from pincal.measure import NoiseModel
from pincal.model import COMPONENTS, Mechanism, ParameterSet
from pincal.sensitivity import identification_jacobian, jacobian_rank

__all__ = [
    "CramerRaoReport",
    "Efficiency",
    "cramer_rao",
    "cramer_rao_from_jacobian",
    "efficiency",
]


def _split(components: Sequence[str]) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
    is_pos = np.array([c in ("x", "y", "z") for c in components])
    return is_pos, ~is_pos


@dataclass(frozen=True, eq=False)
class CramerRaoReport:
    """What a pose set can achieve at best, before measuring.

    Attributes:
        names: parameter names (n,); units: their units ("m" or "rad").
        covariance: Cramér–Rao bound F⁻¹ (n, n) [SI].
        std: predicted standard deviations sqrt(diag F⁻¹) (n,) [m or rad].
        validation_position_rms: predicted RMS over validation poses of the
            position-error norm [m] (NaN if position is not measured or no
            validation poses were given).
        validation_orientation_rms: same for the orientation-error angle [rad].
        m: number of measurement poses; rank: rank of the whitened Jacobian.
    """

    names: tuple[str, ...]
    units: tuple[str, ...]
    covariance: NDArray[np.float64]
    std: NDArray[np.float64]
    validation_position_rms: float
    validation_orientation_rms: float
    m: int
    rank: int

    @property
    def rms_std(self) -> float:
        """sqrt(tr(F⁻¹)/n): the predicted RMS parameter error [SI].

        It adds m² and rad² when the set mixes lengths and angles: a design criterion
        (comparing pose sets of one parameter set), never a figure to print; see
        :meth:`std_by_unit`.
        """
        return float(np.sqrt(np.mean(self.std**2)))

    def std_by_unit(self) -> dict[str, dict[str, float | int | str]]:
        """The predicted σ summarised per unit class, never mixed in one figure.

        Returns:
            ``{"lengths": {...}, "angles": {...}}`` for the classes present, each
            ``{"unit": "mm" | "mrad", "count": k, "rms": sqrt(mean σ²), "max": max σ}``
            (lengths in mm, angles in mrad); parameters of another unit are not in it.
        """
        out: dict[str, dict[str, float | int | str]] = {}
        for unit, kind, shown in (("m", "lengths", "mm"), ("rad", "angles", "mrad")):
            s = self.std[np.asarray(self.units) == unit] * 1e3
            if s.size:
                out[kind] = {"unit": shown, "count": int(s.size), "rms": _rms(s),
                             "max": float(s.max())}  # fmt: skip
        return out

    def summary(self) -> str:
        """Two lines: predicted parameter and validation accuracy (mm, mrad).

        The parameter σ are summarised per unit class (lengths in mm, angles in mrad,
        any other unit in SI), never mixed in one figure.
        """
        parts = [f"{kind} {c['rms']:.4g} {c['unit']} (max {c['max']:.4g})"
                 for kind, c in self.std_by_unit().items()]  # fmt: skip
        other = [(n, u, v) for n, u, v in zip(self.names, self.units, self.std, strict=True)
                 if u not in ("m", "rad")]  # fmt: skip
        if other:
            n, u, v = max(other, key=lambda t: t[2])
            parts.append(f"{len(other)} other terms (largest {n}: {v:.3g} {u})")
        if not parts:  # no units given: SI, as it is
            parts.append(f"{_rms(self.std):.4g} (SI, max {self.std.max():.4g})")
        lines = [f"Cramér–Rao bound for {self.m} poses: RMS parameter std " + "; ".join(parts)]
        if np.isfinite(self.validation_position_rms) or np.isfinite(
            self.validation_orientation_rms
        ):
            lines.append(
                f"predicted validation error: position RMS {self.validation_position_rms * 1e3:.4g}"
                f" mm, orientation RMS {self.validation_orientation_rms * 1e3:.4g} mrad"
            )
        return "\n".join(lines)


def _rms(v: NDArray[np.float64]) -> float:
    return float(np.sqrt(np.mean(v**2)))


def cramer_rao_from_jacobian(
    J_blocks: ArrayLike,
    components: Sequence[str],
    noise: NoiseModel,
    J_validation: ArrayLike | None = None,
    names: Sequence[str] | None = None,
    units: Sequence[str] | None = None,
) -> CramerRaoReport:
    """Cramér–Rao report from Jacobian blocks.

    Args:
        J_blocks: unscaled identification Jacobian of the measurement poses
            (m, k, n) [SI], rows = ``components``.
        components: the k measured components.
        noise: measurement noise (position [mm], orientation [mrad]), all > 0
            for the measured components.
        J_validation: unscaled Jacobian blocks (m_v, 6, n) of validation poses
            with all six components (x y z rx ry rz), or None.
        names: parameter names (n,) (default "p0", "p1", ...).
        units: parameter units (n,) (default "m" for every parameter).

    Raises:
        UnidentifiableError: the poses do not determine every parameter.
    """
    J = np.asarray(J_blocks, dtype=float)
    if J.ndim != 3 or J.shape[1] != len(components):
        raise PincalError(
            f"J_blocks must have shape (m, {len(components)}, n); got {np.shape(J_blocks)}"
        )
    n = J.shape[2]
    names = tuple(names) if names is not None else tuple(f"p{i}" for i in range(n))
    units = tuple(units) if units is not None else ("m",) * n
    sigma = noise.std(tuple(components))
    if np.any(sigma <= 0):
        raise PincalError(
            f"the noise model must give a positive std for every measured component; "
            f"got {noise} for components {tuple(components)}"
        )
    Jw = weight_rows(J, sigma).J
    cov = crb_covariance(Jw, names=names)
    rank = jacobian_rank(Jw.reshape(-1, n))
    pos_rms = rot_rms = float("nan")
    if J_validation is not None:
        Jv = np.asarray(J_validation, dtype=float)
        if Jv.ndim != 3 or Jv.shape[1:] != (6, n):
            raise PincalError(f"J_validation must have shape (m_v, 6, {n}); got {Jv.shape}")
        is_pos, is_rot = _split(COMPONENTS)
        # E‖J_i δx‖² = tr(J_i C J_iᵀ), averaged over the validation poses
        per_row = np.einsum("vij,jk,vik->vi", Jv, cov, Jv)
        pos_rms = float(np.sqrt(np.mean(per_row[:, is_pos].sum(axis=1))))
        rot_rms = float(np.sqrt(np.mean(per_row[:, is_rot].sum(axis=1))))
    return CramerRaoReport(
        names,
        units,
        cov,
        np.sqrt(np.clip(np.diag(cov), 0, None)),
        pos_rms,
        rot_rms,
        J.shape[0],
        rank,
    )


def cramer_rao(
    mech: Mechanism,
    params: ParameterSet,
    q_act_rows: ArrayLike,
    noise: NoiseModel,
    validation_q_act: ArrayLike | None = None,
) -> CramerRaoReport:
    """Predicted accuracy of measuring ``mech`` at actuator rows (m, n_act).

    Args:
        mech: nominal mechanism.
        params: the n parameters to identify.
        q_act_rows: measurement poses (m, n_act) [m, rad].
        noise: measurement noise model (mm, mrad).
        validation_q_act: validation poses (m_v, n_act) for the predicted
            validation error, or None.
    """
    comps = tuple(mech.measured_components)
    rows = np.atleast_2d(np.asarray(q_act_rows, dtype=float))
    J = identification_jacobian(mech, params, rows).reshape(rows.shape[0], len(comps), len(params))
    Jv = None
    if validation_q_act is not None:
        qv = np.atleast_2d(np.asarray(validation_q_act, dtype=float))
        Jv = identification_jacobian(mech, params, qv, components=COMPONENTS).reshape(
            qv.shape[0], 6, len(params)
        )
    return cramer_rao_from_jacobian(J, comps, noise, Jv, params.names, params.units)


@dataclass(frozen=True, eq=False)
class Efficiency:
    """Achieved accuracy of repeated identifications against the Cramér–Rao bound.

    Attributes:
        mse: mean squared error per parameter over the repetitions (n,) [SI²].
        bound: Cramér–Rao variance per parameter diag(F⁻¹) (n,) [SI²].
        efficiency: trace form η = tr(F⁻¹) / mean ‖x̂ − x‖² (≈ 1: efficient); NaN
            when ``units`` mix lengths and angles (use ``whitened`` or ``by_unit``).
        efficiency_se: Monte-Carlo standard error of η (delta method), NaN likewise.
        repetitions: number of repetitions R.
        whitened: unit-free η_w = rank / mean (x̂ − x)ᵀ F (x̂ − x), F = (F⁻¹)⁺.
        whitened_se: its Monte-Carlo standard error (delta method).
        by_unit: unit → (η_u, standard error), the trace form within one unit class.
        units: the parameters' units (n,) ("m" for all when not given).
    """

    mse: NDArray[np.float64]
    bound: NDArray[np.float64]
    efficiency: float
    efficiency_se: float
    repetitions: int
    whitened: float = float("nan")
    whitened_se: float = float("nan")
    by_unit: dict[str, tuple[float, float]] = field(default_factory=dict)
    units: tuple[str, ...] = ()

    @property
    def rms_error(self) -> float:
        """sqrt(mean over parameters of the MSE) (mixed units if any rad)."""
        return float(np.sqrt(np.mean(self.mse)))

    @property
    def rms_bound(self) -> float:
        """sqrt(tr(F⁻¹)/n) (mixed units if any rad)."""
        return float(np.sqrt(np.mean(self.bound)))


def _ratio_of_mean(numerator: float, samples: NDArray[np.float64]) -> tuple[float, float]:
    """Ratio numerator / mean(samples) and its delta-method standard error."""
    R = samples.size
    mean = float(np.mean(samples))
    if mean <= 0:
        return float("inf"), float("nan")
    eta = numerator / mean
    se = eta * float(np.std(samples, ddof=1)) / (mean * np.sqrt(R)) if R > 1 else float("nan")
    return eta, se


def efficiency(
    errors: ArrayLike, covariance_bound: ArrayLike, units: Sequence[str] | None = None
) -> Efficiency:
    """Estimator efficiency from Monte-Carlo parameter errors.

    Args:
        errors: identified minus true values (R, n) [SI], one row per repetition.
        covariance_bound: Cramér–Rao bound (n, n) [SI], symmetric positive
            semi-definite.
        units: the parameters' units (n,), e.g. ``ParameterSet.units``; default all "m".

    Returns:
        Efficiency with the whitened, per-unit and (single-unit only) trace forms.

    Raises:
        PincalError: shapes do not match.
    """
    e = np.atleast_2d(np.asarray(errors, dtype=float))
    C = np.asarray(covariance_bound, dtype=float)
    n = e.shape[1]
    if C.shape != (n, n):
        raise PincalError(f"covariance_bound must be ({n}, {n}); got {C.shape}")
    units = tuple(units) if units is not None else ("m",) * n
    if len(units) != n:
        raise PincalError(
            f"units must name the unit of each of the {n} parameters; got {len(units)} "
            f"(pass ParameterSet.units)"
        )
    R = e.shape[0]
    u = np.array(units)
    by_unit = {
        str(k): _ratio_of_mean(
            float(np.trace(C[np.ix_(u == k, u == k)])), np.sum(e[:, u == k] ** 2, 1)
        )
        for k in dict.fromkeys(units)
    }
    if len(by_unit) == 1:
        eta, se = next(iter(by_unit.values()))
    else:
        eta = se = float("nan")
    # whitening on the range of C, after scaling to the correlation matrix so that a
    # change of units (a diagonal scaling) cannot change the result:
    # C = D R D, R = V Λ Vᵀ, z = Λ^(-1/2) Vᵀ D⁻¹ e, E‖z‖² = rank for an efficient estimator
    d = np.sqrt(np.clip(np.diag(C), 0.0, None))
    d[d == 0] = 1.0
    lam, V = np.linalg.eigh(0.5 * (C + C.T) / np.outer(d, d))
    keep = lam > max(lam.max(), 0.0) * n * np.finfo(float).eps
    z = ((e / d) @ V[:, keep]) / np.sqrt(lam[keep])
    w, w_se = _ratio_of_mean(float(keep.sum()), np.sum(z**2, axis=1))
    return Efficiency(np.mean(e**2, axis=0), np.diag(C).copy(), eta, se, R, w, w_se, by_unit, units)

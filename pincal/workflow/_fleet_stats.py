"""Out-of-family units of a fleet, judged with each unit's own covariance.

Unit ``u``'s estimate ``x_u`` (its identified parameters, covariance ``C_u``) is
modelled as the fleet's centre ``c`` plus a production deviation (independent per
parameter, variance ``τ_j²``) plus its estimation error (``C_u``). Under that model

    D_u = (x_u − c)ᵀ (C_u + diag τ²)⁻¹ (x_u − c)  ~  χ²(p)

with p the parameters every unit identified. The production spread τ is estimated by
maximum likelihood under that model (the centre by generalised least squares given τ):
the combinations of parameters a unit determines well constrain τ as the individual
parameters do. The estimate is robust, so faulty units do not hide themselves
(a trimmed likelihood, as the minimum covariance determinant does it): it starts from
the 3/4 of the units nearest the per-parameter medians, refits on the 3/4 nearest under
the fit until the set is stable, then refits once on every unit not rejected at
p < 0.001 (efficiency). A unit is out of family when its p-value is below ``alpha / M`` (Bonferroni
over the M units): the chance that one or more in-family units of the fleet is flagged
is at most ``alpha`` (default 1 %) — as far as the model above holds (independent
Gaussian spread per parameter, linearised estimation errors) and the fleet is large
enough for its own centre and τ to be the family's. On fewer than 50 units they are not
(τ fitted to the units it judges comes out small): fault-free fleets drawn from the fitted
family (its centre and τ, each unit's own C_u) and put through the same estimate give the
smallest p-value such a fleet reaches; its ``alpha`` quantile, when below ``alpha / M``,
is the limit. Measured on fault-free fleets of the model, 30 parameters
(``scripts/studies/fleet_small.py``): with ``alpha / M`` alone 85 % of fleets of 4 units,
70 % of 10, 55 % of 20 and 5 % of 40 flagged a unit (20 fleets each).

What the test can see: an error δ of parameter j alone moves D_u by the noncentrality
λ = δ² [S_u⁻¹]_jj (S_u = C_u + diag τ²: the correlations included, so a parameter
the poses confuse with others needs a large δ), and is flagged with probability
P(χ²(p, λ) > threshold). The smallest δ flagged with probability
:data:`DETECTION_POWER` is stated per parameter (the median over the units): an error
below it, however real, the fleet's own data do not tell from the family.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from pincal.errors import ParameterError

__all__ = [
    "DETECTION_POWER",
    "FleetStatistics",
    "UnitEstimate",
    "UnitVerdict",
    "detectable_errors",
    "fleet_statistics",
]

#: per-unit p-value below which a unit is left out of the second (efficient) estimate
FIRST_LOOK_P = 1e-3
#: fleets smaller than this get their limit calibrated by fault-free fleets (module doc)
CALIBRATE_BELOW = 50
#: fault-free fleets drawn to calibrate a small fleet's limit
CALIBRATION_FLEETS = 200
#: the detection probability the ``detectable`` errors are stated at
DETECTION_POWER = 0.95


@dataclass(frozen=True)
class UnitEstimate:
    """One unit's calibration as the fleet test reads it.

    Attributes:
        id: the unit's id.
        names: (k,) its identified parameter names.
        values: (k,) their values [m, rad].
        covariance: (k, k) their covariance [SI].
    """

    id: str
    names: tuple[str, ...]
    values: np.ndarray
    covariance: np.ndarray


@dataclass(frozen=True)
class UnitVerdict:
    """A unit's distance to the fleet.

    Attributes:
        id: the unit's id.
        distance: D_u, the squared Mahalanobis distance (χ²(dof) in family).
        dof: p, the parameters compared.
        p_value: P(χ²(dof) ≥ D_u).
        out_of_family: p_value < alpha / M.
        largest: up to 3 ``(name, z)``: the parameters furthest from the centre in σ of
            ``C_u,jj + τ_j²`` (signed).
    """

    id: str
    distance: float
    dof: int
    p_value: float
    out_of_family: bool
    largest: tuple[tuple[str, float], ...]


@dataclass(frozen=True)
class FleetStatistics:
    """The fleet's centre, spread and each unit's verdict.

    Attributes:
        names: (p,) the parameters compared (identified in every unit).
        centre: (p,) robust centre [m, rad].
        production_std: (p,) τ, the unit-to-unit spread beyond estimation error [m, rad].
        estimate_std: (p,) median over units of each parameter's own σ [m, rad].
        alpha: fleet-wise false-alarm rate; per-unit threshold alpha / M.
        threshold: the χ²(p) distance at ``limit``.
        units: the verdicts, in the order given.
        limit: the per-unit p-value below which a unit is out of family: alpha / M, or
            for a fleet of fewer than :data:`CALIBRATE_BELOW` units the smaller limit
            fault-free fleets like it reach with chance alpha.
        detectable: (p,) per parameter, the smallest error of it alone that the test
            flags with probability :data:`DETECTION_POWER` (median over the units)
            [m, rad] (module doc); empty when not computed.
    """

    names: tuple[str, ...]
    centre: np.ndarray
    production_std: np.ndarray
    estimate_std: np.ndarray
    alpha: float
    threshold: float
    units: tuple[UnitVerdict, ...]
    limit: float = 0.0
    detectable: np.ndarray = field(default_factory=lambda: np.zeros(0))


def detectable_errors(covs: np.ndarray, tau2: np.ndarray, threshold: float) -> np.ndarray:
    """(p,) the smallest single-parameter errors flagged with :data:`DETECTION_POWER`.

    Args:
        covs: (M, p, p) the units' covariances [SI].
        tau2: (p,) the production variances τ² [SI].
        threshold: the χ²(p) distance beyond which a unit is out of family.

    Returns:
        Per parameter, the median over the units of √(λ / [S_u⁻¹]_jj) [m, rad], λ the
        noncentrality at which P(χ²(p, λ) > threshold) = :data:`DETECTION_POWER`.
    """
    from scipy import optimize, stats

    p = covs.shape[1]
    lam = optimize.brentq(
        lambda x: stats.ncx2.sf(threshold, p, x) - DETECTION_POWER, 1e-9, 100.0 * (threshold + p)
    )
    S_inv = np.linalg.pinv(covs + np.diag(tau2)[None])
    diag = np.diagonal(S_inv, axis1=1, axis2=2)
    return np.median(np.sqrt(lam / np.maximum(diag, 1e-300)), axis=0)


def _centre(X: np.ndarray, covs: np.ndarray, tau2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """GLS centre of the units given τ², and each unit's (C_u + diag τ²)⁻¹."""
    inv = np.linalg.inv(covs + np.diag(tau2)[None])
    centre = np.linalg.solve(inv.sum(axis=0), np.einsum("uij,uj->i", inv, X))
    return centre, inv


def _spread(X: np.ndarray, covs: np.ndarray, keep: np.ndarray) -> np.ndarray:
    """τ² by maximum likelihood over the units ``keep`` (x_u ~ N(c, C_u + diag τ²)).

    The well-determined combinations of parameters constrain τ as much as the
    parameters themselves do; the start is the marginal median/MAD moment estimate.
    """
    Xk, Ck = X[keep], covs[keep]
    var = np.diagonal(Ck, axis1=1, axis2=2)
    mad = 1.4826 * np.median(np.abs(Xk - np.median(Xk, axis=0)), axis=0)
    scale = np.maximum(np.median(var, axis=0), 1e-30)
    floor = 1e-8 * scale  # τ² below 1e-8 of the estimates' variance is no spread
    start = np.log(np.maximum(mad**2 - np.median(var, axis=0), 0.01 * scale))

    def nll(theta: np.ndarray) -> tuple[float, np.ndarray]:
        tau2 = np.exp(theta)
        centre, inv = _centre(Xk, Ck, tau2)
        r = Xk - centre
        w = np.einsum("uij,uj->ui", inv, r)
        _, logdet = np.linalg.slogdet(inv)
        value = float(-logdet.sum() + np.einsum("ui,ui->", r, w))
        grad = (np.diagonal(inv, axis1=1, axis2=2) - w**2).sum(axis=0) * tau2
        return value, grad

    bounds = [(float(np.log(f)), float(np.log(1e4 * s))) for f, s in zip(floor, scale, strict=True)]
    start = np.clip(start, [b[0] for b in bounds], [b[1] for b in bounds])
    from scipy import optimize  # here: scipy.optimize and .stats cost ~0.5 s to import

    fit = optimize.minimize(nll, start, jac=True, method="L-BFGS-B", bounds=bounds)
    tau2 = np.exp(fit.x)
    return np.where(tau2 <= 1.01 * floor, 0.0, tau2)


def _nearest(distance: np.ndarray, h: int) -> np.ndarray:
    """(M,) mask of the ``h`` smallest distances (ties by unit order)."""
    mask = np.zeros(distance.size, dtype=bool)
    mask[np.argsort(distance, kind="stable")[:h]] = True
    return mask


def _distances(
    X: np.ndarray, covs: np.ndarray, centre: np.ndarray, tau2: np.ndarray
) -> list[tuple[float, np.ndarray]]:
    """Per unit: (distance² to ``centre`` under C_u + diag τ², (p,) residual over σ)."""
    out = []
    for x, C in zip(X, covs, strict=True):
        S = C + np.diag(tau2)
        r = x - centre
        try:
            d = float(r @ np.linalg.solve(S, r))
        except np.linalg.LinAlgError:
            d = float(r @ np.linalg.pinv(S) @ r)
        out.append((d, r / np.sqrt(np.maximum(np.diag(S), 1e-300))))
    return out


def _fit(
    X: np.ndarray, covs: np.ndarray
) -> tuple[np.ndarray, np.ndarray, list[tuple[float, np.ndarray]], np.ndarray]:
    """Robust centre (p,), τ² (p,), each unit's (distance², z) and χ²(p) p-value (module doc)."""
    M, p = X.shape
    # a robust start: the 3/4 of the units nearest the per-parameter medians (MAD units)
    h = max(3, int(np.ceil(0.75 * M)))
    med = np.median(X, axis=0)
    mad = 1.4826 * np.median(np.abs(X - med), axis=0)
    z0 = ((X - med) / np.maximum(mad, 1e-12 * np.maximum(np.abs(med), 1.0))) ** 2
    keep = _nearest(z0.sum(axis=1), h)
    for _ in range(10):  # concentration steps: refit on the h nearest units until stable
        tau2 = _spread(X, covs, keep)
        centre, _ = _centre(X[keep], covs[keep], tau2)
        now = _nearest(np.array([d for d, _ in _distances(X, covs, centre, tau2)]), h)
        if np.array_equal(now, keep):
            break
        keep = now
    # reweighting: every unit the trimmed fit does not reject at p < 0.001
    from scipy import stats

    first = np.array([stats.chi2.sf(d, p) for d, _ in _distances(X, covs, centre, tau2)])
    if (first >= FIRST_LOOK_P).sum() >= 3:
        keep = first >= FIRST_LOOK_P
        tau2 = _spread(X, covs, keep)
        centre, _ = _centre(X[keep], covs[keep], tau2)
    found = _distances(X, covs, centre, tau2)
    return centre, tau2, found, np.array([stats.chi2.sf(d, p) for d, _ in found])


def _calibrated_limit(
    centre: np.ndarray, tau2: np.ndarray, covs: np.ndarray, alpha: float, seed: int
) -> float:
    """The per-unit p-value a fault-free fleet like this one reaches with chance ``alpha``.

    :data:`CALIBRATION_FLEETS` fleets drawn from the fitted family (centre, τ, each
    unit's own C_u), each put through the whole estimate; the limit is the ``alpha``
    quantile of their smallest p-value.
    """
    rng = np.random.default_rng(seed)
    M, p = covs.shape[:2]
    roots = []
    for C in covs:
        w, V = np.linalg.eigh(C)
        roots.append(V * np.sqrt(np.clip(w, 0.0, None)))
    smallest = []
    for _ in range(CALIBRATION_FLEETS):
        X = centre + np.sqrt(tau2) * rng.standard_normal((M, p))
        X += np.einsum("uij,uj->ui", np.array(roots), rng.standard_normal((M, p)))
        smallest.append(float(_fit(X, covs)[3].min()))
    return float(np.quantile(smallest, alpha))


def fleet_statistics(
    units: Sequence[UnitEstimate], alpha: float = 0.01, seed: int = 0
) -> FleetStatistics:
    """Each unit's distance to the fleet and whether it is out of family (module doc).

    Args:
        units: M ≥ 3 calibrated units (those the gate refused are left out by the caller).
        alpha: fleet-wise false-alarm rate, in (0, 1).
        seed: seed of the fault-free fleets that calibrate a small fleet's limit.

    Returns:
        The :class:`FleetStatistics`.

    Raises:
        ParameterError: fewer than 3 units, alpha outside (0, 1), or no parameter
            identified in every unit.
    """
    if not 0 < alpha < 1:
        raise ParameterError(f"alpha is a false-alarm rate in (0, 1), got {alpha}")
    if len(units) < 3:
        raise ParameterError(
            f"an out-of-family test needs at least 3 calibrated units, got {len(units)}"
        )
    common = [n for n in units[0].names if all(n in u.names for u in units[1:])]
    if not common:
        raise ParameterError("no parameter is identified in every unit: nothing to compare")
    X, covs = [], []
    for u in units:
        idx = [u.names.index(n) for n in common]
        X.append(np.asarray(u.values, dtype=float)[idx])
        covs.append(np.asarray(u.covariance, dtype=float)[np.ix_(idx, idx)])
    X_, covs_ = np.array(X), np.array(covs)
    var = np.diagonal(covs_, axis1=1, axis2=2)
    p, M = len(common), len(units)
    centre, tau2, found, pvals = _fit(X_, covs_)
    from scipy import stats

    limit = alpha / M
    if M < CALIBRATE_BELOW:
        limit = min(limit, _calibrated_limit(centre, tau2, covs_, alpha, seed))
    verdicts = []
    for u, (d, z), pv in zip(units, found, pvals, strict=True):
        top = np.argsort(-np.abs(z))[:3]
        largest = tuple((common[j], float(z[j])) for j in top)
        verdicts.append(UnitVerdict(u.id, d, p, float(pv), bool(pv < limit), largest))
    threshold = float(stats.chi2.isf(limit, p))
    return FleetStatistics(
        tuple(common),
        centre,
        np.sqrt(tau2),
        np.sqrt(np.median(var, axis=0)),
        float(alpha),
        threshold,
        tuple(verdicts),
        limit,
        detectable_errors(covs_, tau2, threshold),
    )

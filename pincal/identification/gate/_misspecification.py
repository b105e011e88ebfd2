"""Does the model fit the data as well as the noise allows? χ² per block and probes.

Two tests of the quality gate that see a wrong *model* (or instrument), not only a
wrong file:

- :func:`chi2_blocks`: with declared noise, the whitened residuals of each block
  (position, orientation) have Σz² ~ χ²(ν_b), ν_b the block's redundancy
  (n_b − tr H_bb). Its upper-tail p-value says how surprising the misfit is.
- :func:`probe_misspecification`: the fit is extended, to first order at the solution,
  by a few nuisance terms that a correct model and an honest instrument do not need —
  a global scale of the measured positions about their centroid (an instrument scale
  or a unit-level error), a gain per actuator (a wrong encoder or lead-screw scale)
  and a linear drift of the measured positions over the pose order (thermal drift) —
  and the reduction of the residual sum of squares is judged by the F-test

      F = (ΔRSS / q) / ((RSS − ΔRSS) / (ν − q)),   F ~ F(q, ν − q) under a correct model,

  which needs no declared noise (it compares the residual with itself). By the
  Frisch–Waugh theorem the coefficient of the nuisance term in the joint linear fit is
  its least-squares size (e.g. the scale in %), and ΔRSS / RSS the share of the residual
  it explains.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from pincal.errors import PincalError
from pincal.identification._distributions import chi2_sf, f_sf
from pincal.identification.gate._coordinate_probe import coordinate_columns, is_trend, trend_size
from pincal.identification.gate._outliers import column_basis
from pincal.identification.gate._probe_floor import detection_floor
from pincal.identification.results import IdentificationResult
from pincal.measure import Measurements
from pincal.model import Mechanism, parameters
from pincal.sensitivity import identification_jacobian

__all__ = [
    "BlockChi2",
    "Probe",
    "chi2_blocks",
    "instrument_chi2",
    "probe_columns",
    "probe_misspecification",
]

_POS = ("x", "y", "z")
_OUTSIDE = 1e-2  # a nuisance column with < 1 % of its norm outside the model is absorbed


@dataclass(frozen=True)
class BlockChi2:
    """χ² of one noise block against its distribution.

    Attributes:
        block: ``position`` or ``orientation``.
        chi2: Σ z² of the block's whitened residuals.
        dof: the block's redundancy ν_b (degrees of freedom).
        p_value: P(χ²(ν_b) ≥ chi2).
    """

    block: str
    chi2: float
    dof: float
    p_value: float

    @property
    def ratio(self) -> float:
        """χ² / ν (the reduced χ² of the block)."""
        return self.chi2 / self.dof if self.dof > 0 else float("nan")


@dataclass(frozen=True)
class Probe:
    """One nuisance term's F-test.

    Attributes:
        name: ``scale``, ``gains``, ``drift`` or ``trend:<coordinate>``.
        dof: number of nuisance columns q (after removing what the model already spans).
        f_stat: the F statistic.
        p_value: P(F(q, ν − q) ≥ f_stat).
        explained: share of the residual sum of squares the term removes, of the blocks
            it acts on (position only for scale and drift; estimated noise scales each
            block's sum to its redundancy, so the share of the total would be diluted).
        size: its size in words (e.g. ``a 1.00 % scale of the measured positions``).
        floor: the smallest error of this kind the probe catches with 90 % power at the
            gate's significance on this design and noise, in the coefficient's unit
            (a scale or gain as a fraction, a drift over the pose order in m, a trend
            in m: positions), NaN when not computed (:mod:`._probe_floor`).
        workspace: the RMS distance of the fitted positions from their centroid [m]
            (NaN when unknown): a drift or trend floor beyond it is not detectable with
            these poses, as a scale or gain floor of 100 % or more.
    """

    name: str
    dof: int
    f_stat: float
    p_value: float
    explained: float
    size: str
    floor: float = float("nan")
    workspace: float = float("nan")

    @property
    def detectable(self) -> bool:
        """False when the floor exceeds the campaign's own scale (see ``workspace``)."""
        if self.name in ("scale", "gains"):
            return self.floor < 1.0
        return not self.floor > self.workspace  # NaN workspace: not judged

    def floor_text(self) -> str:
        """The floor in words (e.g. ``a scale error below 0.02 %``), "" when unknown.

        A floor beyond the campaign's own scale (:attr:`detectable`) is said as not
        detectable with these poses, with the size 90 % detection would need.
        """
        if not math.isfinite(self.floor):
            return ""
        if self.name in ("scale", "gains"):
            what = "a scale error" if self.name == "scale" else "an actuator gain error"
            if not self.detectable:
                return (f"{what} (not detectable with these poses: 90 % detection needs "
                        f"{_figure(self.floor * 100)} %)")  # fmt: skip
            return f"{what} below {_figure(self.floor * 100)} %"
        if self.name == "drift":
            what, where = "a drift", " over the pose order"
        else:
            what, where = "a trend", f" along the {self.name.removeprefix('trend:')}"
        if not self.detectable:
            return (f"{what}{where} (not detectable with these poses: 90 % detection needs "
                    f"{length_text(self.floor)}, more than the {length_text(self.workspace)} "
                    "RMS spread of the positions)")  # fmt: skip
        return f"{what} below {length_text(self.floor)}{where}"

    def describe(self) -> str:
        """One sentence: the effect's size, the share of the residual it explains, its p-value."""
        return (
            f"{self.size} explains {self.explained:.0%} of the residual "
            f"(F-test p = {self.p_value:.2g})"
        )



def _figure(v: float) -> str:
    """``v`` to two significant digits, without an exponent (9.58 → 9.6, 309 → 310)."""
    if v == 0 or not math.isfinite(v):
        return f"{v:g}"
    digits = 1 - math.floor(math.log10(abs(v)))
    digits = 1 - math.floor(math.log10(abs(round(v, digits))))  # 0.9996 → 1.0, not 1.00
    return f"{round(v, digits):.{max(digits, 0)}f}"


def length_text(v: float) -> str:
    """A length [m] in words in a unit that suits it (34 µm, 9.6 mm, 1.2 m)."""
    a = abs(float(_figure(v))) if math.isfinite(v) else math.inf  # the unit of the rounded
    if a < 1e-3:
        return f"{_figure(v * 1e6)} µm"
    if a < 1.0:
        return f"{_figure(v * 1e3)} mm"
    return f"{_figure(v)} m"


def _sf(dist: str, x: float, *df: float) -> float:
    """P(X > x) for the ``chi2`` or ``f`` distribution (degrees of freedom ``df``)."""
    return chi2_sf(x, *df) if dist == "chi2" else f_sf(x, *df)

def chi2_blocks(
    result: IdentificationResult,
    components: tuple[str, ...] | None = None,
    rows: np.ndarray | None = None,
) -> list[BlockChi2]:
    """χ² of each noise block of a fit with declared noise (empty without weights).

    Args:
        result: the identification result (its weighting holds the whitened residuals
            and each block's redundancy).
        components: the k measured components (None: ``x y z [rx ry rz]`` by k).
        rows: pose indices to judge (None: all), e.g. the inliers of a robust fit; the
            redundancy is reduced by the left-out equations.
    """
    w = result.weighting
    if w is None or w.whitened.size == 0:
        return []
    z = np.asarray(w.whitened, dtype=float)
    comps = _components(components, z.shape[1])
    out = []
    for block, names in (("position", _POS), ("orientation", ("rx", "ry", "rz"))):
        cols = [j for j, c in enumerate(comps) if c in names]
        if not cols or block not in w.redundancy:
            continue
        zb = z[:, cols] if rows is None else z[np.asarray(rows, dtype=int)][:, cols]
        dof = float(w.redundancy[block]) - (z.shape[0] - zb.shape[0]) * len(cols)
        if dof < 1.0:
            continue
        c2 = float(np.sum(zb**2))
        out.append(BlockChi2(block, c2, dof, _sf("chi2", c2, dof)))
    return out


def instrument_chi2(result: IdentificationResult) -> list[BlockChi2]:
    """χ² of a scalar-instrument fit (ballbar, sphere, plane, gauge) against its file's σ.

    Its residuals are whitened by the instrument file's ``std``; the redundancy (readings
    minus fitted machine and instrument parameters) is the joint fit's
    ``result.joint.redundancy``. Empty when it is missing or below 1.
    """
    dof = 0.0 if result.joint is None else float(result.joint.redundancy)
    c2 = float(result.reduced_chi2) * dof
    if dof < 1.0 or not math.isfinite(c2):
        return []
    return [BlockChi2("instrument", c2, dof, _sf("chi2", c2, dof))]


def _components(components: tuple[str, ...] | None, k: int) -> tuple[str, ...]:
    if components is not None and len(components) == k:
        return tuple(components)
    return ("x", "y", "z", "rx", "ry", "rz")[:k] if k in (3, 6) else ("x", "y", "z")[:k]


def probe_columns(
    result: IdentificationResult, meas: Measurements
) -> dict[str, np.ndarray]:
    """Raw (m, k, q) derivative of the residuals w.r.t. each probe's nuisance terms.

    ``scale``: the fitted model's positions (measured − residual) about their centroid
    [m per unit scale];
    ``drift``: pose order t ∈ [−½, ½] on each measured position component [m per m];
    ``gains``: −∂pose/∂q_i · q_i per actuator at the calibrated machine [per unit gain]
    (left out when the actuator offsets cannot be built for the mechanism);
    ``trend:<coordinate>``: low-order functions of each pose coordinate (actuator value,
    tool x y z) on every component (:mod:`pincal.identification.gate._coordinate_probe`).
    """
    m, k = len(meas), len(meas.components)
    pos = [j for j, c in enumerate(meas.components) if c in _POS]
    cols: dict[str, np.ndarray] = {}
    model_pos = None  # the fitted model's positions: measured − residual
    raw = np.asarray(result.residuals, dtype=float)
    if raw.shape == (m, k):
        model_pos = np.asarray(meas.positions, dtype=float).copy()
        for j, c in enumerate(meas.components):
            if c in _POS:
                model_pos[:, _POS.index(c)] -= raw[:, j]
    if pos and m > 2:
        # the model's positions, not the measured ones: a measured point the machine
        # barely moves would otherwise offer its own noise — the residual — as a "scale"
        p = np.asarray(meas.positions if model_pos is None else model_pos, dtype=float)
        centred = p - p.mean(axis=0)
        scale = np.zeros((m, k, 1))
        drift = np.zeros((m, k, len(pos)))
        t = np.linspace(-0.5, 0.5, m)
        for n, j in enumerate(pos):
            scale[:, j, 0] = centred[:, _POS.index(meas.components[j])]
            drift[:, j, n] = t
        cols["scale"], cols["drift"] = scale, drift
    cal = result.calibrated_mechanism
    gains = _gain_columns(cal, meas)
    if gains is not None:
        cols["gains"] = gains
    actuators = tuple(cal.actuated)
    cols.update(coordinate_columns(meas, actuators, model_pos))
    return cols


def _gain_columns(mech: Mechanism, meas: Measurements) -> np.ndarray | None:

    try:
        offsets = parameters(mech, [f"{j}.offset" for j in mech.actuated])
        J = identification_jacobian(mech, offsets, meas.q_act, None, meas.components)
    except PincalError:
        return None
    m, k = len(meas), len(meas.components)
    q = np.asarray(meas.q_act, dtype=float)
    if J.shape != (m * k, q.shape[1]):
        return None
    return -J.reshape(m, k, -1) * q[:, None, :]


def probe_misspecification(
    A: np.ndarray,
    z: np.ndarray,
    columns: dict[str, np.ndarray],
    sigma: np.ndarray,
    components: tuple[str, ...] | None = None,
    significance: float | None = None,
    min_share: float = 0.25,
) -> list[Probe]:
    """F-test of each probe's nuisance terms added to the linearised fit.

    Args:
        A: (N, p) whitened Jacobian of the fitted parameters, N = m·k rows.
        z: (N,) whitened residuals at the solution.
        columns: raw (m, k, q) nuisance columns per probe (:func:`probe_columns`).
        sigma: (m, k) σ of each residual [m, rad] (whitens the columns).
        components: the k measured components (names the trend probes' sizes).
        significance: the gate's family-wise significance of the probes (Bonferroni
            over the probes run): with it, each probe's detection floor at 90 % power
            (:func:`pincal.identification.gate._probe_floor.detection_floor`, with ``min_share``
            the share of the residual a probe must explain) — of the position columns
            only for a trend.
        min_share: the share of its blocks' residual a probe must explain to fire.

    Returns:
        One :class:`Probe` per probe that adds at least one direction, in the order given.
    """
    U = column_basis(A)
    zr = z - U @ (U.T @ z)
    rss = float(zr @ zr)
    nu = z.size - U.shape[1]
    probes: list[Probe] = []
    seen: list[tuple[np.ndarray, int, float]] = []  # per probe: its columns, q, ν_t
    if not rss > 0:
        return probes
    comps = _components(components, sigma.shape[1])
    for name, raw in columns.items():
        B0 = (raw / sigma[:, :, None]).reshape(z.size, -1)
        B = B0 - U @ (U.T @ B0)
        # a term the model (nearly) spans is absorbed by it: no test (only rounding is left)
        outside = np.linalg.norm(B, axis=0) > _OUTSIDE * np.linalg.norm(B0, axis=0)
        B = B[:, outside]
        if B.shape[1] == 0:
            continue
        coef, _, rank, _sv = np.linalg.lstsq(B, zr, rcond=1e-6)
        q = int(rank)
        if q == 0 or nu - q < 1:
            continue
        delta = min(float(np.sum((B @ coef) ** 2)), rss)
        f = (delta / q) / max((rss - delta) / (nu - q), 1e-300)
        p = _sf("f", f, q, nu - q)
        touched = np.any(raw != 0, axis=2).ravel()  # the blocks the term acts on
        before = float(np.sum(zr[touched] ** 2))
        after = float(np.sum((zr - B @ coef)[touched] ** 2))
        share = min(max(1.0 - after / before, 0.0), 1.0) if before > 0 else 0.0
        if is_trend(name):
            fitted = (B @ coef).reshape(sigma.shape) * sigma  # the part seen in the residual
            size = trend_size(name, fitted, _components(components, sigma.shape[1]), sigma)
        else:
            size = _size(name, coef)
        probes.append(Probe(name, q, f, p, share, size))
        keep = outside & _position_columns(name, raw, comps)
        nu_t = nu * float(np.mean(touched))  # the touched blocks' share of the redundancy
        seen.append((B0[:, keep] - U @ (U.T @ B0[:, keep]), q, nu_t))
    if significance is None or not probes:
        return probes
    alpha = significance / len(probes)
    reach = _workspace(columns)
    return [
        replace(pr, floor=detection_floor(b, q, nu - q, alpha, min_share, nu_t), workspace=reach)
        for pr, (b, q, nu_t) in zip(probes, seen, strict=True)
    ]


def _workspace(columns: dict[str, np.ndarray]) -> float:
    """RMS distance [m] of the fitted positions from their centroid (the scale column)."""
    scale = columns.get("scale")
    if scale is None or not scale.size:
        return float("nan")
    return float(math.sqrt(np.sum(scale**2) / scale.shape[0]))


def _position_columns(name: str, raw: np.ndarray, comps: tuple[str, ...]) -> np.ndarray:
    """(c,) the columns whose floor is stated: all, or a trend's on position components."""
    if not is_trend(name):
        return np.ones(raw.shape[2], dtype=bool)
    pos = np.array([c in _POS for c in comps])
    return np.any((raw != 0) & pos[None, :, None], axis=(0, 1))


def _size(name: str, coef: np.ndarray) -> str:
    if name == "scale":
        return f"a {coef[0] * 100:.3g} % scale of the measured positions"
    if name == "gains":
        worst = float(np.max(np.abs(coef)))
        return f"actuator gains of up to {worst * 100:.3g} %"
    drift = math.sqrt(float(np.sum(coef**2)))
    return f"a linear drift of {drift * 1e3:.3g} mm over the pose order"

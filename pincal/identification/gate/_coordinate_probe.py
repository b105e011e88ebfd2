"""Residual structure against the pose coordinates: a trend the noise does not have.

A correct model leaves residuals that are noise: they do not grow with an actuator's
stroke or with the tool's position in the workspace. A model error that no named
probe (scale, gains, drift) describes — a bent guide, an encoder's non-linearity, a
tracker's range-dependent error — does. :func:`coordinate_columns` builds, for each
pose coordinate (every actuator value, and the x, y, z of the measured tool position),
low-order functions of it on every measured component: the coordinate normalised to
``t ∈ [−½, ½]`` over its range in the campaign, and ``t² − mean(t²)``. Each coordinate
is one probe of :func:`pincal.identification.gate._misspecification.probe_misspecification`
(F-test on the columns the model does not span; the gate's Bonferroni correction runs
over all probes), named ``trend:<coordinate>`` and sized by :func:`trend_size`: the
largest peak-to-peak change of the fitted trend over the campaign, in mm (positions)
or mrad (orientations).
"""

from __future__ import annotations

import numpy as np

from pincal.measure import Measurements

__all__ = ["PREFIX", "coordinate_columns", "is_trend", "trend_size"]

#: probe names of this module start with it
PREFIX = "trend:"
_POS = ("x", "y", "z")
_MIN_POSES = 8  # fewer poses: no trend test (two columns per component and coordinate)


def is_trend(name: str) -> bool:
    """True for a probe of this module (``trend:<coordinate>``)."""
    return name.startswith(PREFIX)


def _normalised(v: np.ndarray) -> np.ndarray | None:
    """The coordinate mapped onto [−½, ½] over its range, None when it does not vary."""
    lo, hi = float(np.min(v)), float(np.max(v))
    if not hi - lo > 1e-12 * max(1.0, abs(hi), abs(lo)):
        return None
    return (v - lo) / (hi - lo) - 0.5


def coordinate_columns(
    meas: Measurements,
    actuators: tuple[str, ...] | None = None,
    positions: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """Raw (m, k, 2k) columns per pose coordinate: ``t`` and ``t² − mean`` per component.

    Args:
        meas: the fitted measurements (m poses, k components).
        actuators: names of the actuator columns of ``meas.q_act`` (None: ``q0 q1 …``).
        positions: (m, 3) the fitted model's tool positions [m] (None: the measured
            ones). Give them: a measured coordinate carries the noise of the residual it
            is tested against (a tool z that barely varies is then mostly that noise,
            and correlates with it).

    Returns:
        ``{"trend:<coordinate>": (m, k, 2k) array}`` for every coordinate that varies
        (actuators, then the measured tool x, y, z); empty below 8 poses. The columns
        are in the residual's units per unit ``t`` (1 m or 1 rad): a coefficient is the
        trend's size over the coordinate's range.
    """
    m, k = len(meas), len(meas.components)
    if m < _MIN_POSES:
        return {}
    q = np.asarray(meas.q_act, dtype=float).reshape(m, -1)
    names = list(actuators) if actuators is not None and len(actuators) == q.shape[1] else [
        f"q{i}" for i in range(q.shape[1])]  # fmt: skip
    coords: list[tuple[str, np.ndarray]] = [(f"actuator {n}", q[:, i]) for i, n in enumerate(names)]
    p = np.asarray(meas.positions if positions is None else positions, dtype=float)
    for c in meas.components:
        if c in _POS:
            coords.append((f"tool {c}", p[:, _POS.index(c)]))
    out: dict[str, np.ndarray] = {}
    eye = np.eye(k)
    for name, v in coords:
        t = _normalised(v)
        if t is None:
            continue
        t2 = t**2 - float(np.mean(t**2))
        basis = np.stack([t, t2], axis=1)  # (m, 2)
        out[PREFIX + name] = np.einsum("ma,kc->mkca", basis, eye).reshape(m, k, 2 * k)
    return out


def trend_size(
    name: str, fitted: np.ndarray, components: tuple[str, ...], sigma: np.ndarray | None = None
) -> str:
    """In words: the peak-to-peak change of a fitted trend over the campaign.

    Args:
        name: the probe's name (``trend:<coordinate>``).
        fitted: (m, k) the trend's fitted contribution to the raw residuals [m, rad].
        components: the k measured components.
        sigma: (m, k) σ of the residuals [m, rad]: the component named is the one whose
            change is largest against its noise (None: against 1 mm / 1 mrad).
    """
    fitted = np.asarray(fitted, dtype=float)
    span = np.ptp(fitted, axis=0)
    white = span if sigma is None else np.ptp(fitted / sigma, axis=0)
    j = int(np.argmax(white))
    unit = "mm" if components[j] in _POS else "mrad"
    where = name.removeprefix(PREFIX)
    return f"a trend of {span[j] * 1e3:.3g} {unit} in {components[j]} along the {where}"

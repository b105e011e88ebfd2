"""K-fold cross-validation over the poses: held-out error of a fitting procedure.

:func:`kfold` splits m poses into K folds from a seed (a permutation by
``numpy.random.default_rng(seed)``, then K near-equal consecutive parts), so the same
seed gives the same folds on every machine. :func:`cross_validate` fits on K − 1 folds
and predicts the held-out one, for each fold; every pose is held out exactly once.
With several markers per pose (one measurement set each, same rows) a pose's error is
the RMS over its markers. When the first set measures the whole orientation (a 6-D
marker body, a pose file with ``rx ry rz``), each held-out pose's rotation error angle is kept too
(:func:`orientation_errors`). :func:`compare` states whether one procedure beats
another by more than the standard error of the paired difference of their per-pose
squared errors: position errors [m²], or, given each block's noise σ
(:class:`BlockScales`) and orientation measured, the whitened sum
``|Δp|²/σ_p² + θ²/σ_r²`` of each pose (dimensionless; see
:meth:`CrossValidation.squared_errors`). A :class:`CrossValidation` is stored and read
back exactly (:meth:`CrossValidation.to_record`, :meth:`CrossValidation.from_record`),
so the figure a calibration computed is reused rather than refitted.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from pincal.errors import MeasurementError
from pincal.measure import Measurements
from pincal.model import Mechanism

__all__ = [
    "BlockScales",
    "CrossValidation",
    "compare",
    "cross_validate",
    "kfold",
    "orientation_errors",
    "position_errors",
]


def kfold(m: int, k: int, seed: int) -> tuple[np.ndarray, ...]:
    """K folds of pose indices (each sorted), reproducible from ``seed``.

    Raises:
        MeasurementError: K < 2 or more folds than poses.
    """
    if k < 2 or k > m:
        raise MeasurementError(f"cross-validation needs 2 ≤ K ≤ {m} poses, got K = {k}")
    perm = np.random.default_rng(seed).permutation(m)
    return tuple(np.sort(f) for f in np.array_split(perm, k))


def position_errors(mech: Mechanism, meas: Measurements) -> np.ndarray:
    """(m,) distances [m] between predicted and measured positions of the measured frame.

    Over the measured position components only (``x z`` of a machine measuring
    ``x z ry``). The frame is ``meas.frame`` (another marker of the same mechanism).

    Raises:
        MeasurementError: no position component is measured.
    """
    cols = [i for i, c in enumerate("xyz") if c in meas.components]
    if not cols:
        raise MeasurementError("cross-validation compares positions; none is measured")
    qs = mech.configurations(meas.q_act)
    frame = None if meas.frame == mech.measured_frame else meas.frame
    pred = np.array([mech.frame_placement(q, frame).translation for q in qs])
    return np.linalg.norm((pred - meas.positions)[:, cols], axis=1)


def orientation_errors(mech: Mechanism, meas: Measurements) -> np.ndarray:
    """(m,) rotation error angles ‖log3(R_predictedᵀ R_measured)‖ [rad] of the measured frame.

    Raises:
        MeasurementError: no orientation is measured.
    """
    if meas.rotations is None:
        raise MeasurementError("no orientation is measured: no orientation error")
    qs = mech.configurations(meas.q_act)
    frame = None if meas.frame == mech.measured_frame else meas.frame
    pred = [mech.frame_placement(q, frame).rotation for q in qs]
    return np.array(
        [np.linalg.norm(pin.log3(a.T @ b)) for a, b in zip(pred, meas.rotations, strict=True)]
    )


@dataclass(frozen=True)
class BlockScales:
    """The noise σ that whitens each block of a held-out error (6-D poses).

    Attributes:
        position: σ per position coordinate [m].
        orientation: σ per rotation component [rad].
    """

    position: float
    orientation: float

    def to_dict(self) -> dict:
        """The two scales for JSON: position [mm], orientation [mrad]."""
        return {"position_mm": self.position * 1e3, "orientation_mrad": self.orientation * 1e3}


def _floats(v: npt.ArrayLike | None) -> np.ndarray | None:
    return None if v is None else np.asarray(v, dtype=float)


@dataclass(frozen=True)
class CrossValidation:
    """Held-out position (and orientation) errors of one fitting procedure.

    Attributes:
        folds: the K folds (pose indices, 0-based rows of the data file).
        held_out: (m,) each pose's error [m] predicted by the fit that did not see it.
        fit_rms: (K,) RMS position error [m] of each fold's fit on its own poses.
        held_out_orientation: (m,) each pose's held-out rotation error angle [rad], or
            None (no orientation measured).
        fit_orientation_rms: (K,) RMS rotation error angle [rad] of each fold's fit on
            its own poses, or None.
    """

    folds: tuple[np.ndarray, ...]
    held_out: np.ndarray
    fit_rms: np.ndarray
    held_out_orientation: np.ndarray | None = None
    fit_orientation_rms: np.ndarray | None = None

    @property
    def orientation_rms(self) -> float | None:
        """Held-out RMS rotation error angle [rad], or None."""
        h = self.held_out_orientation
        return None if h is None else float(np.sqrt(np.mean(h**2)))

    @property
    def orientation_max(self) -> float | None:
        """Largest held-out rotation error angle [rad], or None."""
        h = self.held_out_orientation
        return None if h is None else float(h.max())

    @property
    def rms(self) -> float:
        """RMS of the held-out pose errors [m]."""
        return float(np.sqrt(np.mean(self.held_out**2)))

    @property
    def max(self) -> float:
        """Largest held-out pose error [m]."""
        return float(self.held_out.max())

    def squared_errors(self, scales: BlockScales | None = None) -> np.ndarray:
        """(m,) each pose's held-out squared error: [m²], or whitened by ``scales``.

        With ``scales`` and orientation measured: ``|Δp|²/σ_p² + θ²/σ_r²``
        (dimensionless, ≈ 3 + 3 per pose for errors at the noise level), so position
        and orientation count by how far each is outside its own noise. Without
        orientation, ``scales`` leaves the position errors [m²] unchanged.
        """
        if scales is None or self.held_out_orientation is None:
            return self.held_out**2
        return (self.held_out / scales.position) ** 2 + (
            self.held_out_orientation / scales.orientation
        ) ** 2

    def fit_scales(self) -> BlockScales | None:
        """Each block's noise σ as the folds' own fits leave it, or None (no orientation).

        σ_p = fold-fit RMS distance / √3, σ_r = fold-fit RMS angle / √3 (per
        coordinate, over the training poses of every fold); None as well when either is
        zero (exact data).
        """
        if self.fit_orientation_rms is None:
            return None
        p = float(np.sqrt(np.mean(self.fit_rms**2) / 3))
        r = float(np.sqrt(np.mean(self.fit_orientation_rms**2) / 3))
        return BlockScales(p, r) if p > 0 and r > 0 else None

    def to_record(self) -> dict:
        """Every array as a JSON list (floats round-trip exactly): :meth:`from_record`."""

        def out(v: np.ndarray | None) -> list | None:
            return None if v is None else [float(x) for x in v]

        return {
            "folds": [[int(i) for i in f] for f in self.folds],
            "held_out_m": out(self.held_out),
            "fit_rms_m": out(self.fit_rms),
            "held_out_orientation_rad": out(self.held_out_orientation),
            "fit_orientation_rms_rad": out(self.fit_orientation_rms),
        }

    @classmethod
    def from_record(cls, d: dict) -> CrossValidation:
        """The cross-validation :meth:`to_record` wrote."""
        return cls(
            tuple(np.asarray(f, dtype=int) for f in d["folds"]),
            np.asarray(d["held_out_m"], dtype=float),
            np.asarray(d["fit_rms_m"], dtype=float),
            _floats(d.get("held_out_orientation_rad")),
            _floats(d.get("fit_orientation_rms_rad")),
        )

    def to_dict(self) -> dict:
        """Held-out RMS / max and the folds' fit RMS [mm] (orientation [mrad]), for JSON."""
        out = {
            "held_out_rms_mm": self.rms * 1e3,
            "held_out_max_mm": self.max * 1e3,
            "fold_fit_rms_mm": float(np.sqrt(np.mean(self.fit_rms**2))) * 1e3,
        }
        if self.held_out_orientation is not None and self.fit_orientation_rms is not None:
            out |= {
                "held_out_orientation_rms_mrad": float(self.orientation_rms or 0.0) * 1e3,
                "held_out_orientation_max_mrad": float(self.orientation_max or 0.0) * 1e3,
                "fold_fit_orientation_rms_mrad": float(
                    np.sqrt(np.mean(self.fit_orientation_rms**2))
                )
                * 1e3,
            }
        return out


def _errors(mech: Mechanism, parts: tuple[Measurements, ...], rows: np.ndarray) -> np.ndarray:
    """Per pose of ``rows``, the RMS over the markers of the position error [m]."""
    e = np.array([position_errors(mech, p.subset(rows)) for p in parts])
    return np.sqrt(np.mean(e**2, axis=0))


def cross_validate(
    fit: Callable[[Any], Mechanism],
    meas: Measurements | Sequence[Measurements],
    k: int,
    seed: int,
) -> CrossValidation:
    """Fit on K − 1 folds, predict the held-out fold, for every fold.

    Args:
        fit: measurements → calibrated mechanism (the whole procedure, registration
            included, so nothing of the held-out fold leaks into the fit); with several
            markers it receives the tuple of their training rows.
        meas: all poses (positions measured), or one set per marker (same rows; the
            mechanism ``fit`` returns predicts each set's frame).
        k: number of folds.
        seed: the folds' seed (:func:`kfold`).
    """
    parts = (meas,) if isinstance(meas, Measurements) else tuple(meas)
    m = len(parts[0])
    folds = kfold(m, k, seed)
    held = np.empty(m)
    fit_rms = np.empty(k)
    turned = parts[0].rotations is not None and {"rx", "ry", "rz"} <= set(parts[0].components)
    held_r, fit_r = (np.empty(m), np.empty(k)) if turned else (None, None)
    for j, rows in enumerate(folds):
        train = np.setdiff1d(np.arange(m), rows)
        sets = tuple(p.subset(train) for p in parts)
        mech = fit(sets[0] if isinstance(meas, Measurements) else sets)
        held[rows] = _errors(mech, parts, rows)
        fit_rms[j] = float(np.sqrt(np.mean(_errors(mech, parts, train) ** 2)))
        if held_r is not None and fit_r is not None:
            held_r[rows] = orientation_errors(mech, parts[0].subset(rows))
            fit_r[j] = float(np.sqrt(np.mean(orientation_errors(mech, sets[0]) ** 2)))
    return CrossValidation(folds, held, fit_rms, held_r, fit_r)


def compare(
    model: CrossValidation, baseline: CrossValidation, scales: BlockScales | None = None
) -> tuple[float, float, bool]:
    """(gain, its standard error, beats) of ``model`` over ``baseline`` on the same folds.

    ``gain`` is the baseline's held-out mean squared error minus the model's [m²] —
    with ``scales`` and orientation measured, of the whitened squared errors
    (:meth:`CrossValidation.squared_errors`, dimensionless) — its standard error that
    of the mean of the paired per-pose differences; ``beats`` is True when the gain
    exceeds its standard error.
    """
    d = baseline.squared_errors(scales) - model.squared_errors(scales)
    se = float(np.std(d, ddof=1) / np.sqrt(d.size)) if d.size > 1 else float("inf")
    gain = float(np.mean(d))
    return gain, se, gain > se

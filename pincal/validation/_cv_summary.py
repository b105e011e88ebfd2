"""The outcome of ``pincal validate --cv K``: held-out errors of a calibration and a baseline.

K-fold refits of the calibration as it was run (:func:`pincal.validation.cross_validate`
for pose and marker files, held-out seatings for a ball-in-socket file), beside the same
for a baseline model (the nominal model, or for a marker campaign the registration-only
model). Lengths in metres and angles in radians inside; with orientation measured (a
6-D marker body, a pose file) the held-out rotation error angles too.
:meth:`CrossValidationSummary.to_dict` gives the ``cv`` record of ``validate --json``
in mm (and mrad), :func:`pincal.report.cross_validation_text` its printed block.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

__all__ = ["CrossValidationBaseline", "CrossValidationSummary", "OrientationErrors"]


@dataclass(frozen=True)
class CrossValidationBaseline:
    """The held-out errors of the baseline model over the same folds [m].

    Attributes:
        model: its name (``"nominal model"`` or ``"registration only"``).
        held_out_rms, held_out_max: held-out position (seating) error, RMS and max.
        fold_fit_rms: RMS over the folds of each fold fit's RMS on its own poses.
        socket_distance_rms, socket_distance_max: held-out socket-distance error (a
            socket calibration), else None.
        orientation: held-out rotation error angle [rad] (RMS, max, fold fit RMS),
            or None (no orientation measured).
    """

    model: str
    held_out_rms: float
    held_out_max: float
    fold_fit_rms: float
    socket_distance_rms: float | None = None
    socket_distance_max: float | None = None
    orientation: OrientationErrors | None = None


@dataclass(frozen=True)
class OrientationErrors:
    """Rotation error angles ‖log3(R_predictedᵀ R_measured)‖ of a cross-validation [rad].

    Attributes:
        held_out_rms, held_out_max: over the poses, each predicted by the fold fit that
            did not see it.
        fold_fit_rms: RMS over the folds of each fold fit's RMS on its own poses.
        fit_rms: of the calibration itself on every pose (None for a baseline).
    """

    held_out_rms: float
    held_out_max: float
    fold_fit_rms: float
    fit_rms: float | None = None

    def to_dict(self) -> dict[str, float]:
        """The orientation keys of the ``cv`` record [mrad]."""
        out = {"held_out_orientation_rms_mrad": self.held_out_rms * 1e3,
               "held_out_orientation_max_mrad": self.held_out_max * 1e3,
               "fold_fit_orientation_rms_mrad": self.fold_fit_rms * 1e3}  # fmt: skip
        if self.fit_rms is not None:
            out["fit_orientation_rms_mrad"] = self.fit_rms * 1e3
        return out


@dataclass(frozen=True)
class CrossValidationSummary:
    """K-fold cross-validation of a calibration beside a baseline [m, m²].

    Attributes:
        k, seed: the folds (:func:`pincal.validation.kfold`); poses: rows split.
        folds: the pose rows of each fold.
        fit_rms: RMS position residual of the calibration itself.
        held_out_rms, held_out_max, fold_fit_rms: as :class:`CrossValidationBaseline`,
            for the calibration refitted per fold.
        baseline: the baseline's errors.
        beats_baseline: the calibration predicts held-out poses better.
        gain_mse, gain_standard_error: the baseline's held-out mean squared error minus
            the calibration's, and its standard error [m²] (pose files), else None.
        socket_distance_rms, socket_distance_max: held-out socket-distance error (a
            socket calibration), else None.
        orientation: the calibration's rotation errors (its ``baseline.orientation``
            the baseline's), or None (no orientation measured).
        whitened_gain: with orientation measured, the gain of the per-pose squared
            errors whitened by each block's noise σ and its standard error
            (dimensionless, :func:`pincal.validation.compare`); the verdict is then
            on it (``gain_mse`` stays the positions' gain), else None.
        recorded: the figures are those calibrate computed and recorded on these folds
            (the same procedure), not refitted here.
    """

    k: int
    seed: int
    poses: int
    folds: tuple[tuple[int, ...], ...]
    fit_rms: float
    held_out_rms: float
    held_out_max: float
    fold_fit_rms: float
    baseline: CrossValidationBaseline
    beats_baseline: bool
    gain_mse: float | None = None
    gain_standard_error: float | None = None
    socket_distance_rms: float | None = None
    socket_distance_max: float | None = None
    orientation: OrientationErrors | None = None
    whitened_gain: tuple[float, float] | None = None
    recorded: bool = False

    @property
    def sockets(self) -> bool:
        """True for a ball-in-socket calibration (socket-distance errors, no MSE gain)."""
        return self.socket_distance_rms is not None

    @property
    def verdict(self) -> str:
        """One sentence: does the calibration beat the baseline on held-out poses [mm]."""
        full, base = self.held_out_rms * 1e3, self.baseline.held_out_rms * 1e3
        if self.sockets:
            assert self.socket_distance_rms is not None
            assert self.baseline.socket_distance_rms is not None
            return (
                f"held-out socket-distance error {self.socket_distance_rms * 1e3:.4f} mm RMS "
                f"over the folds (the nominal model: {self.baseline.socket_distance_rms * 1e3:.4f}"
                f" mm); held-out seating error {full:.4f} mm RMS"
            )
        gain = float("nan") if self.gain_mse is None else self.gain_mse * 1e6
        se = float("nan") if self.gain_standard_error is None else self.gain_standard_error * 1e6
        name = self.baseline.model
        if self.whitened_gain is not None:
            g, e = self.whitened_gain
            o, bo = self.orientation, self.baseline.orientation
            angles = (
                ""
                if o is None or bo is None
                else (f", {o.held_out_rms * 1e3:.3f} against {bo.held_out_rms * 1e3:.3f} mrad")
            )
            word = "beats" if self.beats_baseline else "does NOT beat"
            return (
                f"position and orientation together (each whitened by its noise σ), the "
                f"calibration {word} the {name} on held-out poses: {full:.3f} against "
                f"{base:.3f} mm{angles} RMS (whitened squared error lower by {g:.3g} ± "
                f"{e:.2g})"
            )  # fmt: skip
        if self.beats_baseline:
            return (
                f"the calibration beats the {name} on held-out poses: {full:.3f} mm against "
                f"{base:.3f} mm RMS (mean squared error lower by {gain:.3g} ± {se:.2g} mm²)"
            )
        return (
            f"the calibration does NOT beat the {name} by more than its standard error: "
            f"{full:.3f} mm against {base:.3f} mm RMS held-out (gain {gain:.3g} ± {se:.2g} "
            "mm²); the data do not support the full model — use the simpler one, or measure "
            "more poses"
        )

    def to_dict(self) -> dict[str, Any]:
        """The ``cv`` record of ``validate --json`` (lengths in mm, areas in mm²)."""
        head = {
            "k": self.k,
            "seed": self.seed,
            "poses": self.poses,
            "folds": [list(rows) for rows in self.folds],
            "fit_rms_mm": self.fit_rms * 1e3,
        }
        b = self.baseline
        own = _errors(self.held_out_rms, self.held_out_max, self.fold_fit_rms)
        base = {"model": b.model, **_errors(b.held_out_rms, b.held_out_max, b.fold_fit_rms)}
        extra: dict[str, Any] = {}
        if self.orientation is not None and b.orientation is not None:
            own |= self.orientation.to_dict()
            base |= b.orientation.to_dict()
        if self.sockets:
            own |= _socket_errors(self.socket_distance_rms, self.socket_distance_max)
            base |= _socket_errors(b.socket_distance_rms, b.socket_distance_max)
        else:
            assert self.gain_mse is not None and self.gain_standard_error is not None
            extra = {"gain_mse_mm2": self.gain_mse * 1e6,
                     "gain_standard_error_mm2": self.gain_standard_error * 1e6}  # fmt: skip
        if self.whitened_gain is not None:
            extra |= {"gain_whitened": self.whitened_gain[0],
                      "gain_whitened_standard_error": self.whitened_gain[1]}  # fmt: skip
        if self.recorded:  # figures calibrate computed on these folds, not refitted
            extra["recorded_by_calibrate"] = True
        return {**head, **own, "baseline": base, **extra,
                "beats_baseline": self.beats_baseline, "verdict": self.verdict}  # fmt: skip


def _socket_errors(rms: float | None, mx: float | None) -> dict[str, float]:
    assert rms is not None and mx is not None
    return {"socket_distance_error_rms_mm": rms * 1e3, "socket_distance_error_max_mm": mx * 1e3}


def _errors(rms: float, mx: float, fold_fit: float) -> dict[str, float]:
    return {"held_out_rms_mm": rms * 1e3, "held_out_max_mm": mx * 1e3,
            "fold_fit_rms_mm": fold_fit * 1e3}  # fmt: skip

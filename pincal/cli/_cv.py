"""``pincal validate --cv K``: K-fold cross-validation of a calibration, as calibrate ran it.

Every fold is refitted from scratch on the other folds — for a marker calibration the
closed-form registration too, and ``--prior auto`` chooses its strength again inside the
fold — so nothing of a held-out pose reaches its prediction. The baseline is the
registration-only model (instrument frame + marker: the robot left uncalibrated) for a
marker calibration, the nominal model otherwise. Units: mm.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from pincal.errors import PincalError

__all__ = ["format_cv", "run_cv"]


def _pose_fit(cal):
    """(measurements, fit, baseline fit) of a pose-file calibration."""
    from pincal.identification import identify
    from pincal.io import read_measurement_file
    from pincal.sensitivity import parameters

    files = cal.manifest.get("data_files") or []
    if not files:
        raise PincalError(f"{cal.path}: the calibration records no data file to cross-validate")
    nominal = cal.nominal()
    meas = read_measurement_file(files[0]["path"], nominal).measurements
    params = parameters(nominal, cal.preset)
    if params.joint_terms.size:
        raise PincalError(
            f"{cal.path}: validate --cv predicts with the calibrated URDF, which does not carry "
            f"the joint terms of {cal.preset!r}; cross-validate them with `pincal select-model`"
        )
    method = str(cal.manifest.get("method") or "gauss-newton")

    def fit(m):
        return identify(nominal, params, m, method).calibrated_mechanism

    return meas, fit, lambda m: nominal


def run_cv(cal, k: int, seed: int, folds_out: Path | None) -> dict[str, Any]:
    """The ``cv`` object of ``validate --json`` (held-out RMS / max in mm, folds, verdict)."""
    from pincal.cli._socket_cv import is_socket_calibration
    from pincal.identification import compare, cross_validate

    if is_socket_calibration(cal):
        return _socket_doc(cal, k, seed, folds_out)
    markers = cal.manifest.get("markers")
    if markers:
        from pincal.cli._markers import fold_fitter, rebuild

        setup, mech, meas = rebuild(cal)
        fit = fold_fitter(mech, setup, markers, registration_only=False)
        base = fold_fitter(mech, setup, markers, registration_only=True)
        baseline_name = "registration only"
    else:
        meas, fit, base = _pose_fit(cal)
        baseline_name = "nominal model"
    poses = len(meas[0]) if isinstance(meas, tuple) else len(meas)  # one set per marker
    full = cross_validate(fit, meas, k, seed)
    ref = cross_validate(base, meas, k, seed)
    gain, se, beats = compare(full, ref)
    _write_folds(full.folds, poses, folds_out)
    after = cal.result.after
    doc = {
        "k": k,
        "seed": seed,
        "poses": poses,
        "folds": [[int(i) for i in rows] for rows in full.folds],
        "fit_rms_mm": float(after.rms_position) * 1e3,
        **full.to_dict(),
        "baseline": {"model": baseline_name, **ref.to_dict()},
        "gain_mse_mm2": gain * 1e6,
        "gain_standard_error_mm2": se * 1e6,
        "beats_baseline": bool(beats),
    }
    doc["verdict"] = _verdict(doc)
    return doc


def _write_folds(folds, poses: int, folds_out: Path | None) -> None:
    fold_of = np.empty(poses, dtype=int)
    for j, rows in enumerate(folds):
        fold_of[rows] = j
    if folds_out is not None:
        from pincal.io import atomic_write_text

        text = "pose,fold\n" + "".join(f"{i},{f}\n" for i, f in enumerate(fold_of))
        atomic_write_text(folds_out, text)


def _socket_doc(cal, k: int, seed: int, folds_out: Path | None) -> dict[str, Any]:
    from pincal.cli._socket_cv import socket_cv

    nums, folds, poses = socket_cv(cal, k, seed)
    _write_folds(folds, poses, folds_out)
    full = nums["socket_distance_error_rms_mm"]
    base = nums["baseline"]["socket_distance_error_rms_mm"]
    doc = {
        "k": k,
        "seed": seed,
        "poses": poses,
        "folds": [[int(i) for i in rows] for rows in folds],
        "fit_rms_mm": float(cal.result.after.rms_position) * 1e3,
        **nums,
        "beats_baseline": bool(full < base),
    }
    doc["verdict"] = (
        f"held-out socket-distance error {full:.4f} mm RMS over the folds (the nominal "
        f"model: {base:.4f} mm); held-out seating error {nums['held_out_rms_mm']:.4f} mm RMS"
    )
    return doc


def _verdict(doc: dict) -> str:
    full, base = doc["held_out_rms_mm"], doc["baseline"]["held_out_rms_mm"]
    se = doc["gain_standard_error_mm2"]
    gain = doc["gain_mse_mm2"]
    name = doc["baseline"]["model"]
    if doc["beats_baseline"]:
        return (
            f"the calibration beats the {name} on held-out poses: {full:.3f} mm against "
            f"{base:.3f} mm RMS (mean squared error lower by {gain:.3g} ± {se:.2g} mm²)"
        )
    return (
        f"the calibration does NOT beat the {name} by more than its standard error: "
        f"{full:.3f} mm against {base:.3f} mm RMS held-out (gain {gain:.3g} ± {se:.2g} mm²); "
        "the data do not support the full model — use the simpler one, or measure more poses"
    )


def format_cv(doc: dict) -> str:
    """The printed cross-validation block (mm)."""
    b = doc["baseline"]
    socket = "socket_distance_error_rms_mm" in doc
    registration = b["model"] == "registration only"
    lines = [
        "",
        f"cross-validation: {doc['k']} folds over {doc['poses']} poses (seed {doc['seed']}); "
        "every fold refitted without its poses",
        "                       fit RMS   fold fit RMS   held-out RMS   held-out max   [mm]",
        f"  calibrated model  {doc['fit_rms_mm']:10.3f}   {doc['fold_fit_rms_mm']:12.3f}   "
        f"{doc['held_out_rms_mm']:12.3f}   {doc['held_out_max_mm']:12.3f}",
        f"  {b['model'][:17]:17s} {'':10s}   {b['fold_fit_rms_mm']:12.3f}   "
        f"{b['held_out_rms_mm']:12.3f}   {b['held_out_max_mm']:12.3f}",
        "  (registration only: instrument frame + marker fitted, the robot uncalibrated)"
        if registration
        else "  (nominal model: the model before calibration)",
    ]
    if socket:
        lines[2] = lines[2].replace("held-out RMS", "seating RMS ")
        lines += [
            "  held-out socket-distance error (mean predicted ball centres of each "
            "socket's held-out seatings, minus the known distance) [mm]:",
            f"  calibrated model  RMS {doc['socket_distance_error_rms_mm']:.4f}   max "
            f"{doc['socket_distance_error_max_mm']:.4f}",
            f"  nominal model     RMS {b['socket_distance_error_rms_mm']:.4f}   max "
            f"{b['socket_distance_error_max_mm']:.4f}",
        ]
    lines.append(doc["verdict"])
    return "\n".join(lines) + "\n"

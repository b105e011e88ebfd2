"""The cross-validation of a ball-in-socket calibration (``validate --cv K``): held-out seatings.

Every fold refits the machine, the sockets' centres and the ball (when unknown) from the
other folds' seatings (:func:`pincal.identification.identify_instruments`, the plate's
known distances included), then predicts the ball centre of each held-out seating with
that fit. Two errors per fold [mm]:

* **seating error**: distance from a held-out predicted ball centre to its socket's
  fitted centre (what a probe at that pose would miss by);
* **socket-distance error**: for each known distance A–B whose sockets both have
  held-out seatings, the distance between the mean predicted ball centres in A and in B,
  minus the known value — the length the plate calibrates, measured on poses no fit saw.

The baseline is the nominal machine with only the ball and the socket centres fitted
(linear least squares, in closed form).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from pincal.errors import MeasurementFormatError, PincalError
from pincal.identification import identify_instruments
from pincal.io import CalibrationDirectory, file_kind, read_instrument_file
from pincal.measure import SocketData
from pincal.model import Mechanism, parameters
from pincal.validation import CrossValidationBaseline, CrossValidationSummary, kfold

__all__ = ["is_socket_calibration", "socket_cross_validation"]


def is_socket_calibration(cal: CalibrationDirectory) -> bool:
    """True when the calibration's first data file is a ball-in-socket file."""
    if not cal.manifest.get("data_files"):
        return False
    return file_kind(cal.data_file()) == "sockets"


def _flange(mech: Mechanism, data: SocketData, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    T = [mech.frame_placement(c, data.frame) for c in mech.configurations(data.q_act[rows])]
    return np.array([t.translation for t in T]), np.array([t.rotation for t in T])


def _linear_fit(
    data: SocketData, P: np.ndarray, R: np.ndarray, sockets: list[str]
) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Ball (3,) and socket centres {name: (3,)} [m] of a fixed machine: least squares."""
    names = sorted(set(sockets))
    m = len(sockets)
    if data.ball is not None:
        b = np.asarray(data.ball, dtype=float)
        B = P + np.einsum("mij,j->mi", R, b)
        return b, {s: B[[k for k in range(m) if sockets[k] == s]].mean(axis=0) for s in names}
    A = np.zeros((3 * m, 3 + 3 * len(names)))  # p + R b − c_s = 0
    for k, s in enumerate(sockets):
        A[3 * k : 3 * k + 3, :3] = R[k]
        j = 3 + 3 * names.index(s)
        A[3 * k : 3 * k + 3, j : j + 3] = -np.eye(3)
    x = np.linalg.lstsq(A, -P.reshape(-1), rcond=None)[0]
    return x[:3], {s: x[3 + 3 * i : 6 + 3 * i] for i, s in enumerate(names)}


def _held_out(
    data: SocketData,
    P: np.ndarray,
    R: np.ndarray,
    ball: np.ndarray,
    centres: dict[str, np.ndarray],
    sockets: list[str],
) -> tuple[np.ndarray, list[float]]:
    B = P + np.einsum("mij,j->mi", R, ball)
    seat = np.array([np.linalg.norm(B[k] - centres[s]) for k, s in enumerate(sockets)])
    dist = []
    for d in data.plate.distances:
        ia = [k for k, s in enumerate(sockets) if s == d.a]
        ib = [k for k, s in enumerate(sockets) if s == d.b]
        if ia and ib:
            gap = np.linalg.norm(B[ia].mean(axis=0) - B[ib].mean(axis=0))
            dist.append(float(gap - d.value))
    return seat, dist


def _summary(
    model: str, seat: list[np.ndarray], dist: list[float], fit_rms: list[float]
) -> CrossValidationBaseline:
    """The held-out errors of the folds [m] (``model``: whose they are)."""
    s = np.concatenate(seat)
    d = np.abs(np.array(dist)) if dist else np.array([np.nan])
    return CrossValidationBaseline(
        model,
        held_out_rms=float(np.sqrt(np.mean(s**2))),
        held_out_max=float(s.max()),
        fold_fit_rms=float(np.sqrt(np.mean(np.square(fit_rms)))),
        socket_distance_rms=float(np.sqrt(np.mean(d**2))),
        socket_distance_max=float(d.max()),
    )


def socket_cross_validation(
    cal: CalibrationDirectory, k: int, seed: int
) -> CrossValidationSummary:
    """The cross-validation of a socket calibration (its held-out seatings).

    Args:
        cal: a calibration of a ball-in-socket file (:func:`is_socket_calibration`).
        k: folds of the seatings.
        seed: the folds' seed (:func:`pincal.validation.kfold`).

    Returns:
        Held-out seating and socket-distance errors [m], calibrated model beside the
        nominal one (ball and socket centres fitted); ``folds``: seating rows per fold.

    Raises:
        PincalError: the data file is gone, or no known distance fixes the scale (the
            held-out socket distance would then measure nothing).
    """
    nominal = cal.nominal()
    with cal.reading_data_file() as path:  # the bytes parsed are the ones hashed
        data = read_instrument_file(path, nominal)
    if not isinstance(data, SocketData):
        raise MeasurementFormatError(f"{path}: not a ball-in-socket file (# pincal sockets 1)")
    if not data.plate.distances:
        raise PincalError(
            f"{path}: no known distance between sockets: the length scale is unidentifiable, "
            "so held-out socket distances would measure nothing; add '# distance: A, B, "
            "VALUE, STD' (the plate's calibrated distance; in a campaign file "
            "sockets.distances) and calibrate again"
        )
    params = parameters(nominal, cal.preset)
    method = str(cal.manifest.get("method") or "gauss-newton")
    label = Path(path).stem
    sockets = list(data.socket)
    folds = kfold(len(sockets), k, seed)
    full: dict[str, list] = {"seat": [], "dist": [], "fit": []}
    base: dict[str, list] = {"seat": [], "dist": [], "fit": []}
    for test in folds:
        train = np.setdiff1d(np.arange(len(sockets)), test)
        part = replace(data, q_act=data.q_act[train], socket=tuple(sockets[i] for i in train))
        out = identify_instruments(nominal, params, [part], method=method, labels=[label])
        mech = out.result.calibrated_mechanism
        inst = out.instrument_values()
        ball = (
            np.asarray(data.ball, dtype=float)
            if data.ball is not None
            else np.array([inst[f"{label}.ball_{a}"] for a in "xyz"])
        )
        centres = {key.split(".", 1)[1]: c for key, c in out.socket_centres.items()}
        P, R = _flange(mech, data, test)
        seat, dist = _held_out(data, P, R, ball, centres, [sockets[i] for i in test])
        full["seat"].append(seat)
        full["dist"] += dist
        full["fit"].append(float(out.result.after.rms_position))
        Pt, Rt = _flange(nominal, data, train)
        b0, c0 = _linear_fit(data, Pt, Rt, [sockets[i] for i in train])
        fit0, _ = _held_out(data, Pt, Rt, b0, c0, [sockets[i] for i in train])
        P0, R0 = _flange(nominal, data, test)
        seat0, dist0 = _held_out(data, P0, R0, b0, c0, [sockets[i] for i in test])
        base["seat"].append(seat0)
        base["dist"] += dist0
        base["fit"].append(float(np.sqrt(np.mean(fit0**2))))
    cv = _summary("calibrated model", full["seat"], full["dist"], full["fit"])
    baseline = _summary("nominal model", base["seat"], base["dist"], base["fit"])
    assert cv.socket_distance_rms is not None and baseline.socket_distance_rms is not None
    return CrossValidationSummary(
        k, seed, len(sockets), tuple(tuple(int(i) for i in rows) for rows in folds),
        float(cal.result.after.rms_position), cv.held_out_rms, cv.held_out_max,
        cv.fold_fit_rms, baseline,
        beats_baseline=bool(cv.socket_distance_rms * 1e3 < baseline.socket_distance_rms * 1e3),
        socket_distance_rms=cv.socket_distance_rms, socket_distance_max=cv.socket_distance_max,
    )  # fmt: skip

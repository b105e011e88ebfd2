"""Laser-tracker target files: raw target points per pose (``kind: targets``).

A measurement file (:mod:`pincal.io._measurement_file`) of kind ``targets``: the
header lists the targets fixed on the measured body (``# target: T1 0.1 0.0 0.02`` —
name and coordinates in the measured frame, length unit) and optionally
``# point_std: 0.01`` (1σ per point coordinate, length unit) and
``# max_residual: 0.05`` (moved-target threshold); each row holds the actuator values
and the measured points ``T1.x T1.y T1.z …`` in the world frame. Reading fits each
row's pose (Kabsch, :mod:`pincal.measure._tracker`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pincal.errors import MeasurementError, MeasurementFormatError, PoseFitError, clip
from pincal.io._csv import (
    Header,
    actuator_columns,
    fmt,
    parse_float,
    positive_value,
    write_csv,
)
from pincal.io._names import column_title, quote_value, quote_words, split_words
from pincal.io._units import LENGTH_UNITS, actuator_write_factors, unit_factor
from pincal.measure import Measurements, fit_rigid_transform, rigid_fit_covariance
from pincal.model import COMPONENTS

__all__ = [
    "TargetMeasurements",
    "parse_target_limits",
    "parse_targets",
    "write_target_measurements",
]


@dataclass(frozen=True)
class TargetMeasurements:
    """Raw laser-tracker data: measured target points per pose.

    Attributes:
        q_act: (m, n_act) actuator values [m, rad].
        points: (m, n_t, 3) measured target points, world frame [m].
        targets_local: (n_t, 3) target coordinates in the measured frame [m].
        names: target names (n_t,).
        frame: measured frame name.
        actuated: actuated joint names.
        point_std: 1σ per point coordinate [m], or None if unknown.
        max_residual: moved-target threshold [m], or None.
    """

    q_act: np.ndarray
    points: np.ndarray
    targets_local: np.ndarray
    names: tuple[str, ...]
    frame: str
    actuated: tuple[str, ...]
    point_std: float | None = None
    max_residual: float | None = None

    def to_measurements(self, components: tuple[str, ...] | None = None) -> Measurements:
        """Fit each pose (weighted Kabsch); per-pose std from the fit covariance.

        Args:
            components: components kept for identification (default all six).

        Returns:
            The fitted poses (m rows) as :class:`~pincal.measure.Measurements` [SI].

        Raises:
            PoseFitError (a MeasurementError) naming the data row when a pose cannot
            be fitted, e.g. a target residual exceeds ``max_residual``.
        """
        comps = tuple(components or COMPONENTS)
        m = self.q_act.shape[0]
        positions = np.empty((m, 3))
        rotations = np.empty((m, 3, 3))
        for i in range(m):
            try:
                fit = fit_rigid_transform(
                    self.targets_local, self.points[i], max_residual=self.max_residual
                )
            except MeasurementError as exc:
                raise PoseFitError(f"data row {i + 1}: {exc}", i + 1) from exc
            positions[i] = fit.T.translation
            rotations[i] = fit.T.rotation
        std = None
        if self.point_std is not None:
            cov = rigid_fit_covariance(self.targets_local, self.point_std)
            sd = np.sqrt(np.diag(cov))
            idx = [COMPONENTS.index(c) for c in comps]
            # The covariance is of a local twist; the world-frame position std equals the
            # local one only for isotropic noise, which rigid_fit_covariance assumes per
            # point, so the RMS of the three local linear stds is used for x, y, z.
            lin = float(np.sqrt(np.mean(sd[:3] ** 2)))
            row = np.array([lin if k < 3 else sd[k] for k in idx])
            std = np.tile(row, (m, 1))
        return Measurements(
            self.q_act.copy(), positions, rotations, comps, self.frame, self.actuated, None, std
        )


def parse_targets(header: Header, lf: float, name: str) -> tuple[list[str], np.ndarray]:
    """Target names and local coordinates (n_t, 3) [m] from the ``target`` header lines.

    Args:
        header: the file's header.
        lf: the file's length unit factor (units per metre).
        name: file name (for messages).

    Raises:
        MeasurementFormatError: a malformed target line or fewer than 3 targets.
    """
    names, coords = [], []
    for entry in header.get("target", []):
        parts = split_words(entry, f"{name} header 'target'")
        if len(parts) != 4:
            raise MeasurementFormatError(
                f"{name}: target line {clip(entry)}: expected 'name x y z'"
            )
        coords.append([parse_float(v, f"{name} target {clip(parts[0])}") / lf for v in parts[1:]])
        if not all(math.isfinite(c) for c in coords[-1]):
            raise MeasurementFormatError(
                f"{name}: target line {clip(entry)}: coordinates must be finite"
            )
        names.append(parts[0])
    if len(names) < 3:
        raise MeasurementFormatError(
            f"{name}: a targets file needs at least 3 '# target: name x y z' lines, got "
            f"{len(names)}"
        )
    return names, np.array(coords)


def parse_target_limits(header: Header, lf: float, name: str) -> tuple[float | None, float | None]:
    """(point_std, max_residual) [m] from the header, each None when absent.

    Raises:
        MeasurementFormatError: a value that is not a finite number > 0.
    """
    ps = header.get("point_std")
    point_std = None if ps is None else positive_value(ps[0], "point_std", name) / lf
    max_residual = (
        None
        if "max_residual" not in header
        else positive_value(header["max_residual"][0], "max_residual", name) / lf
    )
    return point_std, max_residual


def write_target_measurements(
    path: str | Path,
    data: TargetMeasurements,
    *,
    length_unit: str = "m",
    actuator_units: Sequence[str] | None = None,
) -> Path:
    """Write raw tracker target data (``kind: targets``) atomically.

    Args:
        path: output file.
        data: the target points [SI].
        length_unit: unit of the target coordinates, points and thresholds in the file.
        actuator_units: optional unit per actuator column (``"mm"``, ``"deg"``…); SI if None.

    Returns:
        The written path.

    Raises:
        MeasurementFormatError: unknown ``length_unit``.
        MeasurementError: bad ``actuator_units``.
    """
    lf = unit_factor(LENGTH_UNITS, length_unit, "length", "write_target_measurements")
    lines = [
        f"frame: {quote_value(data.frame, 'frame')}",
        "kind: targets",
        f"length_unit: {length_unit}",
    ]
    for n, p in zip(data.names, data.targets_local, strict=True):
        lines.append(f"target: {quote_words([n], 'target')} {' '.join(fmt(v * lf) for v in p)}")
    if data.point_std is not None:
        lines.append(f"point_std: {fmt(data.point_std * lf)}")
    if data.max_residual is not None:
        lines.append(f"max_residual: {fmt(data.max_residual * lf)}")
    columns = actuator_columns(data.actuated, actuator_units) + [
        column_title(f"{n}.{a}", None, "target") for n in data.names for a in "xyz"
    ]
    afac = actuator_write_factors(actuator_units, len(data.actuated))
    rows = [
        [fmt(v) for v in (*(data.q_act[i] * afac), *(data.points[i].ravel() * lf))]
        for i in range(data.q_act.shape[0])
    ]
    return write_csv(path, "measurements", lines, columns, rows)

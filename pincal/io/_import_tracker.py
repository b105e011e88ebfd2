"""Import a laser tracker's point export and a controller log as a ``targets`` file.

Three inputs, each a delimited text table (comma, semicolon or tab; ``.`` or ``,``
as the decimal mark; leading ``#`` lines skipped — see :mod:`pincal.io._delimited`):

**Points** (the tracker export, long format, one measured point per row), columns
``pose`` (a pose or group id) and/or ``time``, ``point`` (the target name) and
``x y z`` — the point in the machine base (world) frame, i.e. after the tracker has
been aligned to the base in the tracker software. Recognised titles (case ignored):
pose/group/pose_id/group_id, time/timestamp/t, point/name/target/point_name, x, y, z;
other titles are mapped with ``point_columns={"pose": "Group", "x": "X"}`` (CLI
``--columns pose=Group,x=X``). The length unit is stated with ``length_unit`` (CLI
``--unit``) or as ``X [mm]`` in the titles.

**Targets** (where each target sits on the measured body), one row per target:
``point x y z`` in the model's measured frame, same unit rules.

**Controller log**, one row per pose: ``pose`` and/or ``time`` and one column per
actuated joint, titled with the joint name (or mapped with ``log_columns``). Joint
values are in ``log_length_unit`` (prismatic) / ``log_angle_unit`` (revolute), or in
a bracketed title unit (``leg1_slide [mm]``).

Matching (``match``): ``pose`` pairs points and log rows with equal pose ids
(``1`` and ``1.0`` are equal); ``time`` assigns each point to the log row with the
nearest time stamp (seconds, or ISO 8601 date-times) within ``tolerance`` seconds;
``auto`` uses ``pose`` when both files have a pose column, else ``time``. Every log
row must receive each target exactly once and every point must find its log row;
otherwise :class:`~pincal.errors.ImportMatchError` lists the offending lines (a
point within ``tolerance`` of two log rows is refused as ambiguous; points whose
name is not a target are refused unless ``ignore_unknown_points``). The result
keeps the controller log's row order. Inputs are only read.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from pincal._yaml import shown
from pincal.errors import (
    BadValueError,
    ColumnError,
    ImportMatchError,
    MeasurementError,
    PoseFitError,
)
from pincal.io._delimited import Table, read_table
from pincal.io._tracker_columns import ALIASES, read_actuators, read_xyz
from pincal.io._tracker_file import TargetMeasurements
from pincal.model import Mechanism

__all__ = ["TrackerImport", "TrackerImportOptions", "import_tracker"]

MATCHES = ("auto", "pose", "time")
_SHOWN = 12


@dataclass(frozen=True)
class TrackerImportOptions:
    """How to read the three inputs (see the module doc).

    Attributes:
        match: ``auto``, ``pose`` or ``time``.
        tolerance: largest |time difference| between a point and its log row [s].
        length_unit: unit of points and targets without a bracketed unit, or None.
        log_length_unit, log_angle_unit: units of the log's prismatic / revolute joints.
        point_columns, target_columns, log_columns: field → column title overrides.
        delimiter: ``auto``, ``,``, ``;`` or ``tab`` (all three files).
        decimal: ``auto``, ``.`` or ``,`` (all three files).
        point_std: 1σ per point coordinate [the points file's unit], or None.
        max_residual: moved-target threshold [the points file's unit], or None.
        ignore_unknown_points: skip points whose name is not a target (e.g. base
            reference nests) instead of refusing them.
    """

    match: str = "auto"
    tolerance: float = 0.5
    length_unit: str | None = None
    log_length_unit: str = "m"
    log_angle_unit: str = "rad"
    point_columns: Mapping[str, str] = field(default_factory=dict)
    target_columns: Mapping[str, str] = field(default_factory=dict)
    log_columns: Mapping[str, str] = field(default_factory=dict)
    delimiter: str = "auto"
    decimal: str = "auto"
    point_std: float | None = None
    max_residual: float | None = None
    ignore_unknown_points: bool = False


@dataclass(frozen=True)
class TrackerImport:
    """The imported campaign.

    Attributes:
        targets: the raw target data [SI], rows in controller-log order.
        pose_ids: per row, the pose id (or the log time stamp as text).
        log_lines: per row, its 1-based line in the controller log.
        match: the matching used (``pose`` or ``time``).
        max_time_offset: largest |point time − log time| [s] (time matching), else None.
    """

    targets: TargetMeasurements
    pose_ids: tuple[str, ...]
    log_lines: tuple[int, ...]
    match: str
    max_time_offset: float | None


def _norm_id(text: str) -> str:
    try:
        v = float(text)
    except ValueError:
        return text
    return str(int(v)) if v.is_integer() else repr(v)


def _time(table: Table, i: int, k: int) -> float:
    cell = table.rows[i][k].strip()
    try:
        return table.number(i, k)
    except BadValueError:
        pass
    try:
        stamp = datetime.fromisoformat(cell)
    except ValueError:
        raise BadValueError(
            f"{table.name} line {table.lines[i]}, column {shown(table.columns[k])}: "
            f"{shown(cell)} is "
            f"neither seconds nor an ISO 8601 date-time",
            i + 1,
            table.columns[k],
        ) from None
    if stamp.tzinfo is None:
        stamp = stamp.replace(tzinfo=UTC)
    return stamp.timestamp()


def _listing(items: list) -> str:
    shown = ", ".join(str(v) for v in items[:_SHOWN])
    return shown + (f", … ({len(items) - _SHOWN} more)" if len(items) > _SHOWN else "")


def _assign(
    points: Table, log: Table, opts: TrackerImportOptions
) -> tuple[str, np.ndarray, list[str], float | None]:
    """(mode, log row per point row, pose id per log row, max time offset)."""
    pk = {f: points.find(f, ALIASES[f], opts.point_columns) for f in ("pose", "time")}
    lk = {f: log.find(f, ALIASES[f], opts.log_columns) for f in ("pose", "time")}
    mode = opts.match
    if mode not in MATCHES:
        raise MeasurementError(f"match {shown(mode)} unknown; use one of {MATCHES}")
    if mode == "auto":
        mode = "pose" if pk["pose"] is not None and lk["pose"] is not None else "time"
    pcol, lcol = pk[mode], lk[mode]
    if pcol is None or lcol is None:
        where = [t.name for t, k in ((points, pk), (log, lk)) if k[mode] is None]
        raise ColumnError(
            f"matching by {mode} needs a {mode} column in {where}; map it (--columns "
            f"{mode}=…, --log-columns {mode}=…) or choose --match "
            f"{'time' if mode == 'pose' else 'pose'}",
            missing=[mode],
        )
    n_log = len(log.rows)
    if mode == "pose":
        ids = [_norm_id(log.text(i, lcol)) for i in range(n_log)]
        first: dict[str, int] = {}
        for i, pid in enumerate(ids):
            if pid in first:
                raise ImportMatchError(
                    f"{log.name}: pose {shown(pid)} on lines {log.lines[first[pid]]} and "
                    f"{log.lines[i]}; pose ids must be unique",
                    log_lines=[log.lines[first[pid]], log.lines[i]],
                )
            first[pid] = i
        pairs = [first.get(_norm_id(points.text(i, pcol)), -1) for i in range(len(points.rows))]
        return mode, np.array(pairs, dtype=int), ids, None
    if not opts.tolerance > 0:
        raise MeasurementError(f"time tolerance {shown(opts.tolerance)} s must be > 0")
    lt = np.array([_time(log, i, lcol) for i in range(n_log)])
    pt = np.array([_time(points, i, pcol) for i in range(len(points.rows))])
    dist = np.abs(pt[:, None] - lt[None, :])
    nearest = dist.argmin(axis=1) if n_log else np.zeros(0, int)
    offset = dist[np.arange(len(pt)), nearest] if n_log else np.full(len(pt), np.inf)
    owner = np.where(offset <= opts.tolerance, nearest, -1)
    if n_log > 1:
        twice = np.flatnonzero(np.partition(dist, 1, axis=1)[:, 1] <= opts.tolerance)
        if twice.size:
            lines = [points.lines[i] for i in twice]
            raise ImportMatchError(
                f"{points.name}: {len(lines)} points lie within {opts.tolerance} s of two "
                f"controller-log rows: lines {_listing(lines)}; use a tolerance below half "
                f"the time between poses",
                points_lines=lines,
            )
    if pk["pose"] is not None and lk["pose"] is not None:
        _check_ids_agree(points, log, owner, pk["pose"], lk["pose"])
    ids = [log.rows[i][lcol].strip() for i in range(n_log)]
    ok = offset[owner >= 0]
    return mode, owner, ids, float(ok.max()) if ok.size else None


def _check_ids_agree(points: Table, log: Table, owner: np.ndarray, pcol: int, lcol: int) -> None:
    """Points paired by time carry the pose id of their log row (when both files have ids)."""
    bad = [
        i
        for i, r in enumerate(owner)
        if r >= 0 and _norm_id(points.text(i, pcol)) != _norm_id(log.text(int(r), lcol))
    ]
    if bad:
        i, r = bad[0], int(owner[bad[0]])
        lines = [points.lines[k] for k in bad]
        raise ImportMatchError(
            f"{points.name}: matching by time pairs {len(bad)} points with a log row of "
            f"another pose id, e.g. line {points.lines[i]} (pose "
            f"{shown(points.text(i, pcol))}) with {log.name} line {log.lines[r]} (pose "
            f"{shown(log.text(r, lcol))}); both files give pose ids and times, and they "
            "must agree: fix the ids or the clocks, or match by pose (--match pose)",
            points_lines=lines,
        )


def import_tracker(
    points_path: str | Path,
    log_path: str | Path,
    targets_path: str | Path,
    mech: Mechanism,
    options: TrackerImportOptions | None = None,
) -> TrackerImport:
    """Pair a tracker point export with a controller log (see the module doc).

    Args:
        points_path: the tracker export (long format), read only.
        log_path: the controller log (one row per pose), read only.
        targets_path: target coordinates in the measured frame, read only.
        mech: the model (actuated joints, measured frame).
        options: how to read and match the files (default :class:`TrackerImportOptions`).

    Returns:
        The raw target data [SI] in controller-log order, with the pose ids.

    Raises:
        ImportMatchError: points without a log row, log rows without points, a target
            missing or repeated in a pose, duplicate pose ids (lines listed).
        ColumnError, BadValueError, MeasurementFormatError: a column or cell that
            cannot be read (file, line and column named).
        PoseFitError: a pose whose targets do not fit the rigid target set.
        MeasurementError: a bad option (unit, delimiter, match, tolerance).
    """
    o = options or TrackerImportOptions()
    points = read_table(points_path, o.delimiter, o.decimal, hints=True)
    log = read_table(log_path, o.delimiter, o.decimal, hints=True)
    tgt = read_table(targets_path, o.delimiter, o.decimal, hints=True)
    tnames, local, _ = read_xyz(tgt, o.target_columns, o.length_unit, "targets file")
    dup = sorted({n for n in tnames if tnames.count(n) > 1})
    if dup or len(tnames) < 3:
        raise MeasurementError(
            f"{tgt.name}: needs at least 3 targets with distinct names; got {tnames}"
        )
    names, pts, lf = read_xyz(points, o.point_columns, o.length_unit, "points file")
    q_act = read_actuators(log, mech, o.log_columns, o.log_length_unit, o.log_angle_unit)
    stray = sorted({n for n in names if n not in tnames})
    if stray and not o.ignore_unknown_points:
        bad = [points.lines[i] for i, n in enumerate(names) if n not in tnames]
        raise ImportMatchError(
            f"{points.name}: points {stray} are not in {tgt.name} (targets {tnames}): lines "
            f"{_listing(bad)}; remove them or ignore them (--ignore-unknown-points)",
            points_lines=bad,
        )
    mode, owner, ids, max_dt = _assign(points, log, o)
    owner[[i for i, n in enumerate(names) if n not in tnames]] = -2  # ignored points
    lost = [points.lines[i] for i in np.flatnonzero(owner == -1)]
    if lost:
        raise ImportMatchError(
            f"{points.name}: {len(lost)} points have no controller-log row (matching by "
            f"{mode}{f', tolerance {o.tolerance} s' if mode == 'time' else ''}): lines "
            f"{_listing(lost)}",
            points_lines=lost,
        )
    empty = sorted(set(range(len(log.rows))) - set(owner.tolist()))
    if empty:
        lines = [log.lines[i] for i in empty]
        raise ImportMatchError(
            f"{log.name}: {len(empty)} rows have no tracker points (matching by {mode}): "
            f"lines {_listing(lines)} ({mode} {_listing([ids[i] for i in empty])})",
            log_lines=lines,
        )
    index = {n: j for j, n in enumerate(tnames)}
    out = np.full((len(log.rows), len(tnames), 3), np.nan)
    seen: dict[tuple[int, int], int] = {}
    for i, (r, n) in enumerate(zip(owner.tolist(), names, strict=True)):
        if r == -2:
            continue
        key = (r, index[n])
        if key in seen:
            raise ImportMatchError(
                f"{points.name}: target {shown(n)} measured twice for {mode} "
                f"{shown(ids[r])} (lines "
                f"{points.lines[seen[key]]} and {points.lines[i]}); delete one",
                points_lines=[points.lines[seen[key]], points.lines[i]],
            )
        seen[key] = i
        out[r, index[n]] = pts[i]
    holes = np.argwhere(np.isnan(out[:, :, 0]))
    if holes.size:
        msg = [f"{mode} {shown(ids[r])} (log line {log.lines[r]}): {tnames[j]}" for r, j in holes]
        raise ImportMatchError(
            f"{points.name}: targets missing: {_listing(msg)}",
            log_lines=sorted({log.lines[r] for r, _ in holes}),
        )
    data = TargetMeasurements(
        q_act=q_act,
        points=out,
        targets_local=local,
        names=tuple(tnames),
        frame=mech.measured_frame,
        actuated=tuple(mech.actuated),
        point_std=None if o.point_std is None else o.point_std / lf,
        max_residual=None if o.max_residual is None else o.max_residual / lf,
    )
    try:
        data.to_measurements()
    except PoseFitError as exc:
        r = exc.row - 1
        raise PoseFitError(
            f"{mode} {shown(ids[r])} (log line {log.lines[r]}): {exc}", exc.row
        ) from exc
    return TrackerImport(data, tuple(ids), log.lines, mode, max_dt)

"""The reading options of ``pincal import-tracker``, gathered into one :class:`TrackerArgs`.

:func:`tracker_options` adds ``--match`` … ``--ignore-unknown-points`` (with ``--out-unit``
among them, in the order ``--help`` lists) to a command, which receives their values as
one ``tracker`` argument.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from functools import wraps
from typing import TYPE_CHECKING, Any, TypeVar

import click

if TYPE_CHECKING:
    from pincal.io import TrackerImportOptions

__all__ = ["TrackerArgs", "tracker_options"]

_R = TypeVar("_R")


@dataclass(frozen=True)
class TrackerArgs:
    """The values of the reading options, as given (see ``pincal import-tracker --help``).

    Attributes:
        match: how points and log rows are paired (auto, pose, time).
        tolerance: largest point-to-log time difference [s].
        unit: length unit of points and targets (None: from the titles or m).
        log_length_unit: the log's prismatic joints' unit.
        log_angle_unit: the log's revolute joints' unit.
        columns: the points' column mapping ``field=Title,…``, or None.
        target_columns: the targets' column mapping, or None.
        log_columns: the log's column mapping, or None.
        delimiter: auto, ``,``, ``;`` or tab.
        decimal: auto, ``.`` or ``,``.
        point_std: 1σ per point coordinate [``unit``], or None.
        max_residual: moved-target threshold [``unit``], or None.
        out_unit: length unit of the written file.
        ignore_unknown_points: skip points that are not among the targets.
    """

    match: str
    tolerance: float
    unit: str | None
    log_length_unit: str
    log_angle_unit: str
    columns: str | None
    target_columns: str | None
    log_columns: str | None
    delimiter: str
    decimal: str
    point_std: float | None
    max_residual: float | None
    out_unit: str
    ignore_unknown_points: bool

    def options(self) -> TrackerImportOptions:
        """The reader's options, the column mappings parsed.

        Raises:
            MeasurementError: a column mapping item without ``=`` or a field given twice.
        """
        from pincal.io import TrackerImportOptions, parse_mapping

        return TrackerImportOptions(
            match=self.match,
            tolerance=self.tolerance,
            length_unit=self.unit,
            log_length_unit=self.log_length_unit,
            log_angle_unit=self.log_angle_unit,
            point_columns=parse_mapping(self.columns, "--columns"),
            target_columns=parse_mapping(self.target_columns, "--target-columns"),
            log_columns=parse_mapping(self.log_columns, "--log-columns"),
            delimiter=self.delimiter,
            decimal=self.decimal,
            point_std=self.point_std,
            max_residual=self.max_residual,
            ignore_unknown_points=self.ignore_unknown_points,
        )


_FIELDS = tuple(f.name for f in dataclasses.fields(TrackerArgs))


def tracker_options(func: Callable[..., _R]) -> Callable[..., _R]:
    """Add the reading options to a command; it receives them as one ``tracker`` argument."""

    @wraps(func)
    def wrapper(*args: object, **kwargs: Any) -> _R:
        tracker = TrackerArgs(**{name: kwargs.pop(name) for name in _FIELDS})
        return func(*args, tracker=tracker, **kwargs)

    options = [
        click.option("--match", type=click.Choice(["auto", "pose", "time"]), default="auto",
                     show_default=True, help="Pair points and log rows by pose id or time."),
        click.option("--tolerance", type=float, default=0.5, show_default=True,
                     help="Largest point-to-log time difference [s] (--match time)."),
        click.option("--unit", default=None,
                     help="Length unit of points and targets (m, mm, um)."),
        click.option("--log-length-unit", default="m", show_default=True,
                     help="Prismatic joints' unit."),
        click.option("--log-angle-unit", default="rad", show_default=True,
                     help="Revolute joints' unit."),
        click.option("--columns", default=None,
                     help="Points columns: field=Title,… (pose,time,point,x,y,z)."),
        click.option("--target-columns", default=None, help="Targets columns: field=Title,…."),
        click.option("--log-columns", default=None,
                     help="Log columns: field=Title,… (pose,time,joints)."),
        click.option("--delimiter", type=click.Choice(["auto", ",", ";", "tab"]),
                     default="auto", show_default=True),
        click.option("--decimal", type=click.Choice(["auto", ".", ","]), default="auto",
                     show_default=True),
        click.option("--point-std", type=float, default=None,
                     help="1σ per point coordinate [--unit]."),
        click.option("--max-residual", type=float, default=None,
                     help="Moved-target threshold [--unit]."),
        click.option("--out-unit", type=click.Choice(["m", "mm", "um"]), default="m",
                     show_default=True,
                     help="Length unit of the written file (m round-trips exactly)."),
        click.option("--ignore-unknown-points", is_flag=True,
                     help="Skip points that are not in --targets (e.g. base nests)."),
    ]  # fmt: skip
    for option in reversed(options):
        wrapper = option(wrapper)
    return wrapper

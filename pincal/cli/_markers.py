"""The marker-table options of the command line and the set-up they describe.

``pincal calibrate MODEL --link LINK --data TABLE`` reads TABLE as a marker table and
runs :func:`pincal.workflow.calibrate_markers` (registration, prior and loss settled by
the data, the joint fit, the gate judged by held-out prediction); this module turns the
options into a :class:`pincal.measure.MarkerSetup`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, TypeVar

import click

if TYPE_CHECKING:  # imported in the calls: the CLI starts without the model stack
    from pincal.identification import GateLimits
    from pincal.measure import MarkerSetup
    from pincal.workflow import MarkerSettings

_F = TypeVar("_F", bound=Callable[..., object])

__all__ = ["marker_options", "marker_settings", "marker_table_options", "setup_from_options"]

#: the --orientation conventions (pincal.measure.ORIENTATIONS, listed without importing it)
ORIENTATION_CHOICES = ("rpy-deg", "rpy-rad", "xyz-deg", "xyz-rad", "rotvec-deg", "rotvec-rad",
                       "quat-wxyz", "quat-xyzw")  # fmt: skip


def _apply(f: _F, opts: list[Callable[[Any], Any]]) -> _F:
    for opt in reversed(opts):
        f = opt(f)
    return f


def marker_table_options(f: _F) -> _F:
    """The options that read a marker table's positions (``pincal select-model``).

    ``--link``, ``--instrument-frame``, ``--marker``, ``--marker-columns``,
    ``--length-unit``: a command offers only the options it uses.
    """
    return _apply(f, _table_options())


def marker_options(f: _F) -> _F:
    """The marker-calibration options of ``pincal calibrate``.

    Those of :func:`marker_table_options`, a marker body's orientation and the prior.
    """
    return _apply(f, [*_table_options(), *_calibration_options()])


def _table_options() -> list[Callable[[Any], Any]]:
    return [
        click.option("--link", default=None, metavar="LINK[,LINK2…]",
                     help="Measured link carrying the marker: read --data as a marker table "
                     "(instrument-frame positions + joint columns). Markers on several "
                     "links (two arms): one link per --marker-columns set, comma-separated; "
                     "the chains to them are calibrated together, sharing the joints they "
                     "have in common."),
        click.option("--instrument-frame", type=click.Choice(["unknown", "known"]),
                     default="unknown", show_default=True,
                     help="unknown: registered in closed form, then identified; known: the "
                     "positions are in the robot's base frame."),
        click.option("--marker", "marker_spec", default="unknown", show_default=True,
                     metavar="unknown|X,Y,Z[,SIGMA]",
                     help="Marker in LINK's frame [mm]: unknown (identified), or given; "
                     "with SIGMA [mm] it is refined with that 1σ, without it held."),
        click.option("--marker-columns", default=("x,y,z",), show_default=True, multiple=True,
                     help="The marker's three position columns (e.g. x1,y1,z1). Several "
                     "markers on LINK: separate them by ';' or repeat the option "
                     "(x1,y1,z1;x2,y2,z2): fitted together, one instrument frame, an "
                     "unknown offset each; a marker exported twice is used once."),
        click.option("--length-unit", type=click.Choice(["m", "mm", "um"]), default="m",
                     show_default=True, help="Unit of the marker columns."),
    ]  # fmt: skip


def _calibration_options() -> list[Callable[[Any], Any]]:
    return [
        click.option("--orientation-columns", default=None, metavar="A,B,C[,D]",
                     help="A 6-D marker body: its orientation columns (e.g. roll,pitch,yaw, "
                     "or qw,qx,qy,qz): the body's pose on LINK is fitted, orientation "
                     "weighted by its own estimated noise. Needs --orientation."),
        click.option("--orientation", "orientation", default=None,
                     type=click.Choice(list(ORIENTATION_CHOICES)),
                     help="Convention of --orientation-columns: rpy = roll,pitch,yaw with "
                     "R = Rz(yaw)·Ry(pitch)·Rx(roll); xyz = Euler about moving x,y',z'' "
                     "(R = Rx·Ry·Rz); rotvec = axis×angle; in deg or rad; quat-wxyz / "
                     "quat-xyzw = unit quaternion, scalar first / last."),
        click.option("--prior", "prior_spec", default=None,
                     metavar="auto|none|LEN_MM,ANG_MRAD",
                     help="Gaussian prior on the machine's parameters about nominal (1σ) "
                     "[default: auto, its strength chosen by 5-fold cross-validation]."),
    ]  # fmt: skip


#: a given marker lies at most this far from its link's origin [m]
MAX_MARKER_M = 10.0


def _numbers(text: str, what: str, n: tuple[int, ...]) -> list[float]:
    try:
        vals = [float(v) for v in text.split(",")]
    except ValueError:
        vals = []
    if len(vals) not in n or not all(math.isfinite(v) for v in vals):
        raise click.BadParameter(f"expected {' or '.join(map(str, n))} numbers, got {text!r}",
                                 param_hint=what)  # fmt: skip
    return vals


def setup_from_options(link: str, frame: str, marker_spec: str, columns: str | tuple[str, ...],
                       unit: str, lock_spec: str | None = None,
                       orientation_columns: str | None = None,
                       orientation: str | None = None) -> MarkerSetup:  # fmt: skip
    """The :class:`pincal.measure.MarkerSetup` of the command-line options.

    ``columns``: ``--marker-columns`` (a text, or the texts of a repeated option), each
    ``X,Y,Z`` or several joined by ``;``. ``orientation_columns`` (``A,B,C[,D]``) and
    ``orientation``: a 6-D marker body's orientation columns and their convention.

    ``lock_spec`` (``JOINT=VALUE,…`` [m, rad]) is for the model options' ``--lock`` of
    the main line (h-arms); joints off the chain to ``link`` are locked at 0 anyway.
    """
    from pincal.measure import MarkerSetup

    marker = std = None
    if marker_spec != "unknown":
        vals = _numbers(marker_spec, "--marker", (3, 4))
        marker = tuple(v * 1e-3 for v in vals[:3])
        if math.hypot(*marker) > MAX_MARKER_M:
            raise click.BadParameter(
                f"the marker is {math.hypot(*vals[:3]):.3g} mm from the link's origin; a marker "
                f"lies within {MAX_MARKER_M * 1e3:.0f} mm of it (X,Y,Z in mm, in the link's "
                "frame), or give 'unknown'", param_hint="--marker")  # fmt: skip
        if len(vals) == 4:
            if not 1e-6 <= vals[3] <= 1000:
                raise click.BadParameter("the marker's σ lies between 1e-06 and 1000 mm, got "
                                         f"{vals[3]:g}", param_hint="--marker")  # fmt: skip
            std = vals[3] * 1e-3
    lock: dict[str, float] = {}
    for item in (lock_spec or "").split(","):
        if not item.strip():
            continue
        name, sep, value = item.partition("=")
        if not sep:
            raise click.BadParameter(f"{item!r} is not JOINT=VALUE", param_hint="--lock")
        lock[name.strip()] = _numbers(value, "--lock", (1,))[0]
    texts = (columns,) if isinstance(columns, str) else columns
    sets = []
    for text in (t for joined in texts for t in joined.split(";") if t.strip()):
        cols = tuple(c.strip() for c in text.split(","))
        if len(cols) != 3:
            raise click.BadParameter(f"give three columns per marker, got {text!r}",
                                     param_hint="--marker-columns")  # fmt: skip
        sets.append(cols)
    if not sets:
        raise click.BadParameter("no columns given", param_hint="--marker-columns")
    if len(sets) > 1 and marker is not None:
        raise click.BadParameter("a given --marker applies to one marker; with several "
                                 "--marker-columns every offset is unknown: use "
                                 "--marker unknown", param_hint="--marker")  # fmt: skip
    turned = tuple(c.strip() for c in (orientation_columns or "").split(",") if c.strip())
    if bool(turned) != (orientation is not None):
        raise click.BadParameter("give --orientation-columns and --orientation together (e.g. "
                                 "--orientation-columns roll,pitch,yaw --orientation rpy-deg)",
                                 param_hint="--orientation-columns")  # fmt: skip
    if turned and len(sets) > 1:
        raise click.BadParameter("orientation columns describe one marker body: give one set "
                                 "of --marker-columns with them",
                                 param_hint="--orientation-columns")  # fmt: skip
    links = [v.strip() for v in link.split(",") if v.strip()]
    if len(links) > 1 and len(links) != len(sets):
        raise click.BadParameter(f"{len(links)} links for {len(sets)} marker column sets: give "
                                 "one link per set (--link L1,L2 --marker-columns "
                                 "'x1,y1,z1;x2,y2,z2'), or one link for all",
                                 param_hint="--link")  # fmt: skip
    if not turned:
        return MarkerSetup(links[0], frame, marker, std, lock, sets[0], unit,  # type: ignore[arg-type]
                           tuple(sets[1:]), tuple(links[1:]))  # fmt: skip
    from pincal.errors import MeasurementError

    try:
        return MarkerSetup(link, frame, marker, std, lock, sets[0], unit,  # type: ignore[arg-type]
                           orientation_columns=turned, orientation=orientation)  # fmt: skip
    except MeasurementError as exc:
        raise click.BadParameter(str(exc), param_hint="--orientation-columns") from None


def marker_settings(preset: str | None, method: str, prior_spec: str | None, loss: str,
                    limits: GateLimits, instrument: str | None) -> MarkerSettings:  # fmt: skip
    """The :class:`pincal.workflow.MarkerSettings` of the command-line options.

    Raises:
        click.BadParameter: ``--prior`` is not auto, none or two positive numbers.
    """
    from pincal.errors import OptionValueError
    from pincal.workflow import MarkerSettings, parse_prior

    try:
        parse_prior(prior_spec)
    except OptionValueError as exc:
        raise click.BadParameter(str(exc), param_hint="--prior") from None
    return MarkerSettings(preset=preset or "chain", method=method, prior=prior_spec or "auto",
                          loss=loss, limits=limits, instrument=instrument)  # fmt: skip

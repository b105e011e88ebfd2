"""The options of ``pincal calibrate`` (the command's body is in :mod:`pincal.cli.calibrate`)."""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

import click

from pincal.cli._limits import yes_option
from pincal.cli._marker_root import root_option
from pincal.cli._markers import marker_options
from pincal.cli.common import jobs_option, model_options
from pincal.identification import METHODS

_F = TypeVar("_F", bound=Callable[..., object])

__all__ = ["calibrate_options"]

_OPTIONS = [
    click.option(
        "--data",
        required=True,
        multiple=True,
        type=click.Path(dir_okay=False),
        help="Measurement CSV (pincal measurements format); repeat it for several instrument "
        "files fitted together (e.g. socket files of one plate, several tool positions).",
    ),
    click.option(
        "--params", "preset", default=None, help="Parameter preset (default: first preset)."
    ),
    click.option(
        "--model",
        "error_model",
        default="geometric",
        show_default=True,
        help="Error model: 'geometric' or geometric+TERM[+TERM…] with TERM compliance (under "
        "gravity + payload; closed loops by their equilibrium), gain, harmonics: joint-space "
        "terms on every actuated joint, identified beside the geometric parameters; "
        "temperature: thermal expansion of each actuated joint's length (needs a per-pose "
        "temperature_C column, °C, that varies); strut-compliance: the axial yield of "
        "fixed-length struts (a hexaslide's) under the loop-closure forces.",
    ),
    click.option(
        "--payload",
        default=None,
        metavar="MASS[,X,Y,Z]",
        help="Payload on the tool during the measurements (kg; centre of mass in m in the tool "
        "frame), e.g. 20,0,0,0.1: part of the load a compliance term sees.",
    ),
    click.option(
        "--method",
        type=click.Choice(list(METHODS)),
        default="gauss-newton",
        show_default=True,
        help="Identification solver.",
    ),
    click.option(
        "--out",
        required=True,
        type=click.Path(file_okay=False),
        help="Calibration directory to write: calibration.json, calibrated.urdf + "
        "calibrated.yaml, identification.json, report.txt.",
    ),
    click.option(
        "--json",
        "as_json",
        is_flag=True,
        help="Print identification.json on stdout instead of the report.",
    ),
    click.option(
        "--noise",
        default=None,
        help="Instrument noise 1σ 'pos_mm,ori_mrad' (overrides the file's '# noise:'); "
        "default: the file's, else estimated from the residuals.",
    ),
    click.option(
        "--loss",
        type=click.Choice(["auto", "linear", "huber", "soft_l1", "cauchy"]),
        default=None,
        help="Robust loss (gauss-newton or lm); poses it down-weights are reported. Default: "
        "linear; with --link auto (least squares, then huber when the outlier test names poses).",
    ),
    click.option(
        "--force",
        is_flag=True,
        help="Write the calibration even when the quality gate refuses it (recorded).",
    ),
    click.option(
        "--max-change",
        default=None,
        metavar="MM,RAD",
        help="Quality gate: largest parameter change [default: 20,0.1].",
    ),
    click.option(
        "--significance",
        type=float,
        default=None,
        metavar="P",
        help="Quality gate: p-value below which the χ² test (declared noise) and the "
        "misspecification probes (scale, actuator gains, drift, coordinate trends) refuse "
        "[default: 1e-3].",
    ),
    click.option(
        "--instrument",
        "instrument",
        default=None,
        metavar="NAME",
        help="Instrument profile judging an estimated noise: laser-tracker, motion-capture, "
        "ballbar, touch-probe, cmm (overrides the file's '# instrument:').",
    ),
    click.option(
        "--bootstrap",
        "bootstrap",
        type=click.IntRange(min=0),
        default=0,
        metavar="N",
        help="Also run N parametric-bootstrap refits (e.g. 100) and report their σ beside the "
        "linear σ (calibration.json quality.uncertainty.bootstrap); never written as the "
        "covariance. Default: none (no refit runs after the fit).",
    ),
    jobs_option(
        "Processes of the --bootstrap refits (-1: every CPU); same σ for any value. Each "
        "worker loads pincal and rebuilds the model (seconds): worth it for long refits."
    ),
]


def calibrate_options(f: _F) -> _F:
    """Every option of ``pincal calibrate``, in the order ``--help`` lists them."""
    g: Callable[..., object] = yes_option(model_options(marker_options(root_option(f))))
    for opt in reversed(_OPTIONS):
        g = opt(g)
    return g  # type: ignore[return-value]

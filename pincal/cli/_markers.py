"""Marker calibrations from the command line: options, the fit, the prior's choice.

``pincal calibrate MODEL --link LINK --data TABLE`` reads TABLE as a marker table
(:func:`pincal.io.read_marker_data`: joint columns named as the URDF joints or
mapped, scaled and referenced by the model's sidecar; the marker's x, y, z columns
chosen by ``--marker-columns``; rows where a marker was not seen left out, said) and runs
:func:`pincal.identification.fit_markers`: closed-form registration of the instrument
frame and the marker, then the joint fit with its guards. ``--prior`` adds a Gaussian
prior on the machine's parameters (σ per class: lengths [mm], angles [mrad]); ``auto``
chooses its strength by 5-fold cross-validation on the calibration data (seed 0) among
:data:`PRIOR_GRID` and "no prior".
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, NamedTuple

import click

from pincal.errors import PincalError

__all__ = [
    "PRIOR_GRID",
    "MarkerCalibration",
    "marker_calibration",
    "marker_options",
    "parse_prior",
    "setup_from_options",
]

#: prior σ tried by ``--prior auto`` (the same number in mm for lengths and mrad for angles)
PRIOR_GRID = (0.3, 1.0, 3.0, 10.0)
#: registration RMS [m] beyond which the table does not describe the nominal robot
MISFIT_RMS = 0.02


def _misfit_note(rms: float) -> str:
    return (
        f"the registration leaves {rms * 1e3:.3g} mm RMS, more than {MISFIT_RMS * 1e3:g} mm: "
        "a nominal robot seen by a capture system fits to millimetres, so the table and the "
        "model disagree — check the joint columns (mapping, unit, reference pose: columns, "
        "joint_units, joint_reference), the joints locked and their values, the marker's link "
        "and the marker columns' unit"
    )


def marker_options(f: Callable[..., Any]) -> Callable[..., Any]:
    """The marker-calibration options of ``pincal calibrate``."""
    opts = [
        click.option("--link", default=None, metavar="LINK",
                     help="Measured link carrying the marker: read --data as a marker table "
                     "(instrument-frame positions + joint columns)."),
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
        click.option("--prior", "prior_spec", default=None, metavar="LEN_MM,ANG_MRAD|auto",
                     help="Gaussian prior on the machine's parameters about nominal (1σ); "
                     "auto: strength chosen by 5-fold cross-validation."),
    ]  # fmt: skip
    for opt in reversed(opts):
        f = opt(f)
    return f


def _numbers(text: str, what: str, n: tuple[int, ...]) -> list[float]:
    try:
        vals = [float(v) for v in text.split(",")]
    except ValueError:
        vals = []
    if len(vals) not in n or not all(math.isfinite(v) for v in vals):
        raise click.BadParameter(f"expected {' or '.join(map(str, n))} numbers, got {text!r}",
                                 param_hint=what)  # fmt: skip
    return vals


def parse_prior(spec: str | None) -> str | tuple[float, float] | None:
    """``None``, ``"auto"`` or (length [m], angle [rad]) from ``LEN_MM,ANG_MRAD``."""
    if spec is None or spec == "none":
        return None
    if spec == "auto":
        return "auto"
    a, b = _numbers(spec, "--prior", (2,))
    if a <= 0 or b <= 0:
        raise click.BadParameter("prior σ must be > 0 (or use 'auto')", param_hint="--prior")
    return a * 1e-3, b * 1e-3


def setup_from_options(link: str, frame: str, marker_spec: str, columns: str | tuple[str, ...],
                       unit: str, lock_spec: str | None = None):  # fmt: skip
    """The :class:`pincal.measure.MarkerSetup` of the command-line options.

    ``columns``: ``--marker-columns`` (a text, or the texts of a repeated option), each
    ``X,Y,Z`` or several joined by ``;``.

    ``lock_spec`` (``JOINT=VALUE,…`` [m, rad]) is for the model options' ``--lock`` of
    the main line (h-arms); joints off the chain to ``link`` are locked at 0 anyway.
    """
    from pincal.measure import MarkerSetup

    marker = std = None
    if marker_spec != "unknown":
        vals = _numbers(marker_spec, "--marker", (3, 4))
        marker = tuple(v * 1e-3 for v in vals[:3])
        if len(vals) == 4:
            if vals[3] <= 0:
                raise click.BadParameter("the marker's σ must be > 0 mm", param_hint="--marker")
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
    return MarkerSetup(link, frame, marker, std, lock, sets[0], unit,  # type: ignore[arg-type]
                       tuple(sets[1:]))  # fmt: skip


def _choose_prior(mech, setup, meas, preset: str, method: str, loss: str = "linear"):
    """(the prior with the lowest 5-fold held-out RMS, or None; the table tried [mm])."""
    from pincal.identification import Prior, cross_validate, fit_markers

    table: list[tuple[float | None, float]] = []
    best: tuple[float, Any] = (math.inf, None)
    for s in (None, *PRIOR_GRID):
        prior = None if s is None else Prior(s * 1e-3, s * 1e-3)

        def fit(m, prior=prior):
            return fit_markers(mech, setup, m, preset, method, prior, loss=loss).calibrated

        rms = cross_validate(fit, meas, 5, 0).rms
        table.append((s, rms * 1e3))
        if rms < best[0]:
            best = (rms, prior)
    return best[1], table


class MarkerCalibration(NamedTuple):
    """A marker calibration as :func:`marker_calibration` ran it.

    Attributes:
        fit: the fit (:class:`pincal.identification.MarkerFit`).
        meas: one measurement set per marker (copies of one marker left out).
        setup: the marker set-up fitted (copies left out).
        prior: the prior on the machine's parameters, or None.
        prior_cv: ``--prior auto``'s table (σ or None, held-out RMS [mm]), or None.
        doc: the ``markers`` entry of the manifest / identification.json: the setup,
            the registration, the prior (and the table of ``auto``), the notes.
    """

    fit: Any
    meas: Any
    setup: Any
    prior: Any
    prior_cv: list[tuple[float | None, float]] | None
    doc: dict


def marker_calibration(model: str, data: str, setup, preset: str | None, method: str,
                       prior_spec: str | None, loss: str = "linear",
                       progress: bool = True) -> MarkerCalibration:  # fmt: skip
    """Read the marker table, choose the prior, fit (see :class:`MarkerCalibration`).

    Copies of one marker are left out, said on stderr and in the notes.
    """
    from pincal.identification import Prior, fit_markers
    from pincal.io import distinct_markers, read_marker_data
    from pincal.measure import marker_mechanism

    setup, copies = distinct_markers(data, setup)
    mech = marker_mechanism(model, setup)
    read = read_marker_data(data, mech, setup)
    meas = read.sets
    copies = (*copies, *read.notes)
    for note in copies:
        click.echo(f"pincal: note: {note}", err=True)
    preset = preset or "chain"
    if preset not in mech.presets:
        raise click.BadParameter(f"preset {preset!r} unknown; marker calibrations have "
                                 f"{sorted(mech.presets)}", param_hint="--params")  # fmt: skip
    parsed = parse_prior(prior_spec)
    table = None
    prior = None
    if parsed == "auto":
        if progress:
            click.echo("… choosing the prior's strength by 5-fold cross-validation", err=True)
        prior, table = _choose_prior(mech, setup, meas, preset, method, loss)
    elif parsed is not None:
        prior = Prior(*parsed)  # type: ignore[misc]
    if progress:
        click.echo(f"… registering the instrument frame and {len(meas)} marker(s), then "
                   f"identifying from {len(meas[0])} poses", err=True)  # fmt: skip
    fit = fit_markers(mech, setup, meas, preset, method, prior, loss=loss)
    reg = fit.registration
    if reg.fit.rms > MISFIT_RMS:
        copies = (*copies, _misfit_note(reg.fit.rms))
        click.echo(f"pincal: warning: {copies[-1]}", err=True)
    doc = {
        **setup.to_dict(),
        "preset": preset,
        "method": method,
        "loss": loss,
        "prior_spec": prior_spec,
        "prior": None if prior is None else {"length_mm": prior.length * 1e3,
                                             "angle_mrad": prior.angle * 1e3},
        "prior_cv": None if table is None else [{"sigma": s, "held_out_rms_mm": r}
                                                for s, r in table],
        "registration": {
            "rms_mm": reg.fit.rms * 1e3,
            "iterations": reg.iterations,
            "marker_mm": [float(v) * 1e3 for v in reg.marker],
            "more_markers_mm": [[float(v) * 1e3 for v in m] for m in reg.more_markers],
            "instrument_translation_mm": [float(v) * 1e3
                                          for v in reg.T_instrument_base.translation],
        },
        "identified": _identified(fit, len(meas)),
        "solver": fit.method,
        "notes": [*copies, *fit.notes],
        "held_weak": list(fit.held_weak),
    }  # fmt: skip
    return MarkerCalibration(fit, meas, setup, prior, table, doc)


def _identified(fit, markers: int = 1) -> dict:
    """The refined instrument frame and marker(s) [mm, mrad] with 2σ where identified."""
    import pinocchio as pin

    from pincal.measure import marker_frame
    from pincal.model import BASE_JOINT, TOOL_JOINT

    res = fit.result
    joints = fit.calibrated.tree.joints
    two_sigma = dict(zip(res.identified_names, 2 * res.std, strict=True))

    def sig(prefix: str, dofs: str) -> list[float | None]:
        out = [two_sigma.get(f"{prefix}.{d}") for d in dofs.split()]
        return [None if v is None else float(v) * 1e3 for v in out]

    T = joints[BASE_JOINT].origin
    return {
        "instrument_translation_mm": [float(v) * 1e3 for v in T.translation],
        "instrument_rotation_rpy_mrad": [float(v) * 1e3 for v in pin.rpy.matrixToRpy(T.rotation)],
        "instrument_2sigma_mm_mrad": sig(BASE_JOINT, "tx ty tz rx ry rz"),
        "marker_mm": [float(v) * 1e3 for v in joints[TOOL_JOINT].origin.translation],
        "marker_2sigma_mm": sig(TOOL_JOINT, "tx ty tz"),
        "more_markers_mm": [
            [float(v) * 1e3 for v in joints[marker_frame(k)[0]].origin.translation]
            for k in range(1, markers)
        ],
        "more_markers_2sigma_mm": [sig(marker_frame(k)[0], "tx ty tz") for k in range(1, markers)],
    }


def rebuild(cal) -> tuple[Any, Any, Any]:
    """(setup, mechanism, measurements: one set per marker) of a marker calibration.

    Raises:
        PincalError: the data file is gone or changed.
    """
    from pincal.io import read_marker_sets, sha256_file
    from pincal.measure import MarkerSetup, marker_mechanism

    doc = cal.manifest.get("markers") or {}
    setup = MarkerSetup.from_dict(doc)
    files = cal.manifest.get("data_files") or []
    if not files:
        raise PincalError(f"{cal.path}: the calibration records no data file")
    path = files[0]["path"]
    try:
        changed = sha256_file(path) != files[0]["sha256"]
    except PincalError as exc:
        raise PincalError(f"cross-validation needs the fitted data file: {exc}") from exc
    if changed:
        raise PincalError(f"{path} changed since the calibration was written; re-run calibrate")
    mech = marker_mechanism(cal.model_source or cal.model, setup)
    return setup, mech, read_marker_sets(path, mech, setup)


def as_prior(doc: dict):
    """The fixed prior recorded in a marker calibration's doc, or None."""
    from pincal.identification import Prior

    p = doc.get("prior")
    return None if p is None else Prior(p["length_mm"] * 1e-3, p["angle_mrad"] * 1e-3)


def fold_fitter(mech, setup, doc: dict, registration_only: bool):
    """Measurements → calibrated mechanism, as calibrate ran (``auto`` re-chosen per fold)."""
    from pincal.identification import fit_markers

    preset, method = doc.get("preset", "chain"), doc.get("method", "gauss-newton")
    loss = doc.get("loss", "linear")

    def fit(meas):
        if registration_only:
            return fit_markers(mech, setup, meas, registration_only=True).calibrated
        prior = as_prior(doc)
        if doc.get("prior_spec") == "auto":  # nested: the held-out fold never chooses it
            prior, _ = _choose_prior(mech, setup, meas, preset, method, loss)
        return fit_markers(mech, setup, meas, preset, method, prior, loss=loss).calibrated

    return fit

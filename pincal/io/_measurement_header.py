"""The header lines of a measurement file that are not units: components, noise, instrument.

See :mod:`pincal.io._measurement_file` for the format (``# components:``, ``# noise:``,
``# instrument:``).
"""

from __future__ import annotations

from pincal._yaml import shown
from pincal.errors import MeasurementFormatError, UnknownNameError
from pincal.identification import INSTRUMENT_PROFILES, instrument_profile
from pincal.io._csv import Header, header_value
from pincal.io._names import is_decimal, is_non_finite
from pincal.measure import NoiseModel
from pincal.model import COMPONENTS

__all__ = [
    "MAX_COORDINATE",
    "NOISE_RANGE",
    "length_sigma",
    "parse_components",
    "parse_instrument",
    "parse_noise",
]


def parse_components(header: Header, name: str) -> list[str]:
    """The header's ``components`` in canonical order (default all six)."""
    comps = header_value(header, "components", "x y z rx ry rz", name).split()
    bad = [c for c in comps if c not in COMPONENTS]
    if bad or not comps or len(set(comps)) != len(comps):
        raise MeasurementFormatError(
            f"{name}: components {shown(comps)} invalid; choose distinct names from {COMPONENTS}"
        )
    return [c for c in COMPONENTS if c in comps]


#: largest |measured coordinate| [m]: beyond, a cell is a typo (and spreads overflow)
MAX_COORDINATE = 1e4

#: a declared noise σ [mm, mrad] is 0 or in this range (1 nm .. 1 m)
NOISE_RANGE = (1e-6, 1e3)


def length_sigma(value: float, what: str, lf: float, name: str) -> float:
    """A declared 1σ length [m] of a file header, within :data:`NOISE_RANGE`.

    Args:
        value: the σ as written (> 0, finite), in the file's length unit.
        what: where the σ was given, for the message (``header 'std'``, ``--std``).
        lf: the file's length unit per metre.
        name: file name.

    Raises:
        MeasurementFormatError: outside 1 nm … 1 m (the weights would under- or
            overflow: a σ of 1e300 leaves nothing fitted).
    """
    lo, hi = NOISE_RANGE
    sigma = value / lf
    if not lo <= sigma * 1e3 <= hi:
        raise MeasurementFormatError(
            f"{name}: {what} is {value:g} in its length unit, {sigma * 1e3:g} mm; a 1σ must be "
            f"between {lo:g} and {hi:g} mm (a σ outside makes the weights under- or "
            "overflow); check the value and the length unit"
        )
    return sigma


def parse_noise(header: Header, name: str) -> NoiseModel | None:
    """The header's ``noise position_mm=σ orientation_mrad=σ`` as a NoiseModel, or None."""
    if "noise" not in header:
        return None
    vals = {}
    for item in header_value(header, "noise", None, name).split():
        key, _, v = item.partition("=")
        if key not in ("position_mm", "orientation_mrad"):
            raise MeasurementFormatError(
                f"{name}: noise entry {shown(item)}; use position_mm=<σ> orientation_mrad=<σ>"
            )
        if not (is_decimal(v) or is_non_finite(v)):
            raise MeasurementFormatError(
                f"{name}: noise entry {shown(item)} is not a number; write e.g. position_mm=0.01"
            )
        sigma = float(v)
        lo, hi = NOISE_RANGE
        if not (sigma == 0 or lo <= sigma <= hi):
            raise MeasurementFormatError(
                f"{name}: noise entry {shown(item)} must be 0 or between {lo:g} and {hi:g} "
                "(mm, mrad); a σ outside makes the weights under- or overflow"
            )
        vals[key.split("_")[0]] = sigma
    return NoiseModel(vals.get("position", 0.0), vals.get("orientation", 0.0))


def parse_instrument(header: Header, name: str) -> str | None:
    """The header's ``instrument`` as a registered profile name, or None."""
    if "instrument" not in header:
        return None
    value = header_value(header, "instrument", None, name)
    try:
        return instrument_profile(value).name
    except UnknownNameError:
        raise MeasurementFormatError(
            f"{name}: instrument {shown(value)} unknown; use one of "
            f"{', '.join(INSTRUMENT_PROFILES)} (or remove the '# instrument:' line)"
        ) from None

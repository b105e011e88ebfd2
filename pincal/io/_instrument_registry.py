"""The instrument file kinds: header magic → reader (one line per kind).

A file whose first line is ``# pincal <kind> 1`` with ``<kind>`` a key of
:data:`INSTRUMENT_FILES` is read by its reader into a dataset of the joint instrument
identification (:func:`pincal.identification.identify_instruments`).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from pincal.errors import MeasurementFormatError
from pincal.io._csv import file_kind
from pincal.io._instrument_file import read_instrument_data
from pincal.io._socket_file import read_socket_data
from pincal.measure import Artefact, InstrumentData
from pincal.model import Mechanism

__all__ = ["INSTRUMENT_FILES", "is_instrument_file", "read_instrument_file"]

#: header magic → reader(path, mech) of that instrument's dataset
INSTRUMENT_FILES: dict[str, Callable[[str | Path, Mechanism], InstrumentData | Artefact]] = {
    "instrument": read_instrument_data,
    "sockets": read_socket_data,
}


def is_instrument_file(path: str | Path) -> bool:
    """True when ``path`` starts with the header of an instrument file kind."""
    return file_kind(path) in INSTRUMENT_FILES


def read_instrument_file(path: str | Path, mech: Mechanism) -> InstrumentData | Artefact:
    """The dataset of an instrument file of any registered kind.

    Raises:
        MeasurementFormatError: not an instrument file (the kinds are named); the
            reader's own errors for a bad file.
    """
    kind = file_kind(path)
    if kind not in INSTRUMENT_FILES:
        raise MeasurementFormatError(
            f"{Path(path).name} is not an instrument file (kind {kind!r}); its first line must "
            f"be '# pincal <kind> 1' with kind one of {sorted(INSTRUMENT_FILES)}"
        )
    return INSTRUMENT_FILES[kind](path, mech)

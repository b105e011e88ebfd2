"""The environment, read once per command: the ``PINCAL_MAX_*`` size limits.

The library never reads the environment (:mod:`pincal._limits`); every command runs
under the limits built here from ``PINCAL_MAX_FILE_MB`` (megabytes in (0, 10⁹]) and
``PINCAL_MAX_LINKS``, ``PINCAL_MAX_DOF``, ``PINCAL_MAX_TREE_DEPTH``,
``PINCAL_MAX_PARAMETERS`` (positive integers). A variable that is unset or empty keeps
the library default.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from pincal._limits import DEFAULT_MAX_BYTES, ENVIRONMENT, Limits
from pincal.errors import InputLimitError, clip

__all__ = ["limits_from_environment"]

_MAX_MB = 1e9  # PINCAL_MAX_FILE_MB above one petabyte is a typo


def limits_from_environment(environ: Mapping[str, str]) -> Limits:
    """The limits the variables of ``environ`` set, library defaults for the others.

    Args:
        environ: the environment (``os.environ`` at the command line).

    Raises:
        InputLimitError: a variable is malformed (the message says what is valid).
    """
    default = Limits()
    values: dict[str, int] = {}
    for field, name in ENVIRONMENT.items():
        text = environ.get(name)
        if not text:
            continue
        if field == "file_bytes":
            values[field] = _megabytes(name, text)
            continue
        try:
            value = int(text)
        except ValueError:
            value = 0
        if value < 1:
            fallback = getattr(default, field)
            raise InputLimitError(
                f"{name}={clip(text)} must be a positive integer (default {fallback})"
            )
        values[field] = value
    return Limits(**values)


def _megabytes(name: str, text: str) -> int:
    try:
        mb = float(text)
    except ValueError:
        mb = math.nan
    if not 0 < mb <= _MAX_MB:  # also refuses nan and inf
        raise InputLimitError(
            f"{name}={clip(text)} is not a number of megabytes in (0, {_MAX_MB:.0f}]; set it "
            f"to e.g. 500 or unset it (default {DEFAULT_MAX_BYTES // 2**20})"
        )
    return max(1, int(mb * 1024 * 1024))

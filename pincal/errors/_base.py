"""The root of pincal's errors and the bounded text of user values in their messages."""

from __future__ import annotations

import reprlib
from collections.abc import Iterable

__all__ = [
    "PincalError",
    "clip",
    "listing",
]


class PincalError(Exception):
    """Root of all pincal errors."""


def clip(value: object, limit: int = 80, *, quote: bool = False) -> str:
    """Return bounded text of a user value for a message, at most ``limit`` characters.

    Every user-supplied value that goes into a message passes through here, so a
    huge or hostile value (a YAML alias bomb, a 10 MB CSV cell, a 5 000-digit integer)
    cannot make the message itself huge or slow. Strings are shown as they are, with
    control characters escaped (quoted with ``quote=True``); other values by a ``repr``
    bounded in depth and item count (:mod:`reprlib`).

    Args:
        value: anything.
        limit: maximum length of the returned text, in characters.
        quote: put strings in single quotes (as ``repr`` would).

    Returns:
        The text, ending in "… (N chars)" when cut.
    """
    value = _plain(value, limit)
    if isinstance(value, str):
        text = value.encode("unicode_escape", "backslashreplace").decode("ascii", "replace")
        if quote:
            text = "'" + text.replace("'", "\\'") + "'"
    elif isinstance(value, int) and not isinstance(value, bool) and value.bit_length() > 128:
        text = f"<integer of ~{int(value.bit_length() * 0.30103) + 1} digits>"
    elif isinstance(value, (list, tuple, set, dict)) and len(value) > limit:
        text = f"<{type(value).__name__} of {len(value)} items>"
    else:
        short = reprlib.Repr()
        short.maxlevel, short.maxstring, short.maxother = 3, limit, limit
        try:
            text = short.repr(value)
        except ValueError:  # an integer too long to print, nested somewhere
            text = f"<{type(value).__name__}>"
    if len(text) <= limit:
        return text
    tail = f"… ({len(text)} chars)"
    return text[: max(limit - len(tail), 1)] + tail


def _plain(value: object, limit: int, depth: int = 3) -> object:
    """``value`` with numpy scalars and small arrays as Python numbers and lists.

    A message shows ``0.5``, not ``np.float64(0.5)`` (numpy 2's repr), also inside
    tuples and lists (to ``depth`` levels, containers of at most ``limit`` items).
    """
    module = type(value).__module__
    if module == "numpy" or module.startswith("numpy."):
        item, size = getattr(value, "item", None), getattr(value, "size", limit + 1)
        if getattr(value, "ndim", None) == 0 and callable(item):
            return item()
        to_list = getattr(value, "tolist", None)
        if callable(to_list) and isinstance(size, int) and size <= limit:
            return to_list()
        return value
    if depth and isinstance(value, (list, tuple)) and len(value) <= limit:
        plain = [_plain(v, limit, depth - 1) for v in value]
        return plain if isinstance(value, list) else tuple(plain)
    return value


def listing(names: Iterable[str], limit: int = 40) -> str:
    """Return the names quoted and comma-separated, at most ``limit`` of them.

    Args:
        names: the names to show, in order.
        limit: how many to show; the rest are counted ("… (N more)").
    """
    names = list(names)
    shown = ", ".join(repr(n) for n in names[:limit])
    if len(names) > limit:
        shown += f", … ({len(names) - limit} more)"
    return shown

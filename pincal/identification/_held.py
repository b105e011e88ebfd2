"""What a fit held at nominal although the analysis calls it identifiable, and why.

A fit may hold identifiable parameters at their nominal values: the directions the
declared noise places only beyond :data:`pincal.sensitivity.PLACEMENT_BOUND` (a pose
file's :class:`WeakBound`) or the parameters whose marginal σ a marker fit finds beyond
its bound. The result records them in ``annotations[HELD_AT_NOMINAL]`` — ``{"names":
[...], "reason": "..."}`` — written with ``identification.json`` and read back, so the
``identifiable:`` line of ``report.txt`` and the report's parameter section say them in
one form on every route (:func:`held_summary`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from typing import Any, TypeVar

from pincal.identification.results import IdentificationRecord

__all__ = ["HELD_AT_NOMINAL", "held_at_nominal", "held_summary", "with_held"]

#: the annotation key of the parameters a fit held at nominal although identifiable
HELD_AT_NOMINAL = "held_at_nominal"

R = TypeVar("R", bound=IdentificationRecord)


def with_held(result: R, names: Sequence[str], reason: str) -> R:
    """``result`` (an identification record) with ``names`` recorded as held, and why.

    Args:
        result: an :class:`pincal.identification.IdentificationRecord` (or result).
        names: the parameters held at nominal although identifiable (none: unchanged).
        reason: why, as a phrase (e.g. ``"placed beyond 20 mm / 0.1 rad (1σ) by the
            poses"``).
    """
    if not names:
        return result
    notes = dict(result.annotations)
    notes[HELD_AT_NOMINAL] = {"names": list(names), "reason": reason}
    return dataclasses.replace(result, annotations=notes)


def held_at_nominal(annotations: Mapping[str, Any]) -> tuple[tuple[str, ...], str]:
    """(names, reason) of the parameters held at nominal; ``((), "")`` when none."""
    entry = annotations.get(HELD_AT_NOMINAL)
    if not isinstance(entry, Mapping):
        return (), ""
    names = tuple(str(n) for n in entry.get("names") or ())
    return names, str(entry.get("reason") or "")


def held_summary(annotations: Mapping[str, Any], shown: int = 3) -> str:
    """The held parameters in one phrase ("" when nothing was held).

    ``"2 held at nominal: REASON — a.tx, b.ry"``, at most ``shown`` names, then "and K
    more".
    """
    names, reason = held_at_nominal(annotations)
    if not names:
        return ""
    listed = ", ".join(names[:shown])
    if len(names) > shown:
        listed += f" and {len(names) - shown} more"
    return f"{len(names)} held at nominal: {reason} — {listed}"

"""``pincal import-sockets``'s option strings (``--distance``, ``--ball``) parsed into values."""

from __future__ import annotations

import click

__all__ = ["parse_ball", "parse_distance"]


def parse_distance(text: str) -> tuple[str, str, float, float]:
    """``A,B,VALUE,STD`` → (A, B, value, std) (lengths in --length-unit).

    Raises:
        click.BadParameter: not four fields, or the last two not numbers.
    """
    parts = [p.strip() for p in text.split(",")]
    try:
        if len(parts) != 4 or not all(parts):
            raise ValueError
        return parts[0], parts[1], float(parts[2]), float(parts[3])
    except ValueError:
        raise click.BadParameter(
            f"{text!r}: write A,B,DISTANCE,STD (two socket ids, the calibrated distance "
            "and its 1σ in --length-unit), e.g. 1,2,50,0.002",
            param_hint="--distance",
        ) from None


def parse_ball(text: str) -> tuple[float, float, float] | None:
    """``--ball``: ``X,Y,Z`` → (x, y, z) (lengths in --length-unit), ``unknown`` → None.

    Raises:
        click.BadParameter: neither ``unknown`` nor three numbers.
    """
    if text.strip() == "unknown":
        return None
    try:
        x, y, z = (float(v) for v in text.split(","))
    except ValueError:
        raise click.BadParameter(
            f"{text!r}: give 'unknown' or X,Y,Z", param_hint="--ball"
        ) from None
    return (x, y, z)

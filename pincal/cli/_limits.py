"""Checked numeric options: finite, positive, integer, and bounded unless ``--yes``.

Every numeric option of the CLI passes through here before any work, so a value
like ``inf``, ``-1`` or ``1e8`` poses ends in one line naming the option, the value
and what is valid (exit code 1), never in a traceback, a hang or a MemoryError.
Sizes past a stated bound (:data:`MAX_POSES`, the candidate bounds of
:mod:`pincal.design`) are refused unless the user passes ``--yes``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any, TypeVar

import click

from pincal.errors import InputLimitError, OptionValueError, clip

__all__ = [
    "MAX_POSES",
    "MAX_RESTARTS",
    "check_count",
    "check_data_rows",
    "check_number",
    "naming_option",
    "number_pair",
    "yes_option",
]

#: most poses a command simulates, samples or selects without ``--yes``
MAX_POSES = 100_000
#: most random restarts of a pose selection without ``--yes``
MAX_RESTARTS = 1_000

F = TypeVar("F", bound=Callable[..., Any])


def yes_option(func: F) -> F:
    """The ``--yes`` flag: go ahead past the stated size bounds."""
    return click.option(
        "--yes",
        is_flag=True,
        help="Go ahead past the stated size bounds (candidate count and memory, "
        f"{MAX_POSES} poses); without it such requests are refused with an estimate.",
    )(func)


#: cost of a fit, measured (wedge3, 20 000 poses: 16 s, 211 MB; hexaslide_6pus, 5 000
#: poses: 14 s, 297 MB): about 0.1 ms per pose and parameter, 150 bytes per Jacobian entry
_FIT_S_PER_ROW_PARAM = 1e-4
_FIT_BYTES_PER_ENTRY = 150


def check_data_rows(path: str, option: str, n_params: int, yes: bool) -> int | None:
    """Refuse a data file of more than :data:`MAX_POSES` rows unless ``yes``.

    The rows are counted (data lines after the column titles) before the file is
    parsed; the message estimates the fit's time and memory (for ``n_params`` > 0).

    Returns:
        The row count, or None when the file cannot be read (its reader says why).

    Raises:
        InputLimitError: more rows than the bound without ``--yes``.
    """
    from pincal._files import read_bytes
    from pincal.errors import PincalError

    try:
        data = read_bytes(path, "data file")
    except PincalError:
        return None
    lines = (ln for ln in data.splitlines() if ln.strip() and not ln.lstrip().startswith(b"#"))
    rows = max(0, sum(1 for _ in lines) - 1)
    if rows > MAX_POSES and not yes:
        seconds = rows * n_params * _FIT_S_PER_ROW_PARAM
        gb = rows * 6 * n_params * _FIT_BYTES_PER_ENTRY / 1e9
        cost = (
            f"; with {n_params} parameters the fit would take about {seconds:.0f} s and "
            f"{gb:.1f} GB of memory"
            if n_params > 0
            else ""
        )
        raise InputLimitError(
            f"{option} {clip(path, 300)} has {rows} poses, over the {MAX_POSES} fitted without "
            f"--yes{cost}; pass --yes to fit it anyway, or use a subset of the poses"
        )
    return rows


def check_number(
    value: float | None, option: str, *, positive: bool = False, minimum: float = 0.0
) -> float | None:
    """A finite number ≥ ``minimum`` (> 0 with ``positive``); None passes.

    Raises:
        OptionValueError: naming the option, the value and what is valid.
    """
    if value is None:
        return None
    ok = isinstance(value, (int, float)) and math.isfinite(value)
    ok = ok and (value > 0 if positive else value >= minimum)
    if not ok:
        valid = "a finite number > 0" if positive else f"a finite number >= {minimum:g}"
        raise OptionValueError(f"{option} {clip(value)} is not valid; give {valid}")
    return float(value)


#: range of a noise σ [mm, mrad] (1 nm .. 1 m): outside it, weights under/overflow
NOISE_RANGE = (1e-6, 1e3)
#: range of a simulated error bound [mm, mrad]
ERROR_SIZE_RANGE = (1e-6, 1e3)


def number_pair(
    spec: str,
    option: str,
    *,
    positive: bool = False,
    form: str = "a,b",
    bounds: tuple[float, float] | None = None,
) -> tuple[float, float]:
    """Parse ``'a,b'`` into two finite numbers ≥ 0 (> 0 with ``positive``).

    ``form`` names the two numbers in the message (e.g. ``"pos_mm,ori_mrad"``).
    ``bounds`` (lo, hi): each number must lie in [lo, hi] (or be 0 without ``positive``).

    Raises:
        OptionValueError: not two numbers, or one is not finite / negative / out of bounds.
    """
    parts = str(spec).split(",")
    try:
        a, b = (float(v) for v in parts)
    except ValueError:
        raise OptionValueError(
            f"{option} {clip(spec)}: expected two numbers '{form}', e.g. 0.01,0.05"
        ) from None
    for v in (a, b):
        if not math.isfinite(v) or (v <= 0 if positive else v < 0):
            valid = "> 0" if positive else ">= 0"
            raise OptionValueError(
                f"{option} {clip(spec)}: both numbers '{form}' must be finite and {valid}"
            )
        if bounds is not None and v != 0 and not bounds[0] <= v <= bounds[1]:
            zero = "" if positive else "0 or "
            raise OptionValueError(
                f"{option} {clip(spec)}: both numbers '{form}' must be {zero}between "
                f"{bounds[0]:g} and {bounds[1]:g}; got {v:g}"
            )
    return a, b


def check_count(
    value: int | None, option: str, bound: int, yes: bool, *, least: int = 1, what: str = "poses"
) -> int | None:
    """An integer ≥ ``least`` and ≤ ``bound`` unless ``yes``; None passes.

    Raises:
        OptionValueError: not an integer ≥ ``least``.
        InputLimitError: past ``bound`` without ``--yes`` (naming both).
    """
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int) or value < least:
        raise OptionValueError(f"{option} {clip(value)} is not valid; give an integer >= {least}")
    if value > bound and not yes:
        raise InputLimitError(
            f"{option} {value} asks for {value} {what}; the bound is {bound}: give a smaller "
            f"number or pass --yes to go ahead"
        )
    return value


@contextmanager
def naming_option(option: str) -> Iterator[None]:
    """Prefix the option to a limit or value error of the library call inside.

    Raises:
        InputLimitError, OptionValueError: as raised inside, with "OPTION: " in front.
    """
    try:
        yield
    except (InputLimitError, OptionValueError) as exc:
        raise type(exc)(f"{option} {exc}") from exc

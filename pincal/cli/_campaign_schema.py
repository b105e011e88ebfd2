"""Typed reading of campaign-file sections: YAML data → frozen dataclasses.

:func:`build` makes a dataclass from a mapping by its type hints (nested dataclasses,
optional values, tuples, ``dict[str, T]``, bool/int/float/str); every error names the
key path (``measurements.noise``) and an unknown key suggests the nearest valid one.
The sections themselves and their checks: :mod:`pincal.cli._campaign`.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import types
import typing
from typing import TYPE_CHECKING, Any, TypeVar

from pincal._yaml import shown
from pincal.errors import CampaignError

if TYPE_CHECKING:
    from _typeshed import DataclassInstance

_T = TypeVar("_T", bound="DataclassInstance")

__all__ = ["build", "choice"]


def choice(value: str, valid: tuple[str, ...], key: str) -> None:
    """Refuse ``value`` unless one of ``valid``, suggesting the nearest (``key``: its path)."""
    if value not in valid:
        same = [v for v in valid if v.lower() == str(value).lower()]
        near = same or difflib.get_close_matches(str(value), valid, n=1)
        hint = f" (did you mean {near[0]!r}?)" if near else ""
        raise CampaignError(
            f"{key}: {shown(value)} is not valid{hint}; use one of {', '.join(valid)}"
        )


def _type_name(tp: object) -> str:
    return getattr(tp, "__name__", str(tp))


def _looks_numeric(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _coerce(value: Any, tp: Any, key: str) -> Any:
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        inner = [a for a in typing.get_args(tp) if a is not type(None)]
        if value is None:
            return None
        return _coerce(value, inner[0], key)
    if isinstance(tp, type) and dataclasses.is_dataclass(tp):
        return build(tp, value, key)
    if origin is dict:
        _, vt = typing.get_args(tp)
        if not isinstance(value, dict):
            raise CampaignError(f"{key}: expected a mapping NAME: VALUE, got {shown(value)}")
        return {str(k): _coerce(v, vt, f"{key}.{k}") for k, v in value.items()}
    if origin is tuple:
        args = typing.get_args(tp)
        if len(args) == 2 and args[1] is Ellipsis:  # any length
            if not isinstance(value, (list, tuple)):
                raise CampaignError(f"{key}: expected a list, got {shown(value)}")
            return tuple(_coerce(v, args[0], f"{key}[{k}]") for k, v in enumerate(value))
        if not isinstance(value, (list, tuple)) or len(value) != len(args):
            raise CampaignError(
                f"{key}: expected a list of {len(args)} numbers, got {shown(value)}"
            )
        return tuple(
            _coerce(v, a, f"{key}[{k}]") for k, (v, a) in enumerate(zip(value, args, strict=True))
        )
    ok = {
        bool: isinstance(value, bool),
        int: isinstance(value, int) and not isinstance(value, bool),
        float: isinstance(value, (int, float)) and not isinstance(value, bool),
        str: isinstance(value, str),
    }.get(tp, False)
    if not ok:
        hint = ""
        if tp in (int, float) and isinstance(value, str) and _looks_numeric(value):
            r = repr(float(value))
            r = r.replace("e", ".0e") if "e" in r and "." not in r else r
            hint = f" (YAML reads an exponent without '.' or sign as text: write {r})"
        raise CampaignError(f"{key}: expected {_type_name(tp)}, got {shown(value)}{hint}")
    if tp is float:
        try:
            number = float(value)
        except OverflowError:
            number = math.inf
        if not math.isfinite(number):
            raise CampaignError(f"{key}: expected a finite number, got {shown(value)}")
        return number
    return value


def build(cls: type[_T], data: object, key: str) -> _T:
    """An instance of the dataclass ``cls`` from YAML ``data``; ``key`` is its path ('' at the top).

    Every key is checked: an unknown one suggests the nearest valid key; a value of the
    wrong type names its key path (``measurements.noise``).

    Raises:
        CampaignError: unknown or missing key, wrong type, non-finite number.
    """
    where = key or "campaign file"
    if data is None:
        data = {}
    if not isinstance(data, dict):
        raise CampaignError(f"{where}: expected a mapping of keys, got {shown(data)}")
    hints = typing.get_type_hints(cls)
    valid = [f.name for f in dataclasses.fields(cls)]
    for name in data:
        if name not in valid:
            near = difflib.get_close_matches(str(name), valid, n=1, cutoff=0.5)
            hint = f"did you mean {near[0]!r}? " if near else ""
            raise CampaignError(
                f"{where}: unknown key {name!r}; {hint}valid keys are {', '.join(valid)}"
            )
    kwargs = {}
    for f in dataclasses.fields(cls):
        sub = f"{key}.{f.name}" if key else f.name
        if f.name in data:
            kwargs[f.name] = _coerce(data[f.name], hints[f.name], sub)
        elif f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            raise CampaignError(f"{where}: key {f.name!r} is required")
    return cls(**kwargs)

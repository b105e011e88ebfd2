"""Values of locked joints: ``lock:`` mappings of sidecars and robot files."""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from pincal._yaml import shown
from pincal.errors import ModelFileError

__all__ = ["lock_values", "lock_values_at_home"]


def lock_values(v: Any, where: str) -> dict[str, float | str]:
    """A ``lock`` mapping checked: joint name → value [rad or m] or ``"home"``."""
    if v is None:
        return {}
    if not isinstance(v, Mapping):
        raise ModelFileError(f"{where} 'lock' must map joint names to values [rad, m]: {shown(v)}")
    out: dict[str, float | str] = {}
    for name, value in v.items():
        if value == "home":
            out[str(name)] = "home"
            continue
        number = isinstance(value, int | float) and not isinstance(value, bool)
        if not number or not math.isfinite(value):
            raise ModelFileError(
                f"{where} lock[{shown(name)}] must be a finite number or 'home', got {shown(value)}"
            )
        out[str(name)] = float(value)
    return out


def lock_values_at_home(lock: Mapping[str, float | str], home: Any) -> dict[str, float]:
    """Lock values with ``"home"`` replaced by the joint's home value (else 0) [rad or m]."""
    home = home if isinstance(home, Mapping) else {}
    out = {}
    for name, value in lock.items():
        if value == "home":
            h = home.get(name, 0.0)
            value = h[0] if isinstance(h, list | tuple) else h
        out[name] = float(value)
    return out

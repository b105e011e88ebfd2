"""Checked inputs of a view: configurations, error arrows, colours, the up direction."""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from pincal.errors import VisualizationError

__all__ = [
    "UP_DIRECTIONS",
    "Arrow",
    "check_inputs",
    "hex_colour",
    "parse_colour",
    "up_rotation",
]


@dataclass(frozen=True)
class Arrow:
    """An error arrow from ``start`` to ``end`` (world frame, [m], shape (3,)).

    ``colour`` is ``"#rrggbb"``, an ``(r, g, b)`` tuple in [0, 1] or an int
    ``0xRRGGBB``. The drawn arrow is ``start → start + scale·(end − start)``.
    """

    start: np.ndarray
    end: np.ndarray
    colour: Any = "#d62728"
    label: str = ""


def _as_configurations(model: pin.Model, configurations: Any) -> list[np.ndarray]:
    if isinstance(configurations, np.ndarray) and configurations.ndim == 1:
        configurations = [configurations]
    qs = [np.asarray(q, dtype=float) for q in configurations]
    if not qs:
        raise VisualizationError("no configurations given; expected at least one of shape (nq,)")
    for k, q in enumerate(qs):
        if q.shape != (model.nq,):
            raise VisualizationError(
                f"configuration {k} has shape {q.shape}; expected ({model.nq},) (model.nq)"
            )
        if not np.all(np.isfinite(q)):
            raise VisualizationError(f"configuration {k} contains NaN or inf")
    return qs


#: world direction shown pointing up → rotation R_view_world mapping it to +z
_UP_ROTATIONS = {
    "+z": np.eye(3),
    "-z": np.diag([1.0, -1.0, -1.0]),  # 180° about x
    "+y": np.array([[1.0, 0, 0], [0, 0, -1], [0, 1, 0]]),  # +90° about x: y → z
    "-y": np.array([[1.0, 0, 0], [0, 0, 1], [0, -1, 0]]),
    "+x": np.array([[0.0, 0, -1], [0, 1, 0], [1, 0, 0]]),  # x → z about y
    "-x": np.array([[0.0, 0, 1], [0, 1, 0], [-1, 0, 0]]),
}
UP_DIRECTIONS: tuple[str, ...] = tuple(_UP_ROTATIONS)


def up_rotation(up: str) -> np.ndarray:
    """Rotation (3, 3) from world to view coordinates that makes world ``up`` point up."""
    key = str(up).strip().lower()
    if key in ("x", "y", "z"):
        key = "+" + key
    if key not in _UP_ROTATIONS:
        raise VisualizationError(f"up {up!r} not understood; use one of {', '.join(UP_DIRECTIONS)}")
    return _UP_ROTATIONS[key]


def parse_colour(colour: Any) -> tuple[float, float, float]:
    """RGB in [0, 1] from ``#rrggbb``, a 0xRRGGBB integer or three floats (ValueError otherwise)."""
    if isinstance(colour, str) and re.fullmatch(r"#?[0-9a-fA-F]{6}", colour):
        h = colour.lstrip("#")
        return tuple(int(h[i : i + 2], 16) / 255.0 for i in (0, 2, 4))  # type: ignore[return-value]
    if isinstance(colour, (int, np.integer)) and 0 <= int(colour) <= 0xFFFFFF:
        c = int(colour)
        return ((c >> 16 & 255) / 255.0, (c >> 8 & 255) / 255.0, (c & 255) / 255.0)
    try:
        rgb = tuple(float(x) for x in colour)
    except (TypeError, ValueError):
        rgb = ()
    if len(rgb) in (3, 4) and all(0.0 <= x <= 1.0 for x in rgb):
        return rgb[:3]  # type: ignore[return-value]
    raise VisualizationError(
        f"colour {colour!r} not understood; use '#rrggbb', 0xRRGGBB or (r, g, b) in [0, 1]"
    )


def hex_colour(rgb: Sequence[float]) -> int:
    """The 0xRRGGBB integer of an RGB triple in [0, 1]."""
    r, g, b = (min(255, max(0, round(255 * x))) for x in rgb[:3])
    return (r << 16) | (g << 8) | b


def _as_arrows(arrows: Any) -> list[Arrow]:
    out = []
    for k, a in enumerate(arrows or []):
        if not isinstance(a, Arrow):
            try:
                a = Arrow(*a)
            except TypeError as exc:
                raise VisualizationError(
                    f"arrow {k} must be Arrow or (start (3,), end (3,), colour, label)"
                ) from exc
        start = np.asarray(a.start, dtype=float)
        end = np.asarray(a.end, dtype=float)
        if start.shape != (3,) or end.shape != (3,):
            raise VisualizationError(
                f"arrow {k}: start and end must have shape (3,), got {start.shape}, {end.shape}"
            )
        parse_colour(a.colour)
        out.append(Arrow(start, end, a.colour, str(a.label)))
    return out


# --------------------------------------------------------------------------- geometry


def check_inputs(
    model: pin.Model,
    configurations: Sequence[np.ndarray] | np.ndarray,
    arrows: Sequence[Arrow | tuple] | None,
    arrow_scale: float | None,
    ghost_opacity: float,
) -> tuple[list[np.ndarray], list[Arrow]]:
    """Validate the arguments shared by :func:`static_html` and :func:`live`."""
    if not 0.0 <= ghost_opacity <= 1.0:
        raise VisualizationError(f"ghost_opacity must be in [0, 1], got {ghost_opacity}")
    if arrow_scale is not None and not (math.isfinite(arrow_scale) and arrow_scale > 0):
        raise VisualizationError(f"arrow_scale must be a positive number, got {arrow_scale}")
    return _as_configurations(model, configurations), _as_arrows(arrows)

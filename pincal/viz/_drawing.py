"""Drawing primitives on a meshcat node: parts, ghosts, frame axes, arrows, grid, camera."""

from __future__ import annotations

import colorsys
import math
from collections.abc import Sequence

import meshcat
import meshcat.geometry as mg
import numpy as np
import pinocchio as pin

from pincal.viz._geometry import Part, homogeneous, segment_transform
from pincal.viz._inputs import hex_colour

__all__ = [
    "draw_arrow",
    "draw_floor_grid",
    "draw_parts",
    "draw_triad",
    "frame_pose",
    "ghost_colour",
    "nice_scale",
    "part_poses",
    "set_camera",
]

_AXIS_RGBA = ((0.85, 0.1, 0.1, 1.0), (0.1, 0.7, 0.1, 1.0), (0.1, 0.25, 0.9, 1.0))


def part_poses(model: pin.Model, parts: list[Part], q: np.ndarray) -> list[np.ndarray]:
    """(4, 4) world placement of each visual part at configuration q."""
    data = model.createData()
    pin.forwardKinematics(model, data, q)
    return [homogeneous(data.oMi[p.joint]) @ p.T_joint_part for p in parts]


def frame_pose(model: pin.Model, frame_id: int, q: np.ndarray) -> np.ndarray:
    """(4, 4) world placement of frame ``frame_id`` at configuration q."""
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    return homogeneous(data.oMf[frame_id])


def ghost_colour(k: int, n: int) -> tuple[float, float, float]:
    """RGB of ghost k of n, from blue (first) to red (last)."""
    hue = 0.62 - 0.62 * (k / max(1, n - 1))  # blue → red through green
    return colorsys.hsv_to_rgb(hue, 0.75, 0.9)


def _material(rgb: Sequence[float], opacity: float) -> mg.MeshPhongMaterial:
    return mg.MeshPhongMaterial(
        color=hex_colour(rgb), opacity=opacity, transparent=opacity < 1.0, depthWrite=opacity >= 1.0
    )


def draw_parts(
    vis: meshcat.Visualizer,
    parts: list[Part],
    poses: list[np.ndarray],
    rgb: Sequence[float] | None,
    opacity: float,
) -> None:
    """Draw each part at its pose, in its own colour or ``rgb``, at ``opacity``."""
    for part, T in zip(parts, poses, strict=True):
        colour = part.rgba[:3] if (rgb is None or part.keep_colour) else rgb
        vis[part.name].set_transform(T)
        vis[part.name]["shape"].set_object(part.geometry, _material(colour, opacity))
        vis[part.name]["shape"].set_transform(part.T_part_shape)


def draw_triad(vis: meshcat.Visualizer, T: np.ndarray, length: float, opacity: float) -> None:
    """Draw x/y/z axes (red/green/blue) of ``length`` [m] at placement T."""
    radius = 0.04 * length
    vis.set_transform(T)
    directions = np.eye(3)
    for axis, (name, rgba) in enumerate(zip("xyz", _AXIS_RGBA, strict=True)):
        tip = directions[axis] * length
        vis[name].set_object(mg.Cylinder(length, radius), _material(rgba[:3], opacity))
        vis[name].set_transform(segment_transform(np.zeros(3), tip))


def _arrow_material(rgb: Sequence[float]) -> mg.MeshPhongMaterial:
    """Opaque colour drawn over everything (no depth test): arrows start inside parts."""
    return mg.MeshPhongMaterial(
        color=hex_colour(rgb), opacity=1.0, transparent=True, depthTest=False
    )


def draw_arrow(
    vis: meshcat.Visualizer, start: np.ndarray, end: np.ndarray, rgb: Sequence[float], width: float
) -> None:
    """Draw an arrow from ``start`` to ``end`` [m] (a dot when they coincide)."""
    length = float(np.linalg.norm(end - start))
    if length < 1e-12:
        vis["dot"].set_object(mg.Sphere(1.5 * width), _arrow_material(rgb))
        vis["dot"].set_transform(pin.SE3(np.eye(3), start).homogeneous)
        vis["dot"].set_property("renderOrder", 10)
        return
    head = min(0.35 * length, 6.0 * width)
    direction = (end - start) / length
    neck = end - head * direction
    if np.linalg.norm(neck - start) > 1e-9:
        vis["shaft"].set_object(mg.Cylinder(1.0, width), _arrow_material(rgb))
        vis["shaft"].set_transform(
            segment_transform(start, neck)
            @ np.diag([1.0, float(np.linalg.norm(neck - start)), 1, 1])
        )
    vis["head"].set_object(
        mg.Cylinder(head, radiusTop=0.0, radiusBottom=2.5 * width), _arrow_material(rgb)
    )
    vis["head"].set_transform(segment_transform(neck, end))
    for part in ("shaft", "head"):  # drawn after the transparent ghosts, which would veil it
        vis[part].set_property("renderOrder", 10)


def nice_scale(target: float) -> float:
    """Largest 1-2-5 × 10^k not above ``target`` (at least 1)."""
    if not math.isfinite(target) or target <= 1.0:
        return 1.0
    exponent = math.floor(math.log10(target))
    for mantissa in (5.0, 2.0, 1.0):
        if mantissa * 10**exponent <= target:
            return mantissa * 10**exponent
    return 10.0**exponent


def draw_floor_grid(vis: meshcat.Visualizer, lo: np.ndarray, hi: np.ndarray) -> float:
    """Hide meshcat's 20 m grid; draw one sized to the scene at z = min(0, lo_z).

    Returns the cell size [m] (a 1-2-5 value, about an eighth of the scene).
    """
    vis["/Grid"].set_property("visible", False)
    span = float(max(hi[0] - lo[0], hi[1] - lo[1], 1e-3))
    cell = _nice_scale_down(span / 8)
    x0, x1 = math.floor(lo[0] / cell - 1) * cell, math.ceil(hi[0] / cell + 1) * cell
    y0, y1 = math.floor(lo[1] / cell - 1) * cell, math.ceil(hi[1] / cell + 1) * cell
    z = min(0.0, float(lo[2]))
    segments = []
    for x in np.arange(x0, x1 + 0.5 * cell, cell):
        segments += [[x, y0, z], [x, y1, z]]
    for y in np.arange(y0, y1 + 0.5 * cell, cell):
        segments += [[x0, y, z], [x1, y, z]]
    points = np.array(segments, dtype=np.float32).T
    vis.set_object(
        mg.LineSegments(
            mg.PointsGeometry(points), mg.LineBasicMaterial(color=0x9AA3B5, linewidth=1.0)
        )
    )
    return cell


def _nice_scale_down(target: float) -> float:
    """Largest 1-2-5 × 10^k not above ``target`` (any positive size)."""
    exponent = math.floor(math.log10(target))
    for mantissa in (5.0, 2.0, 1.0):
        if mantissa * 10**exponent <= target * (1 + 1e-9):
            return mantissa * 10**exponent
    return 10.0**exponent


def set_camera(vis: meshcat.Visualizer, radius: float, extent: np.ndarray) -> None:
    """Place the default camera to see a sphere of ``radius`` around the origin.

    ``extent`` (3,) is the size of the scene's bounding box in view coordinates [m].

    meshcat's orbit controls always look at the world origin, so the scene is
    shifted to put its centre there (see :func:`build_scene`).
    """
    distance = 1.45 * radius / math.tan(math.radians(75.0 / 2))  # meshcat's 75° vertical fov
    # direction from target to camera: look across the longer horizontal extent
    if extent[0] > 1.5 * extent[1]:
        view = np.array([0.55, -1.0, 0.75])  # an x-elongated scene seen from its side
    else:
        view = np.array([1.0, 0.55, 0.75])
    x, y, z = distance * view / np.linalg.norm(view)
    # the camera node lives in a frame rotated +90° about x: local (x, y, z) = world (x, -z, y)
    vis["/Cameras/default/rotated/<object>"].set_property("position", [x, z, -y])

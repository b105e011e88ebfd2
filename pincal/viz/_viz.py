"""Meshcat views of a mechanism: offline static HTML and a live local session.

A view shows a Pinocchio model at a list of configurations:

- *ghosts*: one semi-transparent copy of the mechanism per configuration, each in
  its own colour (the legend names them);
- *animation*: an opaque copy that moves through the configurations in a loop
  (joint-space interpolation between them, a short hold at each);
- the axes of a named frame (the measured frame) at every configuration
  (x red, y green, z blue);
- optional error arrows, drawn magnified by a stated factor.

The geometry comes from the URDF's ``<visual>`` elements through Pinocchio's
geometry model: boxes, cylinders, spheres, capsules and meshes (``.dae``, ``.stl``,
``.obj``) whose files can be found. Links without a visual get a thin grey stick
from their origin to each child joint origin, so every model is visible.

:func:`static_html` produces one self-contained HTML page (viewer JavaScript and
scene inlined; no server, no network) without starting meshcat's server: the
meshcat command stream is recorded in-process and replayed by the page.
:func:`live` starts meshcat's server bound to 127.0.0.1 for interactive use.
"""

from __future__ import annotations

import base64
import colorsys
import contextlib
import html
import io
import itertools
import logging
import math
import os
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import meshcat
import meshcat.geometry as mg
import numpy as np
import pinocchio as pin
import umsgpack
from meshcat.animation import Animation

from pincal.errors import ModelFileError, UnknownNameError, VisualizationError
from pincal.io._atomic import atomic_write_text

__all__ = [
    "Arrow",
    "LiveSession",
    "live",
    "static_html",
    "write_html",
]

log = logging.getLogger(__name__)

_VIEWER_JS = Path(meshcat.__file__).parent / "viewer" / "dist" / "main.min.js"
_ROOT = "pincal"
#: Embedded mesh data above this many bytes (summed over all copies) switches to
#: the URDF's collision meshes, which are usually much lighter.
MESH_BUDGET_BYTES = 12_000_000
_STICK_RGBA = (0.55, 0.55, 0.6, 1.0)
_AXIS_RGBA = ((0.85, 0.1, 0.1, 1.0), (0.1, 0.7, 0.1, 1.0), (0.1, 0.25, 0.9, 1.0))


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


@dataclass(frozen=True)
class _Part:
    """One rigid visual item attached to a joint.

    ``T_joint_part`` places the part rigidly on joint ``joint``; ``T_part_shape``
    holds a constant shape correction (axis convention, mesh scale) kept on a
    child node so animation keyframes stay rigid.
    """

    name: str
    geometry: mg.Geometry
    rgba: tuple[float, float, float, float]
    joint: int
    T_joint_part: np.ndarray  # (4, 4)
    T_part_shape: np.ndarray  # (4, 4)
    hull: np.ndarray  # (k, 3) points [m] in the part frame bounding the drawn shape
    keep_colour: bool = False  # meshes drawn in their URDF colour even as ghosts
    mesh_bytes: int = 0


@dataclass
class _RecordingWindow:
    """Stands in for meshcat's ViewerWindow: records commands instead of sending them."""

    commands: list[bytes] = field(default_factory=list)

    def send(self, command: Any) -> None:
        self.commands.append(umsgpack.packb(command.lower()))


class _SetAnimationLooped:
    """``set_animation`` command that loops forever (meshcat's own plays a fixed count)."""

    def __init__(self, animation: Animation):
        self.animation = animation

    def lower(self) -> dict:
        return {
            "type": "set_animation",
            "animations": self.animation.lower(),
            "options": {"play": True, "repetitions": 1_000_000, "clampWhenFinished": False},
            "path": "",
        }


@dataclass(frozen=True)
class LiveSession:
    """A running meshcat server (bound to 127.0.0.1) showing a view.

    Attributes:
        visualizer: the ``meshcat.Visualizer`` (draw more into it if wanted).
        web_url: address to open in a browser.
        zmq_url: address of the server's command socket.
    """

    visualizer: meshcat.Visualizer
    web_url: str
    zmq_url: str

    def close(self) -> None:
        """Stop the server subprocess started for this session."""
        proc = getattr(self.visualizer.window, "server_proc", None)
        if proc is not None and proc.poll() is None:
            proc.kill()
            proc.wait()


# --------------------------------------------------------------------------- inputs


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


def _up_rotation(up: str) -> np.ndarray:
    """Rotation (3, 3) from world to view coordinates that makes world ``up`` point up."""
    key = str(up).strip().lower()
    if key in ("x", "y", "z"):
        key = "+" + key
    if key not in _UP_ROTATIONS:
        raise VisualizationError(f"up {up!r} not understood; use one of {', '.join(UP_DIRECTIONS)}")
    return _UP_ROTATIONS[key]


def _rgb(colour: Any) -> tuple[float, float, float]:
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


def _hex(rgb: Sequence[float]) -> int:
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
        _rgb(a.colour)
        out.append(Arrow(start, end, a.colour, str(a.label)))
    return out


# --------------------------------------------------------------------------- geometry


def _homogeneous(M: pin.SE3) -> np.ndarray:
    return np.array(M.homogeneous, dtype=float)


def _box_corners(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """The 8 corners (8, 3) of the axis-aligned box [lo, hi]."""
    return np.array(
        [
            [(lo, hi)[i][0], (lo, hi)[j][1], (lo, hi)[k][2]]
            for i in (0, 1)
            for j in (0, 1)
            for k in (0, 1)
        ]
    )


def _rot_x90() -> np.ndarray:
    """Three.js cylinders run along y; URDF/FCL cylinders along z."""
    T = np.eye(4)
    T[:3, :3] = pin.utils.rotate("x", math.pi / 2)
    return T


def _segment_transform(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Pose (4, 4) of a y-axis cylinder centred between points a and b."""
    d = b - a
    y = d / np.linalg.norm(d)
    helper = np.array([1.0, 0, 0]) if abs(y[0]) < 0.9 else np.array([0, 0, 1.0])
    x = np.cross(y, helper)
    x /= np.linalg.norm(x)
    z = np.cross(x, y)
    T = np.eye(4)
    T[:3, :3] = np.column_stack([x, y, z])
    T[:3, 3] = 0.5 * (a + b)
    return T


def _load_geometry_model(
    model: pin.Model, urdf: str | os.PathLike, kind: pin.GeometryType
) -> pin.GeometryModel:
    text = str(urdf)
    if text.lstrip().startswith("<"):
        return pin.buildGeomFromUrdfString(model, text, kind, package_dirs=[])
    path = Path(urdf)
    if not path.is_file():
        raise ModelFileError(f"URDF file {str(path)!r} not found")
    # package://pkg/... resolves against any ancestor holding a folder named pkg
    package_dirs = [str(p) for p in path.resolve().parents][:8]
    return pin.buildGeomFromUrdf(model, str(path), kind, package_dirs=package_dirs)


def _mesh_geometry(path: str) -> tuple[mg.Geometry, int] | None:
    suffix = Path(path).suffix.lower()
    if not Path(path).is_file():
        return None
    if suffix == ".stl":
        data = _stl_with_normals(Path(path).read_bytes())
        _, ext_code = mg.threejs_type(np.uint8)
        return mg.MeshGeometry(umsgpack.Ext(ext_code, data), "stl"), len(data)
    if suffix == ".dae":
        return mg.DaeMeshGeometry.from_file(path), Path(path).stat().st_size
    if suffix == ".obj":
        return mg.ObjMeshGeometry.from_file(path), Path(path).stat().st_size
    return None


def _stl_with_normals(data: bytes) -> bytes:
    """Binary STL with its facet normals recomputed (many files store zeros → black shading)."""
    if len(data) < 84 or (data[:5].lower() == b"solid" and b"facet" in data[:400]):
        return data  # ASCII STL: three.js computes the normals itself
    count = int(np.frombuffer(data, "<u4", 1, 80)[0])
    if len(data) < 84 + 50 * count:
        return data
    facet = np.dtype([("n", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")])
    tris = np.frombuffer(data, facet, count, 84).copy()
    v = tris["v"].astype(float)
    n = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    norm = np.linalg.norm(n, axis=1, keepdims=True)
    tris["n"] = np.divide(n, norm, out=np.zeros_like(n), where=norm > 0)
    return data[:84] + tris.tobytes()


def _parts_from_geometry(gmodel: pin.GeometryModel) -> tuple[list[_Part], set[int]]:
    """Parts for every drawable geometry object and the set of frames that have one."""
    parts: list[_Part] = []
    frames_with_visual: set[int] = set()
    for obj in gmodel.geometryObjects:
        shape = obj.geometry
        rgba = tuple(float(x) for x in obj.meshColor)
        T_part_shape = np.eye(4)
        mesh_bytes = 0
        keep_colour = False
        kind = type(shape).__name__
        if kind == "Box":
            half = np.array(shape.halfSide, dtype=float)
            geometry: mg.Geometry = mg.Box(list(2.0 * half))
            hull = _box_corners(-half, half)
        elif kind == "Cylinder":
            r, h = float(shape.radius), 2.0 * float(shape.halfLength)
            geometry = mg.Cylinder(h, r)
            T_part_shape = _rot_x90()
            hull = _box_corners(np.array([-r, -r, -h / 2]), np.array([r, r, h / 2]))
        elif kind == "Capsule":
            r, h = float(shape.radius), 2.0 * float(shape.halfLength)
            geometry = mg.Cylinder(h + 2 * r, r)  # drawn as a cylinder of full length
            T_part_shape = _rot_x90()
            hull = _box_corners(np.array([-r, -r, -h / 2 - r]), np.array([r, r, h / 2 + r]))
        elif kind == "Sphere":
            r = float(shape.radius)
            geometry = mg.Sphere(r)
            hull = _box_corners(np.full(3, -r), np.full(3, r))
        elif kind == "Cone":
            r, h = float(shape.radius), 2.0 * float(shape.halfLength)
            geometry = mg.Cylinder(h, radiusTop=0.0, radiusBottom=r)
            T_part_shape = _rot_x90()
            hull = _box_corners(np.array([-r, -r, -h / 2]), np.array([r, r, h / 2]))
        else:
            loaded = _mesh_geometry(obj.meshPath) if obj.meshPath else None
            if loaded is None:
                log.warning("geometry %r (%s) cannot be drawn; skipped", obj.name, kind)
                continue
            geometry, mesh_bytes = loaded
            scale = np.asarray(obj.meshScale, dtype=float)
            T_part_shape = np.diag([*scale, 1.0])
            shape.computeLocalAABB()
            box = shape.aabb_local
            hull = _box_corners(np.array(box.min_), np.array(box.max_)) * scale
        parts.append(
            _Part(
                name=_safe(obj.name),
                geometry=geometry,
                rgba=rgba,  # type: ignore[arg-type]
                joint=int(obj.parentJoint),
                T_joint_part=_homogeneous(obj.placement),
                T_part_shape=T_part_shape,
                hull=hull,
                keep_colour=keep_colour,
                mesh_bytes=mesh_bytes,
            )
        )
        frames_with_visual.add(int(obj.parentFrame))
    return parts, frames_with_visual


def _point_in_joint(model: pin.Model, frame_id: int, joint: int) -> np.ndarray | None:
    """Origin of frame ``frame_id`` in the frame of joint ``joint`` if rigidly attached."""
    f = model.frames[frame_id]
    if f.parentJoint == joint:
        return np.array(f.placement.translation)
    child = f.parentJoint
    if model.parents[child] == joint and f.type == pin.FrameType.JOINT:
        joint_type = model.joints[child].shortname()
        if "FreeFlyer" in joint_type or "Planar" in joint_type:
            return None  # a floating body is not attached by a stick
        return np.array((model.jointPlacements[child] * f.placement).translation)
    return None


def _skeleton_parts(model: pin.Model, frames_with_visual: set[int], size: float) -> list[_Part]:
    """Thin sticks from each visual-less link's origin to its child joint origins."""
    parts = []
    radius = max(0.002, 0.01 * size)
    geometry = mg.Cylinder(1.0, radius)
    for j, f in enumerate(model.frames):
        if f.type not in (pin.FrameType.JOINT, pin.FrameType.FIXED_JOINT) or j == 0:
            continue
        body = f.parentFrame
        if body in frames_with_visual or model.frames[body].type != pin.FrameType.BODY:
            continue
        joint = model.frames[body].parentJoint
        a = np.array(model.frames[body].placement.translation)
        b = _point_in_joint(model, j, joint)
        if b is None or np.linalg.norm(b - a) < 1e-6:
            continue
        length = float(np.linalg.norm(b - a))
        T_part_shape = np.diag([1.0, length, 1.0, 1.0])
        parts.append(
            _Part(
                name=_safe(f"stick_{model.frames[body].name}_{f.name}"),
                geometry=geometry,
                rgba=_STICK_RGBA,
                joint=joint,
                T_joint_part=_segment_transform(a, b),
                T_part_shape=T_part_shape,
                hull=np.array([[0.0, -length / 2, 0.0], [0.0, length / 2, 0.0]]),
            )
        )
    return parts


def _joint_sticks_extent(model: pin.Model, qs: list[np.ndarray]) -> float:
    """Size [m] of the cloud of joint and frame origins over all configurations."""
    data = model.createData()
    pts = []
    for q in qs:
        pin.forwardKinematics(model, data, q)
        pin.updateFramePlacements(model, data)
        pts.extend(np.array(M.translation) for M in data.oMf)
    pts_arr = np.array(pts)
    return float(np.max(np.ptp(pts_arr, axis=0))) if len(pts_arr) else 1.0


def _safe(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]", "_", name) or "_"


# --------------------------------------------------------------------------- scene


def _poses(model: pin.Model, parts: list[_Part], q: np.ndarray) -> list[np.ndarray]:
    data = model.createData()
    pin.forwardKinematics(model, data, q)
    return [_homogeneous(data.oMi[p.joint]) @ p.T_joint_part for p in parts]


def _frame_pose(model: pin.Model, frame_id: int, q: np.ndarray) -> np.ndarray:
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    return _homogeneous(data.oMf[frame_id])


def _ghost_colour(k: int, n: int) -> tuple[float, float, float]:
    hue = 0.62 - 0.62 * (k / max(1, n - 1))  # blue → red through green
    return colorsys.hsv_to_rgb(hue, 0.75, 0.9)


def _material(rgb: Sequence[float], opacity: float) -> mg.MeshPhongMaterial:
    return mg.MeshPhongMaterial(
        color=_hex(rgb), opacity=opacity, transparent=opacity < 1.0, depthWrite=opacity >= 1.0
    )


def _draw_parts(
    vis: meshcat.Visualizer,
    parts: list[_Part],
    poses: list[np.ndarray],
    rgb: Sequence[float] | None,
    opacity: float,
) -> None:
    for part, T in zip(parts, poses, strict=True):
        colour = part.rgba[:3] if (rgb is None or part.keep_colour) else rgb
        vis[part.name].set_transform(T)
        vis[part.name]["shape"].set_object(part.geometry, _material(colour, opacity))
        vis[part.name]["shape"].set_transform(part.T_part_shape)


def _draw_triad(vis: meshcat.Visualizer, T: np.ndarray, length: float, opacity: float) -> None:
    radius = 0.04 * length
    vis.set_transform(T)
    directions = np.eye(3)
    for axis, (name, rgba) in enumerate(zip("xyz", _AXIS_RGBA, strict=True)):
        tip = directions[axis] * length
        vis[name].set_object(mg.Cylinder(length, radius), _material(rgba[:3], opacity))
        vis[name].set_transform(_segment_transform(np.zeros(3), tip))


def _arrow_material(rgb: Sequence[float]) -> mg.MeshPhongMaterial:
    """Opaque colour drawn over everything (no depth test): arrows start inside parts."""
    return mg.MeshPhongMaterial(color=_hex(rgb), opacity=1.0, transparent=True, depthTest=False)


def _draw_arrow(
    vis: meshcat.Visualizer, start: np.ndarray, end: np.ndarray, rgb: Sequence[float], width: float
) -> None:
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
            _segment_transform(start, neck)
            @ np.diag([1.0, float(np.linalg.norm(neck - start)), 1, 1])
        )
    vis["head"].set_object(
        mg.Cylinder(head, radiusTop=0.0, radiusBottom=2.5 * width), _arrow_material(rgb)
    )
    vis["head"].set_transform(_segment_transform(neck, end))
    for part in ("shaft", "head"):  # drawn after the transparent ghosts, which would veil it
        vis[part].set_property("renderOrder", 10)


def _nice_scale(target: float) -> float:
    """Largest 1-2-5 × 10^k not above ``target`` (at least 1)."""
    if not math.isfinite(target) or target <= 1.0:
        return 1.0
    exponent = math.floor(math.log10(target))
    for mantissa in (5.0, 2.0, 1.0):
        if mantissa * 10**exponent <= target:
            return mantissa * 10**exponent
    return 10.0**exponent


def _draw_floor_grid(vis: meshcat.Visualizer, lo: np.ndarray, hi: np.ndarray) -> float:
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


def _set_camera(vis: meshcat.Visualizer, radius: float, extent: np.ndarray) -> None:
    """Place the default camera to see a sphere of ``radius`` around the origin.

    ``extent`` (3,) is the size of the scene's bounding box in view coordinates [m].

    meshcat's orbit controls always look at the world origin, so the scene is
    shifted to put its centre there (see :func:`_build_scene`).
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


def _check_inputs(
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


def _build_scene(
    vis: meshcat.Visualizer,
    model: pin.Model,
    urdf: str | os.PathLike,
    qs: list[np.ndarray],
    *,
    frame: str | None,
    ghosts: bool,
    animate: bool,
    arrows: list[Arrow],
    arrow_scale: float | None,
    ghost_opacity: float,
    fps: int,
    up: str = "+z",
) -> dict:
    """Send the scene to ``vis``; returns legend facts (colours, arrow scale)."""
    R_view_world = _up_rotation(up)
    frame_id = None
    if frame is not None:
        names = [f.name for f in model.frames]
        if frame not in names:
            raise UnknownNameError("frame", frame, names)
        frame_id = model.getFrameId(frame)

    animate = animate and len(qs) > 1
    copies = (len(qs) if ghosts else 0) + (1 if animate else 0)
    gmodel = _load_geometry_model(model, urdf, pin.GeometryType.VISUAL)
    parts, with_visual = _parts_from_geometry(gmodel)
    mesh_bytes = sum(p.mesh_bytes for p in parts) * max(1, copies)
    if mesh_bytes > MESH_BUDGET_BYTES:
        collision = _load_geometry_model(model, urdf, pin.GeometryType.COLLISION)
        c_parts, c_with = _parts_from_geometry(collision)
        if c_parts and sum(p.mesh_bytes for p in c_parts) < sum(p.mesh_bytes for p in parts):
            log.info(
                "visual meshes would embed %.1f MB; using the collision meshes instead",
                mesh_bytes / 1e6,
            )
            parts, with_visual = c_parts, c_with
    extent = max(_joint_sticks_extent(model, qs), 1e-3)
    parts = parts + _skeleton_parts(model, with_visual, extent)

    # bounding sphere of everything drawn, for camera framing and sizes
    points = [np.zeros((1, 3))]
    pose_sets = [_poses(model, parts, q) for q in qs]
    for poses in pose_sets:
        for part, T in zip(parts, poses, strict=True):
            points.append(part.hull @ T[:3, :3].T + T[:3, 3] if part.hull.size else T[None, :3, 3])
    if frame_id is not None:
        points.extend(_frame_pose(model, frame_id, q)[None, :3, 3] for q in qs)
    p_arr = np.vstack(points) @ R_view_world.T  # view coordinates (up = +z)
    lo, hi = p_arr.min(axis=0), p_arr.max(axis=0)
    size = float(np.max(hi - lo))

    # arrows: magnified so the longest is about 30 % of the scene (twice the triads)
    longest = max((float(np.linalg.norm(a.end - a.start)) for a in arrows), default=0.0)
    if arrow_scale is None:
        arrow_scale = _nice_scale(0.3 * size / longest) if longest > 0 else 1.0
    drawn_ends = [a.start + arrow_scale * (a.end - a.start) for a in arrows]
    for a, e in zip(arrows, drawn_ends, strict=True):
        a_view, e_view = R_view_world @ a.start, R_view_world @ e
        lo = np.minimum(lo, np.minimum(a_view, e_view))
        hi = np.maximum(hi, np.maximum(a_view, e_view))
    centre = 0.5 * (lo + hi)
    radius = max(0.5 * float(np.linalg.norm(hi - lo)), 0.05)

    root = vis[_ROOT]
    # display = R_view_world · world − centre: up is up and the scene centre sits at
    # the origin, where meshcat's orbit controls look; nodes below are in world coordinates
    T_view_world = np.eye(4)
    T_view_world[:3, :3] = R_view_world
    T_view_world[:3, 3] = -centre
    root.set_transform(T_view_world)
    # meshcat's world axes (0.5 m long) would dwarf a small mechanism: scale them to it
    T_axes = T_view_world.copy()
    T_axes[:3, :3] *= max(0.2 * size, 1e-3) / 0.5
    vis["/Axes"].set_transform(T_axes)
    legend: dict = {
        "poses": [],
        "arrows": [],
        "arrow_scale": arrow_scale,
        "frame": frame,
        "up": up,
    }
    opacity = ghost_opacity if (animate or len(qs) > 1) else 1.0
    triad = (0.08 if arrows else 0.12) * size  # axis length [m]
    for k, poses in enumerate(pose_sets):
        rgb = _ghost_colour(k, len(qs))
        legend["poses"].append(rgb)
        if ghosts:
            _draw_parts(root["ghosts"][f"pose{k}"], parts, poses, rgb, opacity)
        if frame_id is not None:
            _draw_triad(
                root["frame_axes"][f"pose{k}"],
                _frame_pose(model, frame_id, qs[k]),
                triad,
                1.0,
            )

    if animate:
        robot = root["robot"]
        _draw_parts(robot, parts, pose_sets[0], None, 1.0)
        if frame_id is not None:
            _draw_triad(
                robot["measured_frame"], _frame_pose(model, frame_id, qs[0]), 1.25 * triad, 1.0
            )
        animation = Animation(default_framerate=fps)
        hold, move, steps = max(1, fps // 2), fps, 12  # [frames]: 0.5 s hold, 1 s move

        def key(time: int, q: np.ndarray) -> None:
            with animation.at_frame(vis, time) as f:
                node = f[_ROOT]["robot"]
                for part, T in zip(parts, _poses(model, parts, q), strict=True):
                    node[part.name].set_transform(T)
                if frame_id is not None:
                    node["measured_frame"].set_transform(_frame_pose(model, frame_id, q))

        cycle = [*qs, qs[0]]
        start = 0
        for q_from, q_to in itertools.pairwise(cycle):
            key(start, q_from)
            key(start + hold, q_from)
            for s in range(1, steps + 1):
                t = s / steps
                key(start + hold + round(t * move), pin.interpolate(model, q_from, q_to, t))
            start += hold + move
        vis.window.send(_SetAnimationLooped(animation))

    width = 0.006 * size
    for k, (a, e) in enumerate(zip(arrows, drawn_ends, strict=True)):
        rgb = _rgb(a.colour)
        _draw_arrow(root["arrows"][f"arrow{k}"], a.start, e, rgb, width)
        legend["arrows"].append((rgb, a.label, float(np.linalg.norm(a.end - a.start))))

    log.debug("scene centre %s radius %.3f m", centre, radius)
    floor = vis[f"{_ROOT}_floor"]
    floor.set_transform(pin.SE3(np.eye(3), -centre).homogeneous)
    legend["grid_cell"] = _draw_floor_grid(floor, lo, hi)
    _set_camera(vis, radius, hi - lo)
    return legend


# --------------------------------------------------------------------------- HTML


def _legend_html(title: str | None, legend: dict, ghosts: bool, animate: bool) -> str:
    rows = []
    if title:
        rows.append(f"<div class='t'>{html.escape(title)}</div>")
    n = len(legend["poses"])
    if ghosts and n > 1:
        swatches = "".join(
            f"<span class='sw' style='background:#{_hex(rgb):06x}'></span>{k}&nbsp;"
            for k, rgb in enumerate(legend["poses"])
        )
        rows.append(f"<div>poses (ghosts): {swatches}</div>")
    if animate and n > 1:
        rows.append(f"<div>opaque copy: animation through the {n} poses</div>")
    if legend["frame"]:
        rows.append(
            f"<div>axes of frame <b>{html.escape(legend['frame'])}</b>: "
            "<span style='color:#d91a1a'>x</span> "
            "<span style='color:#1ab31a'>y</span> "
            "<span style='color:#1a40e6'>z</span></div>"
        )
    if legend.get("up", "+z").lstrip("+") != "z":
        rows.append(f"<div>drawn with world <b>{html.escape(legend['up'])}</b> pointing up</div>")
    if legend.get("grid_cell"):
        rows.append(f"<div>floor grid: {_length_text(legend['grid_cell'])} cells</div>")
    if legend["arrows"]:
        scale = legend["arrow_scale"]
        rows.append(
            f"<div><b>error arrows magnified ×{scale:g}</b> (1 mm drawn as {scale:g} mm)</div>"
        )
        items = [
            f"<span class='sw' style='background:#{_hex(rgb):06x}'></span>"
            f"{html.escape(label) + ': ' if label else ''}{1e3 * length:.3f} mm"
            for rgb, label, length in legend["arrows"]
        ]
        if len(items) <= 3:
            rows.extend(f"<div>{item}</div>" for item in items)
        else:  # many arrows: wrap them in one paragraph
            rows.append("<div>" + " ".join(items) + "</div>")
    if not rows:
        return ""
    return "<div id='pincal-legend'>" + "".join(rows) + "</div>"


def _length_text(metres: float) -> str:
    if metres >= 1.0:
        return f"{metres:g} m"
    if metres >= 1e-3:
        return f"{1e3 * metres:g} mm"
    return f"{1e6 * metres:g} µm"


_PAGE = """<!DOCTYPE html>
<html>
<head>
<meta charset="utf-8">
<title>{title}</title>
<style>
body {{ margin: 0; overflow: hidden; }}
#meshcat-pane {{ width: 100vw; height: 100vh; overflow: hidden; }}
#pincal-legend {{ position: absolute; left: 8px; top: 8px; max-width: 45vw;
  background: rgba(255, 255, 255, 0.85); border-radius: 4px; padding: 6px 9px;
  font: 13px/1.45 sans-serif; color: #222; }}
#pincal-legend .t {{ font-weight: bold; font-size: 15px; }}
#pincal-legend .sw {{ display: inline-block; width: 11px; height: 11px;
  margin: 0 3px 0 4px; border: 1px solid #555; vertical-align: -1px; }}
</style>
</head>
<body>
<div id="meshcat-pane"></div>
{legend}
<script>
{viewer_js}
</script>
<script>
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
var pincalScene = [
{commands}
];
for (var i = 0; i < pincalScene.length; i++) {{
  var raw = atob(pincalScene[i]);
  var bytes = new Uint8Array(raw.length);
  for (var j = 0; j < raw.length; j++) {{ bytes[j] = raw.charCodeAt(j); }}
  viewer.handle_command_bytearray(bytes);
}}
</script>
</body>
</html>
"""


def static_html(
    model: pin.Model,
    urdf_path: str | os.PathLike,
    configurations: Sequence[np.ndarray] | np.ndarray,
    *,
    frame: str | None = None,
    ghosts: bool = True,
    animate: bool = True,
    arrows: Sequence[Arrow | tuple] | None = None,
    arrow_scale: float | None = None,
    title: str | None = None,
    ghost_opacity: float = 0.35,
    fps: int = 30,
    up: str = "+z",
) -> str:
    """A self-contained HTML page showing ``model`` at ``configurations``.

    Args:
        model: the Pinocchio model, built from ``urdf_path`` (possibly with changed
            placements, e.g. a calibrated model; link names must match).
        urdf_path: the URDF file (its ``<visual>`` elements are drawn; ``package://``
            URIs resolve against the file's ancestor folders) or the URDF XML text.
        configurations: sequence of configurations, each shape (model.nq,).
        frame: name of a model frame (the measured frame) whose axes are drawn at
            every configuration, or None.
        ghosts: draw one semi-transparent copy per configuration.
        animate: add an opaque copy looping through the configurations (ignored
            for a single configuration).
        arrows: error arrows, each an :class:`Arrow` or ``(start (3,), end (3,),
            colour, label)`` in the world frame [m].
        arrow_scale: magnification of the arrows; None picks a 1-2-5 value making
            the longest about 30 % of the scene. The legend states it.
        title: page title and legend heading.
        ghost_opacity: opacity of ghost copies in [0, 1].
        fps: animation frame rate.
        up: the world direction drawn pointing up: ``+z`` (default), ``-z`` (a
            machine whose world z points down, towards the table), ``±x``, ``±y``.

    Returns:
        The HTML text (a few MB: meshcat's viewer is inlined). Opening it needs no
        server and no network.

    Raises:
        VisualizationError: malformed configurations, arrows or colours.
        UnknownNameError: ``frame`` is not a frame of ``model``.
        ModelFileError: the URDF file does not exist.
    """
    qs, arrow_list = _check_inputs(model, configurations, arrows, arrow_scale, ghost_opacity)
    window = _RecordingWindow()
    vis = meshcat.Visualizer(window=window)
    legend = _build_scene(
        vis,
        model,
        urdf_path,
        qs,
        frame=frame,
        ghosts=ghosts,
        animate=animate,
        arrows=arrow_list,
        arrow_scale=arrow_scale,
        ghost_opacity=ghost_opacity,
        fps=fps,
        up=up,
    )
    commands = ",\n".join('"' + base64.b64encode(c).decode("ascii") + '"' for c in window.commands)
    return _PAGE.format(
        title=html.escape(title or "pincal view"),
        legend=_legend_html(title, legend, ghosts, animate and len(qs) > 1),
        viewer_js=_VIEWER_JS.read_text(encoding="utf-8"),
        commands=commands,
    )


def write_html(path: str | os.PathLike, html_text: str) -> Path:
    """Write ``html_text`` to ``path`` atomically (temporary file + rename); returns the path."""
    return atomic_write_text(path, html_text)


def live(
    model: pin.Model,
    urdf_path: str | os.PathLike,
    configurations: Sequence[np.ndarray] | np.ndarray,
    *,
    frame: str | None = None,
    ghosts: bool = True,
    animate: bool = True,
    arrows: Sequence[Arrow | tuple] | None = None,
    arrow_scale: float | None = None,
    ghost_opacity: float = 0.35,
    up: str = "+z",
) -> LiveSession:
    """Start a meshcat server on 127.0.0.1 and draw the same view as :func:`static_html`.

    The server (a subprocess) listens on the loopback interface only; open
    ``session.web_url`` in a local browser and call ``session.close()`` when done
    (it is also stopped when Python exits). Arguments are those of
    :func:`static_html`.
    """
    qs, arrow_list = _check_inputs(model, configurations, arrows, arrow_scale, ghost_opacity)
    zmq_url = None
    banner = io.StringIO()
    with contextlib.redirect_stdout(banner):  # meshcat prints the URL; we log it
        vis = meshcat.Visualizer(zmq_url=zmq_url)
    session = LiveSession(vis, vis.window.web_url, vis.window.zmq_url)
    log.info("meshcat viewer at %s", session.web_url)
    try:
        _build_scene(
            vis,
            model,
            urdf_path,
            qs,
            frame=frame,
            ghosts=ghosts,
            animate=animate,
            arrows=arrow_list,
            arrow_scale=arrow_scale,
            ghost_opacity=ghost_opacity,
            fps=30,
            up=up,
        )
    except BaseException:
        session.close()
        raise
    return session

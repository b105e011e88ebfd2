"""Drawable parts of a model: URDF visuals (primitives and meshes) and skeleton sticks.

The geometry comes from the URDF's ``<visual>`` elements through Pinocchio's
geometry model: boxes, cylinders, spheres, capsules and meshes (``.dae``, ``.stl``,
``.obj``) whose files can be found. Links without a visual get a thin grey stick
from their origin to each child joint origin, so every model is visible.
"""

from __future__ import annotations

import logging
import math
import os
import re
from dataclasses import dataclass
from pathlib import Path

import meshcat.geometry as mg
import numpy as np
import pinocchio as pin
import umsgpack

from pincal._files import read_bytes, read_text
from pincal.errors import InputFileError, ModelFileError, VisualizationError, clip
from pincal.model.kernels import captured_stderr
from pincal.viz._meshes import checked_urdf, mesh_access_allowed, mesh_references

__all__ = [
    "Part",
    "homogeneous",
    "joint_sticks_extent",
    "load_geometry_model",
    "parts_from_geometry",
    "segment_transform",
    "skeleton_parts",
    "stl_with_normals",
]

log = logging.getLogger(__name__)

_STICK_RGBA = (0.55, 0.55, 0.6, 1.0)


@dataclass(frozen=True)
class Part:
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


def homogeneous(M: pin.SE3) -> np.ndarray:
    """(4, 4) homogeneous matrix of a placement."""
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


def segment_transform(a: np.ndarray, b: np.ndarray) -> np.ndarray:
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


def load_geometry_model(
    model: pin.Model,
    urdf: str | os.PathLike,
    kind: pin.GeometryType,
    allow_outside: bool | None = None,
) -> pin.GeometryModel:
    """The geometry model of a URDF's visuals or collisions, meshes checked first.

    Args:
        model: the Pinocchio model built from the URDF.
        urdf: the URDF file, or URDF text.
        kind: ``pin.GeometryType.VISUAL`` or ``COLLISION``.
        allow_outside: read meshes outside the model's directory (default: the
            :func:`~pincal.viz.allow_mesh_outside` context, else False).

    Raises:
        ModelFileError: the URDF file is missing or unreadable.
        VisualizationError: a mesh outside the model's directory, a URL, a missing or
            unreadable mesh file (the message names the link and the path).
    """
    allow = mesh_access_allowed() if allow_outside is None else allow_outside
    text = str(urdf)
    if text.lstrip().startswith("<"):
        path = None
    else:
        path = Path(urdf)
        text = read_text(path, "URDF", error=ModelFileError)
    xml = checked_urdf(text, path, allow)
    refs = mesh_references(xml, None, True)
    built, printed, error = captured_stderr(
        lambda: pin.buildGeomFromUrdfString(model, xml, kind, package_dirs=[])
    )
    if error is not None or built is None:
        message = f"{error}\n{printed}"
        culprit = next((r for r in refs if str(r.path) in message), None)
        where = (
            f"link '{clip(culprit.link)}' mesh {clip(str(culprit.path), 200)}"
            if culprit
            else "a mesh"
        )
        said = " ".join(str(error).split())
        said = said.split("message:", 1)[-1].strip()  # the loader's reason, without its source
        raise VisualizationError(
            f"cannot load {where}: {clip(said, 300)}; check that the "
            "file is a valid .stl, .dae or .obj mesh"
        )
    if printed.strip():
        log.debug("geometry loader output: %s", clip(printed, 2000))
    return built


def _mesh_geometry(path: str) -> tuple[mg.Geometry, int] | None:
    suffix = Path(path).suffix.lower()
    if not Path(path).is_file():
        return None
    try:
        if suffix == ".stl":
            data = stl_with_normals(read_bytes(path, "mesh"))
            _, ext_code = mg.threejs_type(np.uint8)
            return mg.MeshGeometry(umsgpack.Ext(ext_code, data), "stl"), len(data)
        if suffix in (".dae", ".obj"):
            text = read_text(path, "mesh")
            return mg.MeshGeometry(text, suffix[1:]), len(text.encode("utf-8"))
    except InputFileError as exc:
        raise VisualizationError(f"cannot embed mesh: {exc}") from None
    return None


def stl_with_normals(data: bytes) -> bytes:
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


def parts_from_geometry(gmodel: pin.GeometryModel) -> tuple[list[Part], set[int]]:
    """Parts for every drawable geometry object and the set of frames that have one."""
    parts: list[Part] = []
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
            Part(
                name=_safe(obj.name),
                geometry=geometry,
                rgba=rgba,  # type: ignore[arg-type]
                joint=int(obj.parentJoint),
                T_joint_part=homogeneous(obj.placement),
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


def skeleton_parts(model: pin.Model, frames_with_visual: set[int], size: float) -> list[Part]:
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
            Part(
                name=_safe(f"stick_{model.frames[body].name}_{f.name}"),
                geometry=geometry,
                rgba=_STICK_RGBA,
                joint=joint,
                T_joint_part=segment_transform(a, b),
                T_part_shape=T_part_shape,
                hull=np.array([[0.0, -length / 2, 0.0], [0.0, length / 2, 0.0]]),
            )
        )
    return parts


def joint_sticks_extent(model: pin.Model, qs: list[np.ndarray]) -> float:
    """Size [m] of the cloud of joint and frame origins over all configurations."""
    data = model.createData()
    pts: list[np.ndarray] = []
    for q in qs:
        pin.forwardKinematics(model, data, q)
        pin.updateFramePlacements(model, data)
        pts.extend(np.array(M.translation) for M in data.oMf)
    pts_arr = np.array(pts)
    return float(np.max(np.ptp(pts_arr, axis=0))) if len(pts_arr) else 1.0


def _safe(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]", "_", name) or "_"


# --------------------------------------------------------------------------- scene

"""The scene of a view: ghosts, animation, frame axes and arrows sent to a meshcat visualizer.

A view shows a Pinocchio model at a list of configurations:

- *ghosts*: one semi-transparent copy of the mechanism per configuration, each in
  its own colour (the legend names them);
- *animation*: an opaque copy that moves through the configurations in a loop
  (joint-space interpolation between them, a short hold at each);
- the axes of a named frame (the measured frame) at every configuration
  (x red, y green, z blue);
- optional error arrows, drawn magnified by a stated factor.
"""

from __future__ import annotations

import itertools
import logging
import os
from collections.abc import Callable

import meshcat
import numpy as np
import pinocchio as pin
from meshcat.animation import Animation

from pincal.errors import UnknownNameError
from pincal.viz._drawing import (
    draw_arrow,
    draw_floor_grid,
    draw_parts,
    draw_triad,
    frame_pose,
    ghost_colour,
    nice_scale,
    part_poses,
    set_camera,
)
from pincal.viz._geometry import (
    joint_sticks_extent,
    load_geometry_model,
    parts_from_geometry,
    skeleton_parts,
)
from pincal.viz._inputs import Arrow, parse_colour, up_rotation

__all__ = ["MESH_BUDGET_BYTES", "build_scene"]

log = logging.getLogger(__name__)

_ROOT = "pincal"
#: Embedded mesh data above this many bytes (summed over all copies) switches to
#: the URDF's collision meshes, which are usually much lighter.
MESH_BUDGET_BYTES = 12_000_000


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


def build_scene(
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
    allow_mesh_outside: bool | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> dict:
    """Send the scene to ``vis``; returns legend facts (colours, arrow scale).

    ``allow_mesh_outside`` None follows :func:`~pincal.viz.allow_mesh_outside`.
    ``progress``: optional callback ``(done, total)`` after each pose drawn and each
    animation segment (total: the poses, twice with an animation).
    """
    R_view_world = up_rotation(up)
    frame_id = None
    if frame is not None:
        names = [f.name for f in model.frames]
        if frame not in names:
            raise UnknownNameError("frame", frame, names)
        frame_id = model.getFrameId(frame)

    animate = animate and len(qs) > 1
    copies = (len(qs) if ghosts else 0) + (1 if animate else 0)
    gmodel = load_geometry_model(model, urdf, pin.GeometryType.VISUAL, allow_mesh_outside)
    parts, with_visual = parts_from_geometry(gmodel)
    mesh_bytes = sum(p.mesh_bytes for p in parts) * max(1, copies)
    if mesh_bytes > MESH_BUDGET_BYTES:
        collision = load_geometry_model(
            model, urdf, pin.GeometryType.COLLISION, allow_mesh_outside
        )
        c_parts, c_with = parts_from_geometry(collision)
        if c_parts and sum(p.mesh_bytes for p in c_parts) < sum(p.mesh_bytes for p in parts):
            log.info(
                "visual meshes would embed %.1f MB; using the collision meshes instead",
                mesh_bytes / 1e6,
            )
            parts, with_visual = c_parts, c_with
    extent = max(joint_sticks_extent(model, qs), 1e-3)
    parts = parts + skeleton_parts(model, with_visual, extent)

    # bounding sphere of everything drawn, for camera framing and sizes
    points = [np.zeros((1, 3))]
    pose_sets = [part_poses(model, parts, q) for q in qs]
    for poses in pose_sets:
        for part, T in zip(parts, poses, strict=True):
            points.append(part.hull @ T[:3, :3].T + T[:3, 3] if part.hull.size else T[None, :3, 3])
    if frame_id is not None:
        points.extend(frame_pose(model, frame_id, q)[None, :3, 3] for q in qs)
    p_arr = np.vstack(points) @ R_view_world.T  # view coordinates (up = +z)
    lo, hi = p_arr.min(axis=0), p_arr.max(axis=0)
    size = float(np.max(hi - lo))

    # arrows: magnified so the longest is about 30 % of the scene (twice the triads)
    longest = max((float(np.linalg.norm(a.end - a.start)) for a in arrows), default=0.0)
    if arrow_scale is None:
        arrow_scale = nice_scale(0.3 * size / longest) if longest > 0 else 1.0
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
    total = len(qs) * (2 if animate else 1)
    for k, poses in enumerate(pose_sets):
        rgb = ghost_colour(k, len(qs))
        legend["poses"].append(rgb)
        if ghosts:
            draw_parts(root["ghosts"][f"pose{k}"], parts, poses, rgb, opacity)
        if frame_id is not None:
            draw_triad(
                root["frame_axes"][f"pose{k}"],
                frame_pose(model, frame_id, qs[k]),
                triad,
                1.0,
            )
        if progress is not None:
            progress(k + 1, total)

    if animate:
        robot = root["robot"]
        draw_parts(robot, parts, pose_sets[0], None, 1.0)
        if frame_id is not None:
            draw_triad(
                robot["measured_frame"], frame_pose(model, frame_id, qs[0]), 1.25 * triad, 1.0
            )
        animation = Animation(default_framerate=fps)
        hold, move, steps = max(1, fps // 2), fps, 12  # [frames]: 0.5 s hold, 1 s move

        def key(time: int, q: np.ndarray) -> None:
            with animation.at_frame(vis, time) as f:
                node = f[_ROOT]["robot"]
                for part, T in zip(parts, part_poses(model, parts, q), strict=True):
                    node[part.name].set_transform(T)
                if frame_id is not None:
                    node["measured_frame"].set_transform(frame_pose(model, frame_id, q))

        cycle = [*qs, qs[0]]
        start = 0
        for k, (q_from, q_to) in enumerate(itertools.pairwise(cycle)):
            key(start, q_from)
            key(start + hold, q_from)
            for s in range(1, steps + 1):
                t = s / steps
                key(start + hold + round(t * move), pin.interpolate(model, q_from, q_to, t))
            start += hold + move
            if progress is not None:
                progress(len(qs) + k + 1, total)
        vis.window.send(_SetAnimationLooped(animation))

    width = 0.006 * size
    for k, (a, e) in enumerate(zip(arrows, drawn_ends, strict=True)):
        rgb = parse_colour(a.colour)
        draw_arrow(root["arrows"][f"arrow{k}"], a.start, e, rgb, width)
        legend["arrows"].append((rgb, a.label, float(np.linalg.norm(a.end - a.start))))

    log.debug("scene centre %s radius %.3f m", centre, radius)
    floor = vis[f"{_ROOT}_floor"]
    floor.set_transform(pin.SE3(np.eye(3), -centre).homogeneous)
    legend["grid_cell"] = draw_floor_grid(floor, lo, hi)
    set_camera(vis, radius, hi - lo)
    return legend


# --------------------------------------------------------------------------- HTML

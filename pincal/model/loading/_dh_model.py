"""A DH table as a pincal model: URDF text, parameter preset and DH ↔ parameter names.

See :mod:`pincal.model.loading._dh` for the conventions and the two-joints-per-row layout.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from pincal.errors import ModelFileError, ParameterError, UnknownNameError
from pincal.model.loading._dh import (
    DH_QUANTITIES,
    Convention,
    DHError,
    DHQuantity,
    DHRow,
    check_dh_errors,
    dh_layout,
    probe_transform,
)

__all__ = ["dh_errors_to_parameters", "dh_preset", "dh_urdf", "parameters_to_dh_errors"]


# --------------------------------------------------------------------------- URDF


def _attr(value: str) -> str:
    """A double-quoted XML attribute value (``& < > "`` and line breaks escaped).

    Written here rather than imported from ``xml.sax.saxutils``, whose import pulls in
    ``urllib.request`` (tens of ms of every command's start).
    """
    for raw, esc in (("&", "&amp;"), ("<", "&lt;"), (">", "&gt;"), ('"', "&quot;")):
        value = value.replace(raw, esc)
    for raw, esc in (("\n", "&#10;"), ("\r", "&#13;"), ("\t", "&#9;")):
        value = value.replace(raw, esc)
    return f'"{value}"'


def _f(x: float) -> str:
    """Float in shortest round-trip form (exact when re-read)."""
    x = float(x)
    return "0" if x == 0.0 else repr(x)


def _origin(xyz: Sequence[float], rpy: Sequence[float]) -> str:
    return f'<origin xyz="{" ".join(_f(v) for v in xyz)}" rpy="{" ".join(_f(v) for v in rpy)}"/>'


def _cylinder(length: float, radius: float, xyz: Sequence[float], rpy: Sequence[float]) -> str:
    return (
        f"    <visual>\n      {_origin(xyz, rpy)}\n"
        f'      <geometry><cylinder radius="{_f(radius)}" length="{_f(length)}"/></geometry>\n'
        f'      <material name="pincal_grey"/>\n    </visual>\n'
    )


def _link(name: str, visuals: Sequence[str] = ()) -> str:
    if not visuals:
        return f"  <link name={_attr(name)}/>\n"
    return f"  <link name={_attr(name)}>\n{''.join(visuals)}  </link>\n"


def _joint(
    name: str,
    jtype: str,
    parent: str,
    child: str,
    origin: str,
    limits: tuple[float, float] | None = None,
) -> str:
    text = (
        f"  <joint name={_attr(name)} type={_attr(jtype)}>\n"
        f"    <parent link={_attr(parent)}/>\n    <child link={_attr(child)}/>\n"
        f"    {origin}\n"
    )
    if jtype != "fixed":
        text += '    <axis xyz="0 0 1"/>\n'
    if limits is not None:
        text += (
            f'    <limit lower="{_f(limits[0])}" upper="{_f(limits[1])}" '
            'effort="100" velocity="1"/>\n'
        )
    return text + "  </joint>\n"


def _limits(row: DHRow) -> tuple[float, float] | None:
    if row.joint_type == "fixed":
        return None
    default = math.pi if row.joint_type == "revolute" else 1.0
    lower = -default if row.lower is None else float(row.lower)
    upper = default if row.upper is None else float(row.upper)
    if not lower < upper:
        raise ModelFileError(f"joint limits must satisfy lower < upper, got [{lower}, {upper}]")
    return lower, upper


def _rpy_from_matrix(R: np.ndarray) -> tuple[float, float, float]:
    """URDF roll-pitch-yaw (R = Rz(y)·Ry(p)·Rx(r)) of a rotation matrix."""
    pitch = math.atan2(-R[2, 0], math.hypot(R[0, 0], R[1, 0]))
    if math.cos(pitch) > 1e-12:
        roll = math.atan2(R[2, 1], R[2, 2])
        yaw = math.atan2(R[1, 0], R[0, 0])
    else:  # gimbal lock: put everything into yaw
        roll = 0.0
        yaw = math.atan2(-R[0, 1], R[1, 1])
    return roll, pitch, yaw


def dh_urdf(
    rows: Sequence[DHRow],
    name: str,
    convention: Convention = "standard",
    probe: Sequence[float] | np.ndarray | None = None,
    joint_names: Sequence[str] | None = None,
    link_names: Sequence[str] | None = None,
    base_link: str = "base_link",
    visual_radius: float | None = 0.015,
) -> str:
    """URDF text of a serial chain given by a DH table.

    Loaded in Pinocchio, the pose of link ``names[i].link`` at configuration q
    equals the DH product ``T_01 ⋯ T_0i`` exactly (to rounding); see the module
    docstring for the joint layout and why each DH error is a single-dof twist.

    Args:
        rows: DH table (SI units: m, rad).
        name: robot name.
        convention: ``"standard"`` or ``"modified"``.
        probe: optional tool point, a position (3,) [m] or a 4x4 transform in the
            last DH frame; adds ``probe_joint`` (fixed) and link ``probe``.
        joint_names: URDF names of the motion joints, one per row (default
            ``joint1 … jointN``; see :func:`dh_layout`).
        link_names: URDF names of the DH frame links, one per row (default
            ``link1 … linkN``).
        base_link: URDF name of the DH frame 0 (the root link).
        visual_radius: radius [m] of the cylinder visuals along d and a; None
            for no visuals.

    Returns:
        The URDF document as a string.
    """
    layout = dh_layout(rows, convention, joint_names, link_names, base_link, probe is not None)
    parts = [f'<?xml version="1.0"?>\n<robot name={_attr(name)}>\n']
    parts.append('  <material name="pincal_grey"><color rgba="0.6 0.6 0.65 1"/></material>\n')
    parts.append(_link(base_link))
    parent = base_link
    r = visual_radius
    for row, nm in zip(layout.rows, layout.names, strict=True):
        motion_origin = _origin((0.0, 0.0, row.d), (0.0, 0.0, row.theta_offset))
        link_origin = _origin((row.a, 0.0, 0.0), (row.alpha, 0.0, 0.0))
        # visuals: the d segment ends at the motion joint's child origin (along z),
        # the a segment ends at the link joint's child origin (along x).
        d_vis, a_vis = [], []
        if r is not None:
            if row.joint_type != "fixed":
                d_vis.append(_cylinder(6 * r, 1.6 * r, (0, 0, 0), (0, 0, 0)))
            if abs(row.d) > 1e-9:
                d_vis.append(_cylinder(abs(row.d), r, (0, 0, -row.d / 2), (0, 0, 0)))
            if abs(row.a) > 1e-9:
                a_vis.append(_cylinder(abs(row.a), r, (-row.a / 2, 0, 0), (0, math.pi / 2, 0)))
        motion = (row.joint_type, motion_origin, _limits(row), d_vis)
        fixed = ("fixed", link_origin, None, a_vis)
        first, second = (
            ((nm.joint, motion), (nm.link_joint, fixed))
            if convention == "standard"
            else ((nm.link_joint, fixed), (nm.joint, motion))
        )
        for jname, (jtype, origin, limits, vis), child in (
            (*first, nm.mid_link),
            (*second, nm.link),
        ):
            parts.append(_link(child, vis))
            parts.append(_joint(jname, jtype, parent, child, origin, limits))
            parent = child
    if probe is not None:
        T = probe_transform(probe)
        parts.append(_link("probe"))
        parts.append(
            _joint(
                "probe_joint",
                "fixed",
                parent,
                "probe",
                _origin(T[:3, 3].tolist(), _rpy_from_matrix(T)),
            )
        )
    parts.append("</robot>\n")
    return "".join(parts)


# --------------------------------------------------------------------------- parameters


def dh_preset(
    rows: Sequence[DHRow],
    convention: Convention = "standard",
    joint_names: Sequence[str] | None = None,
    link_names: Sequence[str] | None = None,
    quantities: Sequence[DHQuantity] = DH_QUANTITIES,
    links: Sequence[int] | None = None,
) -> list[dict[str, object]]:
    """Preset entries (``{"joints": name, "dofs": [...]}``) for DH errors.

    For every selected row (0-based indices ``links``, default all) and quantity
    (``"a"``, ``"d"``, ``"alpha"``, ``"theta"``), one parameter; the entries are
    ordered row by row, the motion joint (d, θ) and the link joint (a, α) of a
    row each in one entry. Parameter names follow :meth:`DHNames.parameter`.
    """
    layout = dh_layout(rows, convention, joint_names, link_names)
    for qn in quantities:
        if qn not in DH_QUANTITIES:
            raise UnknownNameError("DH quantity", str(qn), DH_QUANTITIES)
    selected = range(len(layout.rows)) if links is None else links
    entries: list[dict[str, object]] = []
    for i in selected:
        if not 0 <= i < len(layout.names):
            raise ParameterError(f"DH row index {i} out of range 0..{len(layout.names) - 1}")
        nm = layout.names[i]
        by_joint: dict[str, list[str]] = {}
        for qn in DH_QUANTITIES:
            if qn in quantities:
                joint, dof = nm.parameter(qn).split(".")
                by_joint.setdefault(joint, []).append(dof)
        order = (nm.joint, nm.link_joint) if convention == "standard" else (nm.link_joint, nm.joint)
        entries += [{"joints": j, "dofs": by_joint[j]} for j in order if j in by_joint]
    return entries


def dh_errors_to_parameters(
    errors: Sequence[DHError],
    rows: Sequence[DHRow],
    convention: Convention = "standard",
    joint_names: Sequence[str] | None = None,
    link_names: Sequence[str] | None = None,
) -> dict[str, float]:
    """Values [m, rad] of the pincal parameters equal to the given DH errors.

    The mapping is exact and unscaled (Δa ↦ ``<link joint>.tx``, Δα ↦ ``.rx``,
    Δd ↦ ``<joint>.tz`` / ``.offset``, Δθ ↦ ``<joint>.offset`` / ``.rz``).
    """
    layout = dh_layout(rows, convention, joint_names, link_names)
    errs = check_dh_errors(errors, len(layout.rows))
    values: dict[str, float] = {}
    for nm, e in zip(layout.names, errs, strict=True):
        values[nm.parameter("a")] = float(e.da)
        values[nm.parameter("d")] = float(e.dd)
        values[nm.parameter("alpha")] = float(e.dalpha)
        values[nm.parameter("theta")] = float(e.dtheta)
    return values


def parameters_to_dh_errors(
    values: Mapping[str, float],
    rows: Sequence[DHRow],
    convention: Convention = "standard",
    joint_names: Sequence[str] | None = None,
    link_names: Sequence[str] | None = None,
) -> list[DHError]:
    """DH errors per row read from pincal parameter values (missing names are 0).

    Raises:
        UnknownNameError: a parameter name is not one of the DH parameters.
    """
    layout = dh_layout(rows, convention, joint_names, link_names)
    valid = [nm.parameter(qn) for nm in layout.names for qn in DH_QUANTITIES]
    for key in values:
        if key not in valid:
            raise UnknownNameError("DH parameter", key, valid)
    return [
        DHError(
            da=float(values.get(nm.parameter("a"), 0.0)),
            dd=float(values.get(nm.parameter("d"), 0.0)),
            dalpha=float(values.get(nm.parameter("alpha"), 0.0)),
            dtheta=float(values.get(nm.parameter("theta"), 0.0)),
        )
        for nm in layout.names
    ]

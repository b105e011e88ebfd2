"""Model builders: Denavit–Hartenberg tables to URDF, and example-robot-data lookup.

DH tables
---------
A DH row describes one link of a serial chain. Two conventions are supported
(θ_i = joint variable + ``theta_offset``):

- ``"standard"`` (Denavit–Hartenberg, seed 004, eq. 1):
  ``T_{i-1,i} = Rz(θ_i) · Tz(d_i) · Tx(a_i) · Rx(α_i)``
- ``"modified"`` (Craig): ``T_{i-1,i} = Rx(α_{i-1}) · Tx(a_{i-1}) · Rz(θ_i) · Tz(d_i)``;
  row i then holds ``a_{i-1}`` and ``α_{i-1}`` in its ``a`` and ``alpha`` fields.

Every DH row becomes two URDF joints, chosen so that each DH error is one
single-dof twist of one joint origin (``origin ← origin · exp6(v)``), which is
exact because a single-dof twist is a pure translation or a pure rotation:

- the *motion* joint (revolute, prismatic or fixed), axis z, origin
  ``Tz(d) · Rz(θ_offset)`` (``xyz="0 0 d" rpy="0 0 θ_offset"``). Since Tz and Rz
  about the same axis commute, ``origin · Tz(δ) = Tz(d + δ) · Rz(θ_offset)`` and
  ``origin · Rz(δ) = Tz(d) · Rz(θ_offset + δ)``: Δd is the twist ``tz`` and Δθ the
  twist ``rz`` of this origin. For a revolute joint Δθ is the encoder zero, i.e.
  the joint ``offset``; for a prismatic joint Δd is the ``offset``.
- the fixed *link* joint, origin ``Tx(a) · Rx(α)`` (``xyz="a 0 0" rpy="α 0 0"``):
  ``origin · Tx(δ) = Tx(a + δ) · Rx(α)`` and ``origin · Rx(δ) = Tx(a) · Rx(α + δ)``,
  so Δa is the twist ``tx`` and Δα the twist ``rx`` of this origin.

Standard DH puts the motion joint first (``Rz Tz`` then ``Tx Rx``); modified DH
puts the link joint first. The URDF therefore reproduces the DH forward
kinematics exactly, and the DH error values *are* the pincal parameter values
(same units, m and rad, no scaling): :func:`dh_errors_to_parameters` and
:func:`parameters_to_dh_errors` only rename them.

Link naming for row i (1-based) with DH frame link ``L`` (default ``link{i}``) and
motion joint ``J`` (default ``joint{i}``): standard ``parent → J → L_z → J_ax → L``,
modified ``parent → J_ax → L_x → J → L``. An optional probe (tool point) is a
fixed joint ``probe_joint`` from the last DH frame to link ``probe``.
"""

from __future__ import annotations

import importlib.metadata
import logging
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Literal
from xml.sax.saxutils import quoteattr

import numpy as np

from pincal.errors import ModelFileError, ParameterError, UnknownNameError

__all__ = [
    "DHError",
    "DHLayout",
    "DHNames",
    "DHRow",
    "dh_apply_errors",
    "dh_errors_to_parameters",
    "dh_fk",
    "dh_layout",
    "dh_preset",
    "dh_urdf",
    "example_robot_names",
    "example_robot_urdf",
    "parameters_to_dh_errors",
]

logger = logging.getLogger(__name__)

Convention = Literal["standard", "modified"]
JointType = Literal["revolute", "prismatic", "fixed"]
DHQuantity = Literal["a", "d", "alpha", "theta"]

_CONVENTIONS = ("standard", "modified")
_JOINT_TYPES = ("revolute", "prismatic", "fixed")
_QUANTITIES: tuple[DHQuantity, ...] = ("a", "d", "alpha", "theta")


# --------------------------------------------------------------------------- data


@dataclass(frozen=True)
class DHRow:
    """One row of a DH table (SI units).

    Attributes:
        a: link length [m] (``a_{i-1}`` in the modified convention).
        d: link offset along the joint axis [m] (for a prismatic joint: at q = 0).
        alpha: link twist [rad] (``α_{i-1}`` in the modified convention).
        theta_offset: joint angle at q = 0 [rad] (θ_i = q_i + theta_offset).
        joint_type: ``"revolute"``, ``"prismatic"`` or ``"fixed"`` (a constant
            link such as a probe; θ_i = theta_offset).
        lower, upper: joint limits [rad or m]; default ±π (revolute), ±1 m
            (prismatic).
    """

    a: float
    d: float
    alpha: float
    theta_offset: float = 0.0
    joint_type: JointType = "revolute"
    lower: float | None = None
    upper: float | None = None


@dataclass(frozen=True)
class DHError:
    """Errors of one DH row [m, rad]: Δa, Δd, Δα, Δθ (θ error = joint zero offset)."""

    da: float = 0.0
    dd: float = 0.0
    dalpha: float = 0.0
    dtheta: float = 0.0


@dataclass(frozen=True)
class DHNames:
    """URDF names generated for one DH row.

    Attributes:
        joint: motion joint (carries d and θ: dofs ``tz`` and ``rz``/``offset``).
        link_joint: fixed joint (carries a and α: dofs ``tx`` and ``rx``).
        link: the DH frame i (a URDF link).
        mid_link: the link between the two joints.
        joint_type: the motion joint's type.
    """

    joint: str
    link_joint: str
    link: str
    mid_link: str
    joint_type: JointType

    def parameter(self, quantity: DHQuantity) -> str:
        """pincal parameter name (``<urdf joint>.<dof>``) of this row's DH ``quantity``."""
        if quantity == "a":
            return f"{self.link_joint}.tx"
        if quantity == "alpha":
            return f"{self.link_joint}.rx"
        if quantity == "d":
            dof = "offset" if self.joint_type == "prismatic" else "tz"
            return f"{self.joint}.{dof}"
        if quantity == "theta":
            dof = "offset" if self.joint_type == "revolute" else "rz"
            return f"{self.joint}.{dof}"
        raise UnknownNameError("DH quantity", str(quantity), _QUANTITIES)


@dataclass(frozen=True)
class DHLayout:
    """How a DH table maps onto URDF joints and links (see module docstring)."""

    convention: Convention
    base_link: str
    rows: tuple[DHRow, ...]
    names: tuple[DHNames, ...]
    probe_joint: str | None = None
    probe_link: str | None = None

    @property
    def tip_link(self) -> str:
        """The last link of the chain (probe if any, else the last DH frame)."""
        return self.probe_link if self.probe_link is not None else self.names[-1].link

    def parameter_name(self, row: int, quantity: DHQuantity) -> str:
        """Parameter name of DH ``quantity`` of ``row`` (0-based)."""
        return self.names[row].parameter(quantity)


# --------------------------------------------------------------------------- layout


def _check_rows(rows: Sequence[DHRow]) -> tuple[DHRow, ...]:
    rows = tuple(rows)
    if not rows:
        raise ModelFileError("a DH table needs at least one row")
    for i, row in enumerate(rows):
        if not isinstance(row, DHRow):
            raise ModelFileError(f"DH row {i + 1} is a {type(row).__name__}, expected DHRow")
        if row.joint_type not in _JOINT_TYPES:
            raise UnknownNameError("joint type", row.joint_type, _JOINT_TYPES)
        values = (row.a, row.d, row.alpha, row.theta_offset)
        if not all(math.isfinite(float(v)) for v in values):
            raise ModelFileError(f"DH row {i + 1} has a non-finite value: {values}")
    return rows


def dh_layout(
    rows: Sequence[DHRow],
    convention: Convention = "standard",
    joint_names: Sequence[str] | None = None,
    link_names: Sequence[str] | None = None,
    base_link: str = "base_link",
    probe: bool = False,
) -> DHLayout:
    """URDF names of a DH table (no geometry); shared by all DH functions.

    Args:
        rows: the DH table, one :class:`DHRow` per link.
        convention: ``"standard"`` or ``"modified"``.
        joint_names: motion joint names (default ``joint1 … jointN``).
        link_names: DH frame link names (default ``link1 … linkN``).
        base_link: name of the DH frame 0.
        probe: whether a probe joint/link (``probe_joint``/``probe``) follows.
    """
    rows = _check_rows(rows)
    if convention not in _CONVENTIONS:
        raise UnknownNameError("DH convention", str(convention), _CONVENTIONS)
    n = len(rows)
    joints = list(joint_names) if joint_names is not None else [f"joint{i + 1}" for i in range(n)]
    links = list(link_names) if link_names is not None else [f"link{i + 1}" for i in range(n)]
    for kind, given in (("joint_names", joints), ("link_names", links)):
        if len(given) != n:
            raise ModelFileError(f"{kind} has {len(given)} names, the DH table has {n} rows")
    mid_suffix = "_z" if convention == "standard" else "_x"
    names = tuple(
        DHNames(
            joint=j,
            link_joint=f"{j}_ax",
            link=link,
            mid_link=f"{link}{mid_suffix}",
            joint_type=row.joint_type,
        )
        for j, link, row in zip(joints, links, rows, strict=True)
    )
    every = [base_link]
    for nm in names:
        every += [nm.joint, nm.link_joint, nm.link, nm.mid_link]
    if probe:
        every += ["probe_joint", "probe"]
    duplicates = sorted({x for x in every if every.count(x) > 1})
    if duplicates:
        raise ModelFileError(f"DH layout has duplicate URDF names: {duplicates}")
    return DHLayout(
        convention=convention,
        base_link=base_link,
        rows=rows,
        names=names,
        probe_joint="probe_joint" if probe else None,
        probe_link="probe" if probe else None,
    )


# --------------------------------------------------------------------------- URDF


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
        return f"  <link name={quoteattr(name)}/>\n"
    return f"  <link name={quoteattr(name)}>\n{''.join(visuals)}  </link>\n"


def _joint(
    name: str,
    jtype: str,
    parent: str,
    child: str,
    origin: str,
    limits: tuple[float, float] | None = None,
) -> str:
    text = (
        f"  <joint name={quoteattr(name)} type={quoteattr(jtype)}>\n"
        f"    <parent link={quoteattr(parent)}/>\n    <child link={quoteattr(child)}/>\n"
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


def _probe_transform(probe: Sequence[float] | np.ndarray) -> np.ndarray:
    arr = np.asarray(probe, dtype=float)
    if arr.shape == (3,):
        T = np.eye(4)
        T[:3, 3] = arr
        return T
    if arr.shape == (4, 4):
        return arr.copy()
    raise ModelFileError(f"probe must be a position (3,) [m] or a 4x4 transform, got {arr.shape}")


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
        joint_names, link_names, base_link: URDF names (see :func:`dh_layout`).
        visual_radius: radius [m] of the cylinder visuals along d and a; None
            for no visuals.

    Returns:
        The URDF document as a string.
    """
    layout = dh_layout(rows, convention, joint_names, link_names, base_link, probe is not None)
    parts = [f'<?xml version="1.0"?>\n<robot name={quoteattr(name)}>\n']
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
        T = _probe_transform(probe)
        parts.append(_link("probe"))
        parts.append(
            _joint("probe_joint", "fixed", parent, "probe", _origin(T[:3, 3], _rpy_from_matrix(T)))
        )
    parts.append("</robot>\n")
    return "".join(parts)


# --------------------------------------------------------------------------- numpy FK


def _dh_matrix(theta: float, d: float, a: float, alpha: float, convention: str) -> np.ndarray:
    ct, st, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
    if convention == "standard":  # Rz(θ) Tz(d) Tx(a) Rx(α)
        return np.array(
            [
                [ct, -st * ca, st * sa, a * ct],
                [st, ct * ca, -ct * sa, a * st],
                [0.0, sa, ca, d],
                [0.0, 0.0, 0.0, 1.0],
            ]
        )
    # modified: Rx(α) Tx(a) Rz(θ) Tz(d)
    return np.array(
        [
            [ct, -st, 0.0, a],
            [st * ca, ct * ca, -sa, -sa * d],
            [st * sa, ct * sa, ca, ca * d],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def dh_fk(
    rows: Sequence[DHRow],
    q: Sequence[float] | np.ndarray,
    convention: Convention = "standard",
    errors: Sequence[DHError] | None = None,
    probe: Sequence[float] | np.ndarray | None = None,
) -> np.ndarray:
    """Plain-numpy DH forward kinematics (independent of Pinocchio).

    Args:
        rows: DH table (m, rad).
        q: joint values of the non-fixed rows, shape (n_movable,) [rad or m].
        convention: ``"standard"`` or ``"modified"``.
        errors: optional Δa, Δd, Δα, Δθ per row (added to the nominal values).
        probe: optional tool point (3,) [m] or 4x4 transform in the last DH frame.

    Returns:
        ``T_base_tip``, shape (4, 4): pose of the last DH frame (or the probe).
    """
    rows = _check_rows(rows)
    if convention not in _CONVENTIONS:
        raise UnknownNameError("DH convention", str(convention), _CONVENTIONS)
    q = np.asarray(q, dtype=float).reshape(-1)
    n_movable = sum(r.joint_type != "fixed" for r in rows)
    if q.shape != (n_movable,):
        raise ParameterError(f"q must have shape ({n_movable},), got {q.shape}")
    errs = _check_errors(errors, len(rows))
    T = np.eye(4)
    k = 0
    for row, e in zip(rows, errs, strict=True):
        theta, d = row.theta_offset + e.dtheta, row.d + e.dd
        if row.joint_type == "revolute":
            theta += q[k]
        elif row.joint_type == "prismatic":
            d += q[k]
        k += row.joint_type != "fixed"
        T = T @ _dh_matrix(theta, d, row.a + e.da, row.alpha + e.dalpha, convention)
    if probe is not None:
        T = T @ _probe_transform(probe)
    return T


def _check_errors(errors: Sequence[DHError] | None, n: int) -> tuple[DHError, ...]:
    if errors is None:
        return (DHError(),) * n
    errs = tuple(errors)
    if len(errs) != n:
        raise ParameterError(f"got {len(errs)} DH errors for {n} DH rows")
    return errs


def dh_apply_errors(rows: Sequence[DHRow], errors: Sequence[DHError]) -> list[DHRow]:
    """New DH rows with the errors added to a, d, α and θ-offset (inputs unchanged)."""
    rows = _check_rows(rows)
    errs = _check_errors(errors, len(rows))
    return [
        DHRow(
            a=r.a + e.da,
            d=r.d + e.dd,
            alpha=r.alpha + e.dalpha,
            theta_offset=r.theta_offset + e.dtheta,
            joint_type=r.joint_type,
            lower=r.lower,
            upper=r.upper,
        )
        for r, e in zip(rows, errs, strict=True)
    ]


# --------------------------------------------------------------------------- parameters


def dh_preset(
    rows: Sequence[DHRow],
    convention: Convention = "standard",
    joint_names: Sequence[str] | None = None,
    link_names: Sequence[str] | None = None,
    quantities: Sequence[DHQuantity] = _QUANTITIES,
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
        if qn not in _QUANTITIES:
            raise UnknownNameError("DH quantity", str(qn), _QUANTITIES)
    selected = range(len(layout.rows)) if links is None else links
    entries: list[dict[str, object]] = []
    for i in selected:
        if not 0 <= i < len(layout.names):
            raise ParameterError(f"DH row index {i} out of range 0..{len(layout.names) - 1}")
        nm = layout.names[i]
        by_joint: dict[str, list[str]] = {}
        for qn in _QUANTITIES:
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
    """pincal parameter values [m, rad] equal to the given DH errors.

    The mapping is exact and unscaled (Δa ↦ ``<link joint>.tx``, Δα ↦ ``.rx``,
    Δd ↦ ``<joint>.tz`` / ``.offset``, Δθ ↦ ``<joint>.offset`` / ``.rz``).
    """
    layout = dh_layout(rows, convention, joint_names, link_names)
    errs = _check_errors(errors, len(layout.rows))
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
    valid = [nm.parameter(qn) for nm in layout.names for qn in _QUANTITIES]
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


# --------------------------------------------------------------------------- example-robot-data

#: short names for robots whose URDF file stem differs from the usual name.
_ERD_ALIASES = {"ur10": "ur10_robot", "ur5": "ur5_robot"}
_ERD_MARKER = "share/example-robot-data/robots/"


def _erd_index() -> tuple[dict[str, Path], list[str]]:
    """(all accepted names → path, the short names to show)."""
    try:
        dist = importlib.metadata.distribution("example-robot-data")
    except importlib.metadata.PackageNotFoundError as exc:
        raise ModelFileError(
            "the example-robot-data package is not installed (pip install example-robot-data)"
        ) from exc
    files = [f for f in (dist.files or ()) if _ERD_MARKER in str(f) and str(f).endswith(".urdf")]
    by_stem: dict[str, list[Path]] = {}
    for f in files:
        path = Path(str(dist.locate_file(f)))
        by_stem.setdefault(path.stem, []).append(path)
    index: dict[str, Path] = {}
    shown: list[str] = []
    for stem, paths in by_stem.items():
        for path in paths:
            package = path.relative_to(_erd_robots_dir(path)).parts[0]
            qualified = f"{package.removesuffix('_description')}/{stem}"
            index[qualified] = path
            if len(paths) > 1:
                shown.append(qualified)
        if len(paths) == 1:
            index[stem] = paths[0]
            shown.append(stem)
    for alias, stem in _ERD_ALIASES.items():
        if alias not in index and stem in index:
            index[alias] = index[stem]
            shown.append(alias)
    return index, sorted(shown)


def _erd_robots_dir(path: Path) -> Path:
    for parent in path.parents:
        if parent.name == "robots" and parent.parent.name == "example-robot-data":
            return parent
    raise ModelFileError(f"{path} is not inside example-robot-data/robots")


def example_robot_names() -> list[str]:
    """Robot names for :func:`example_robot_urdf`, sorted.

    A name is the URDF file stem (``panda``, ``ur10_robot``), or
    ``<package>/<stem>`` (``anymal_b_simple/anymal``) when the stem is ambiguous,
    plus the aliases ``ur5`` and ``ur10``. The qualified form ``<package>/<stem>``
    is accepted for every robot but only listed for ambiguous stems.
    """
    return _erd_index()[1]


def example_robot_urdf(name: str) -> Path:
    """Path of a URDF shipped by the installed example-robot-data package.

    Resolved from the installed distribution's file list (no network, no ROS).
    Natural measured frames: UR arms ``tool0`` (fixed joint
    ``wrist_3_link-tool0_fixed_joint`` on ``wrist_3_link``); Panda
    ``panda_hand_tcp`` or ``panda_hand`` (fixed joints on ``panda_link8``, itself
    fixed on ``panda_link7``; the two finger joints are prismatic).

    Raises:
        UnknownNameError: ``name`` is not a known robot (the message lists them).
        ModelFileError: example-robot-data is not installed or the file is missing.
    """
    index, shown = _erd_index()
    if name not in index:
        raise UnknownNameError("robot", name, shown)
    path = index[name]
    if not path.is_file():
        raise ModelFileError(f"example-robot-data lists {path} but the file does not exist")
    return path

"""Model builders: Denavit–Hartenberg tables to URDF.

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

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np

from pincal.errors import ModelFileError, ParameterError, UnknownNameError

__all__ = [
    "DHError",
    "DHLayout",
    "DHNames",
    "DHRow",
    "dh_apply_errors",
    "dh_fk",
    "dh_layout",
]

logger = logging.getLogger(__name__)

Convention = Literal["standard", "modified"]
JointType = Literal["revolute", "prismatic", "fixed"]
DHQuantity = Literal["a", "d", "alpha", "theta"]

_CONVENTIONS = ("standard", "modified")
_JOINT_TYPES = ("revolute", "prismatic", "fixed")
DH_QUANTITIES: tuple[DHQuantity, ...] = ("a", "d", "alpha", "theta")


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
        """Name of the pincal parameter (``<urdf joint>.<dof>``) of this row's DH ``quantity``."""
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
        raise UnknownNameError("DH quantity", str(quantity), DH_QUANTITIES)


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


def probe_transform(probe: Sequence[float] | np.ndarray) -> np.ndarray:
    """(4, 4) probe transform from a (3,) offset [m] or a (4, 4) matrix."""
    try:
        arr = np.asarray(probe, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ModelFileError(f"probe must be numbers: {exc}") from exc
    if arr.shape == (3,):
        T = np.eye(4)
        T[:3, 3] = arr
        return T
    if arr.shape == (4, 4):
        return arr.copy()
    raise ModelFileError(f"probe must be a position (3,) [m] or a 4x4 transform, got {arr.shape}")


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
    try:
        q = np.asarray(q, dtype=float).reshape(-1)
    except (TypeError, ValueError) as exc:
        raise ParameterError(f"q must be numbers: {exc}") from exc
    n_movable = sum(r.joint_type != "fixed" for r in rows)
    if q.shape != (n_movable,):
        raise ParameterError(f"q must have shape ({n_movable},), got {q.shape}")
    errs = check_dh_errors(errors, len(rows))
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
        T = T @ probe_transform(probe)
    return T


def check_dh_errors(errors: Sequence[DHError] | None, n: int) -> tuple[DHError, ...]:
    """One DHError per row (None → zeros); ParameterError on a wrong count."""
    if errors is None:
        return (DHError(),) * n
    errs = tuple(errors)
    if len(errs) != n:
        raise ParameterError(f"got {len(errs)} DH errors for {n} DH rows")
    return errs


def dh_apply_errors(rows: Sequence[DHRow], errors: Sequence[DHError]) -> list[DHRow]:
    """New DH rows with the errors added to a, d, α and θ-offset (inputs unchanged)."""
    rows = _check_rows(rows)
    errs = check_dh_errors(errors, len(rows))
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

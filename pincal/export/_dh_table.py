"""``dh-standard`` / ``dh-modified``: a DH table fitted to a serial arm's joint axes (YAML).

The controller's forward kinematics, with ``θ_i = q_i + theta_offset_i`` (``q_i`` the
joint reading)::

    T_tool(q) = B · A_1(θ_1) ··· A_n(θ_n) · E                              (1)
    standard (Denavit–Hartenberg):  A_i = Rz(θ_i) Tz(d_i) Tx(a_i) Rx(α_i)
    modified (Craig):               A_i = Rx(α_{i-1}) Tx(a_{i-1}) Rz(θ_i) Tz(d_i)

``B`` (world → frame 0) and ``E`` (frame n → measured frame) are written as ``xyz``
[m] and ``rpy`` [rad] (``R = Rz(yaw)·Ry(pitch)·Rx(roll)``). The table is fitted to the
calibrated model's axes at zero readings (:mod:`pincal.export._dh_fit`: common normals,
conventions); the nominal model's table by the same construction is written beside it,
and ``zero_offset = theta_offset − nominal theta_offset`` per joint. Revolute joints
only. Not expressed: actuator gains and other joint terms, and the tilt of axes fitted
by the parallel convention.
"""

from __future__ import annotations

import json
from typing import ClassVar

import numpy as np
import pinocchio as pin

from pincal.errors import ExportError
from pincal.export._dh_fit import DHFit, fit_dh
from pincal.export._format import Built, ControllerFormat, fmt_number
from pincal.export._machine import CalibratedMachine
from pincal.model import Mechanism

__all__ = [
    "ModifiedDH",
    "StandardDH",
    "as_written",
    "joint_axes",
    "transform",
    "xyz_rpy",
    "yaml_seq",
]


def as_written(x: float) -> float:
    """``x`` as the table writes it (12 decimals)."""
    return float(fmt_number(x))


def joint_axes(mech: Mechanism) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Joint axis points and directions (n, 3) and the tool pose (4, 4) at zero readings.

    Raises:
        ExportError: a closed chain, a joint that is not revolute, or actuated joints
            that are not one chain from the base to the tool.
    """
    joints = mech.tree.joints
    if mech.closures:
        raise ExportError(
            f"a DH table describes a serial arm; {mech.name!r} has loop closures "
            f"(use --format generic-table)"
        )
    bad = [j for j in mech.actuated if joints[j].type not in ("revolute", "continuous")]
    if bad:
        raise ExportError(f"the DH export takes revolute joints only; {bad} are not")
    parent_of = {uj.child: uj for uj in joints.values()}
    chain: list[str] = []
    link = mech.frame_link(mech.measured_frame)
    while link in parent_of:
        chain.append(parent_of[link].name)
        link = parent_of[link].parent
    order = [j for j in reversed(chain) if j in mech.actuated]
    if order != list(mech.actuated):
        raise ExportError(
            f"the actuated joints {list(mech.actuated)} are not one chain from the base to "
            f"{mech.measured_frame!r} in this order"
        )
    q = mech.configuration(np.zeros(len(mech.actuated)))
    points, dirs = [], []
    for j in mech.actuated:
        M = mech.frame_placement(q, j)
        points.append(M.translation)
        dirs.append(M.rotation @ joints[j].axis)
    return np.array(points), np.array(dirs), mech.frame_placement(q).homogeneous


def xyz_rpy(T: np.ndarray) -> tuple[list[float], list[float]]:
    """(xyz [m], rpy [rad]) of a (4, 4) transform, as written."""
    rpy = pin.rpy.matrixToRpy(T[:3, :3])
    return [as_written(v) for v in T[:3, 3]], [as_written(v) for v in rpy]


def transform(xyz: list[float], rpy: list[float]) -> np.ndarray:
    """The (4, 4) transform of ``xyz`` [m] and ``rpy`` [rad] (``R = Rz·Ry·Rx``)."""
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = pin.rpy.rpyToMatrix(np.array(rpy)), xyz
    return T


def yaml_seq(values: list[float]) -> str:
    """A YAML flow sequence of numbers as written."""
    return "[" + ", ".join(fmt_number(v) for v in values) + "]"


def _rot(axis: int, angle: float) -> np.ndarray:
    T = np.eye(4)
    c, s = np.cos(angle), np.sin(angle)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    T[i, i], T[i, j], T[j, i], T[j, j] = c, -s, s, c
    return T


def _trans(axis: int, length: float) -> np.ndarray:
    T = np.eye(4)
    T[axis, 3] = length
    return T


class _DHTable(ControllerFormat):
    """A DH table of one convention (subclasses fix it)."""

    modified: ClassVar[bool]
    suffix: ClassVar[str] = ".yaml"

    def _link(self, a: float, alpha: float, theta: float, d: float) -> np.ndarray:
        if self.modified:
            return _rot(0, alpha) @ _trans(0, a) @ _rot(2, theta) @ _trans(2, d)
        return _rot(2, theta) @ _trans(2, d) @ _trans(0, a) @ _rot(0, alpha)

    def build(self, machine: CalibratedMachine, q_fit: np.ndarray) -> Built:
        cal = machine.calibrated
        fit = fit_dh(*joint_axes(cal), self.modified)
        nominal = fit_dh(*joint_axes(machine.nominal), self.modified)
        rows = np.vectorize(as_written)(fit.rows)
        base_xyz, base_rpy = xyz_rpy(fit.base)
        tool_xyz, tool_rpy = xyz_rpy(fit.tool)
        B, E = transform(base_xyz, base_rpy), transform(tool_xyz, tool_rpy)

        def forward(q_act: np.ndarray) -> np.ndarray:
            out = np.empty((len(q_act), 4, 4))
            for s, q in enumerate(q_act):
                T = B
                for (a, alpha, theta, d), qi in zip(rows, q, strict=True):
                    T = T @ self._link(a, alpha, qi + theta, d)
                out[s] = T @ E
            return out

        lines = [
            f"convention: {'modified' if self.modified else 'standard'}",
            "equation: '"
            + (
                "A_i = Rx(alpha_i-1) Tx(a_i-1) Rz(theta_i) Tz(d_i)"
                if self.modified
                else "A_i = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i)"
            )
            + "; theta_i = q_i + theta_offset_i; T = base A_1 ... A_n tool'",
            "units: {length: m, angle: rad}",
            f"measured_frame: {json.dumps(cal.measured_frame)}",
            f"base: {{xyz: {yaml_seq(base_xyz)}, rpy: {yaml_seq(base_rpy)}}}",
            "rows:",
        ]
        for joint, row, nom in zip(cal.actuated, rows, nominal.rows, strict=True):
            a, alpha, theta, d = row
            lines += [
                f"  - joint: {json.dumps(joint)}",
                f"    a: {fmt_number(a)}",
                f"    alpha: {fmt_number(alpha)}",
                f"    d: {fmt_number(d)}",
                f"    theta_offset: {fmt_number(theta)}",
                f"    zero_offset: {fmt_number(np.angle(np.exp(1j * (theta - nom[2]))))}",
                f"    nominal: {{a: {fmt_number(nom[0])}, alpha: {fmt_number(nom[1])}, "
                f"d: {fmt_number(nom[3])}, theta_offset: {fmt_number(nom[2])}}}",
            ]
        lines.append(f"tool: {{xyz: {yaml_seq(tool_xyz)}, rpy: {yaml_seq(tool_rpy)}}}")
        return Built(
            "\n".join(lines) + "\n", forward, self._missing(machine, fit), self._conventions(fit)
        )

    def _missing(self, machine: CalibratedMachine, fit: DHFit) -> list[str]:
        names = machine.calibrated.actuated
        out = [
            f"the tilt {t * 1e6:.4g} urad between the axes of {names[i]} and {names[i + 1]} "
            f"(parallel convention)"
            for i, t in enumerate(fit.parallel)
            if np.isfinite(t) and t > 0.0
        ]
        out += [f"actuator gain {j}.gain = {g:.6g}" for j, g in machine.gains().items()]
        return out + [f"joint term {t}" for t in machine.terms_not_held(("gain",))]

    def _conventions(self, fit: DHFit) -> list[str]:
        out = [
            "frame 0 on the point of axis 1 nearest the world origin, base = world -> frame 0",
            "last frame: a_n = alpha_n = 0, theta offset 0, on axis n nearest the tool; "
            "tool = frame n -> measured frame",
            "parallel axes: the common normal through the previous origin (d_i = 0); axes "
            "whose common normal is farther than 10 arm sizes count as parallel",
        ]
        pairs = int(np.isfinite(fit.parallel).sum())
        if pairs:
            out.append(f"{pairs} axis pair(s) fitted by the parallel convention")
        return out


class StandardDH(_DHTable):
    """``dh-standard``: ``A_i = Rz(θ_i) Tz(d_i) Tx(a_i) Rx(α_i)`` (Denavit–Hartenberg)."""

    name: ClassVar[str] = "dh-standard"
    summary: ClassVar[str] = "standard DH table (Rz Tz Tx Rx) with base and tool transforms"
    modified: ClassVar[bool] = False


class ModifiedDH(_DHTable):
    """``dh-modified``: ``A_i = Rx(α_{i-1}) Tx(a_{i-1}) Rz(θ_i) Tz(d_i)`` (Craig)."""

    name: ClassVar[str] = "dh-modified"
    summary: ClassVar[str] = "modified DH table (Rx Tx Rz Tz, Craig) with base and tool"
    modified: ClassVar[bool] = True

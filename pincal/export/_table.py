"""``generic-table``: every joint placement and actuated zero offset, any machine (YAML).

The table holds, per URDF joint, its type, parent and child link, axis (unit, in the
joint frame) and its placement in the parent link frame, nominal and calibrated:
``xyz`` [m] and ``rpy`` [rad] with ``R = Rz(yaw)·Ry(pitch)·Rx(roll)`` (URDF). Per
actuated joint it holds the calibrated zero offset ``zero_offset`` [rad or m] and,
where the calibration has a gain, ``scale = 1 + g``. A joint moves its child by::

    T_parent_child(q) = Tr(xyz) · Rot(rpy) · Motion(axis, scale · q + zero_offset)   (1)

with ``Motion`` a rotation about ``axis`` (revolute) or a translation along it
(prismatic), ``q`` the joint reading; ``scale = 1`` and ``zero_offset = 0`` where not
listed. The calibrated placement of an actuated joint is given without its zero
offset (pincal's calibrated URDF folds it in: ``origin · exp(offset · axis)``), so (1)
applies it once; a passive joint's offset stays folded into its placement. Loop
closures, actuation and the measured frame are the model's (its sidecar). Numbers
have 12 decimals (pm, prad). Not held: joint terms other than gain.
"""

from __future__ import annotations

import json
from typing import ClassVar

import numpy as np
import pinocchio as pin

from pincal.export._format import Built, ControllerFormat, fmt_number
from pincal.export._machine import CalibratedMachine

__all__ = ["GenericTable"]


def _w(x: float) -> float:
    """``x`` as written (12 decimals)."""
    return float(fmt_number(x))


def _placement(origin: pin.SE3) -> tuple[list[float], list[float]]:
    """(xyz, rpy) of ``origin`` as written."""
    xyz = [_w(v) for v in origin.translation]
    rpy = [_w(v) for v in pin.rpy.matrixToRpy(origin.rotation)]
    return xyz, rpy


def _se3(xyz: list[float], rpy: list[float]) -> pin.SE3:
    return pin.SE3(pin.rpy.rpyToMatrix(np.array(rpy)), np.array(xyz))


def _seq(values: list[float]) -> str:
    return "[" + ", ".join(fmt_number(v) for v in values) + "]"


class GenericTable(ControllerFormat):
    """``generic-table``: the calibrated machine as a documented YAML table."""

    name: ClassVar[str] = "generic-table"
    suffix: ClassVar[str] = ".yaml"
    summary: ClassVar[str] = "joint placements (xyz m, rpy rad) and zero offsets, any machine"

    def build(self, machine: CalibratedMachine, q_fit: np.ndarray) -> Built:
        cal, nom = machine.calibrated, machine.nominal
        gains = machine.gains()
        lines = [
            "format: pincal machine table",
            "version: 1",
            f"model: {json.dumps(machine.model)}",
            "units: {length: m, angle: rad}",
            "equation: 'T_parent_child(q) = Tr(xyz) Rot(rpy) Motion(axis, scale q + zero_offset)'",
            f"measured_frame: {json.dumps(cal.measured_frame)}",
            "actuated:",
        ]
        origins: dict[str, pin.SE3] = {}
        offsets: dict[str, float] = {}
        for joint in cal.actuated:
            offsets[joint] = _w(machine.offset(joint))
            lines += [
                f"  - joint: {json.dumps(joint)}",
                f"    type: {cal.tree.joints[joint].type}",
                f"    zero_offset: {fmt_number(offsets[joint])}",
            ]
            if joint in gains:
                lines.append(f"    scale: {fmt_number(1.0 + gains[joint])}")
        lines.append("joints:")
        for name, uj in cal.tree.joints.items():
            origin = uj.origin
            if name in offsets:  # the table applies the offset by (1): take it out here
                origin = origin * pin.exp6(pin.Motion(-machine.offset(name) * uj.offset_twist()))
            xyz, rpy = _placement(origin)
            n_xyz, n_rpy = _placement(nom.tree.joints[name].origin)
            origins[name] = _se3(xyz, rpy)
            if name in offsets:
                origins[name] = origins[name] * pin.exp6(
                    pin.Motion(offsets[name] * uj.offset_twist())
                )
            lines += [
                f"  - name: {json.dumps(name)}",
                f"    type: {uj.type}",
                f"    parent: {json.dumps(uj.parent)}",
                f"    child: {json.dumps(uj.child)}",
                f"    axis: {_seq(list(uj.axis))}",
                f"    nominal: {{xyz: {_seq(n_xyz)}, rpy: {_seq(n_rpy)}}}",
                f"    calibrated: {{xyz: {_seq(xyz)}, rpy: {_seq(rpy)}}}",
            ]
        table = nom.with_joint_origins(origins)
        scale = np.array([_w(1.0 + gains.get(j, 0.0)) for j in cal.actuated])

        def forward(q_act: np.ndarray) -> np.ndarray:
            return np.array(
                [table.frame_placement(table.configuration(q * scale)).homogeneous for q in q_act]
            )

        missing = [f"joint term {t}" for t in machine.terms_not_held(("gain",))]
        conventions = [
            "actuated joints: calibrated placement without the zero offset; passive joints: "
            "offset folded into the placement",
        ]
        return Built("\n".join(lines) + "\n", forward, missing, conventions)

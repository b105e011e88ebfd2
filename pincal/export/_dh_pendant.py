"""``dh-offsets-lengths``: joint zero offsets and link lengths on the nominal DH table.

The vendor style most teach pendants accept: the controller keeps its own (nominal)
standard DH table — twists ``α_i``, base ``B`` and tool ``E`` — and takes per joint a
zero offset and the two link lengths. Its forward kinematics::

    T_tool(q) = B · A_1(θ_1) ··· A_n(θ_n) · E,   A_i = Rz(θ_i) Tz(d_i) Tx(a_i) Rx(α_i)
    θ_i = q_i + theta_offset_i,   theta_offset_i = nominal theta_offset_i + zero_offset_i   (1)

with ``α_i``, ``B``, ``E`` those of the nominal arm's ``dh-standard`` table (the same
construction, :mod:`pincal.export._dh_fit`) and ``zero_offset_i``, ``a_i``, ``d_i`` written.
These 3n numbers are a least-squares fit of (1) to the calibrated model's measured-frame
poses over workspace readings (position [m] and the rotation angle times the arm's reach
[m], equally weighted), started from the calibrated arm's own DH values. What (1) cannot
hold — axis tilts (changed twists), a moved base or tool, gains and joint terms — is
absorbed as far as lengths and offsets can, and the rest is in the projection.
"""

from __future__ import annotations

import json
from typing import ClassVar

import numpy as np
import pinocchio as pin

from pincal.export._dh_fit import fit_dh
from pincal.export._dh_table import (
    StandardDH,
    as_written,
    joint_axes,
    transform,
    xyz_rpy,
    yaml_seq,
)
from pincal.export._format import Built, fmt_number
from pincal.export._machine import CalibratedMachine

__all__ = ["OffsetsLengthsDH"]


class OffsetsLengthsDH(StandardDH):
    """``dh-offsets-lengths``: zero offsets and link lengths on the nominal DH table."""

    name: ClassVar[str] = "dh-offsets-lengths"
    summary: ClassVar[str] = "joint zero offsets and link lengths a, d on the nominal DH table"

    def build(self, machine: CalibratedMachine, q_fit: np.ndarray) -> Built:
        from scipy.optimize import least_squares  # here: importing pincal must not load scipy

        nominal = fit_dh(*joint_axes(machine.nominal), False)
        own = fit_dh(*joint_axes(machine.calibrated), False)
        base_xyz, base_rpy = xyz_rpy(nominal.base)
        tool_xyz, tool_rpy = xyz_rpy(nominal.tool)
        B, E = transform(base_xyz, base_rpy), transform(tool_xyz, tool_rpy)
        alpha = np.vectorize(as_written)(nominal.rows[:, 1])
        theta0 = nominal.rows[:, 2]

        def forward_with(x: np.ndarray, q_act: np.ndarray) -> np.ndarray:
            dtheta, a, d = x.reshape(3, -1)
            out = np.empty((len(q_act), 4, 4))
            for s, q in enumerate(q_act):
                T = B
                for i, qi in enumerate(q):
                    T = T @ self._link(a[i], alpha[i], qi + theta0[i] + dtheta[i], d[i])
                out[s] = T @ E
            return out

        ref = machine.reference(q_fit)
        reach = max(float(np.linalg.norm(nominal.tool[:3, 3] - nominal.base[:3, 3])), 0.1)
        reach = max(reach, float(np.max(np.linalg.norm(ref[:, :3, 3], axis=1))))

        def residual(x: np.ndarray) -> np.ndarray:
            ctl = forward_with(x, q_fit)
            dp = ctl[:, :3, 3] - ref[:, :3, 3]
            dr = [pin.log3(r[:3, :3].T @ c[:3, :3]) for r, c in zip(ref, ctl, strict=True)]
            return np.concatenate([dp.ravel(), reach * np.ravel(dr)])

        start = np.concatenate([np.angle(np.exp(1j * (own.rows[:, 2] - theta0))),
                                own.rows[:, 0], own.rows[:, 3]])  # fmt: skip
        x = least_squares(residual, start, method="lm", x_scale="jac").x
        x = np.vectorize(as_written)(x)
        dtheta, a, d = x.reshape(3, -1)

        lines = [
            "convention: standard",
            "equation: 'A_i = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i); theta_i = q_i + "
            "theta_offset_i; T = base A_1 ... A_n tool'",
            "written: zero_offset, a, d per joint; alpha, base and tool are the nominal arm's",
            "units: {length: m, angle: rad}",
            f"measured_frame: {json.dumps(machine.calibrated.measured_frame)}",
            f"base: {{xyz: {yaml_seq(base_xyz)}, rpy: {yaml_seq(base_rpy)}}}",
            "rows:",
        ]
        for i, joint in enumerate(machine.calibrated.actuated):
            a0, al0, t0, d0 = nominal.rows[i]
            lines += [
                f"  - joint: {json.dumps(joint)}",
                f"    a: {fmt_number(a[i])}",
                f"    alpha: {fmt_number(alpha[i])}",
                f"    d: {fmt_number(d[i])}",
                f"    theta_offset: {fmt_number(theta0[i] + dtheta[i])}",
                f"    zero_offset: {fmt_number(dtheta[i])}",
                f"    nominal: {{a: {fmt_number(a0)}, alpha: {fmt_number(al0)}, "
                f"d: {fmt_number(d0)}, theta_offset: {fmt_number(t0)}}}",
            ]
        lines.append(f"tool: {{xyz: {yaml_seq(tool_xyz)}, rpy: {yaml_seq(tool_rpy)}}}")
        missing = [
            "changed axis twists (alpha), a moved base or tool: absorbed by offsets and "
            "lengths as far as they can, the rest in the figures above",
            *self._missing(machine, own),
        ]
        conventions = [
            *self._conventions(nominal),
            f"offsets and lengths fitted over {len(q_fit)} workspace readings (position, and "
            f"rotation × {reach:.3g} m)",
        ]
        return Built("\n".join(lines) + "\n", lambda q: forward_with(x, q), missing, conventions)

"""Linear deltas: Klipper ``printer.cfg`` (delta) and LinuxCNC ``lineardeltakins``.

A linear delta (Rostock / Kossel) moves three carriages on vertical towers; each drives
the effector through a parallelogram of two equal rods. With the effector's and the
carriages' joint offsets folded into an effective radius, tower i is a vertical line
at ``(R cos α_i, R sin α_i)`` and its carriage height ``h_i`` sets the sphere::

    (x − R cos α_i)² + (y − R sin α_i)² + (h_i − z)² = L_i²               (1)

so the inverse kinematics is ``h_i = z + sqrt(L_i² − (x − R cos α_i)² − (y − R sin
α_i)²)`` and the forward kinematics the lower intersection of the three spheres
(:mod:`pincal.export._delta`). pincal's reading ``q_i`` of carriage i gives
``h_i = s_i·q_i + c_i`` (s_i = ±1: the reading's direction, c_i the fitted offset);
``(x, y, z)`` are the model's world coordinates of the measured point (z = 0: the bed).

* **Klipper** (``[printer] delta_radius`` = R; per ``[stepper_a|b|c]``: ``angle`` =
  α_i [deg], ``arm_length`` = L_i, ``position_endstop`` = the nozzle's height above
  the bed at the centre when the carriage is at its endstop; [mm]): the endstop is at
  the top of the carriage's range (its highest reading), carriage height there
  ``h_end,i``, so ``position_endstop_i = h_end,i − sqrt(L_i² − R²)``. stepper_a/b/c
  are the model's actuated joints in order.
* **LinuxCNC lineardeltakins** (HAL pins ``lineardeltakins.R``, ``lineardeltakins.L``,
  one radius and one rod length; joint 0's tower at (0, R), joints 1 and 2 at 120°
  steps clockwise, i.e. α = 90°, −30°, 210°; [mm]); joint i's position is its carriage
  height h_i: its home offset is ``h_end,i``. The model's towers are assigned to the
  joints by nearest angle.

What (1) cannot hold: tilted towers, unequal rods within a parallelogram (the platform
then tilts), and for the symmetric forms per-tower radii, angles or rod lengths that
differ. The free per-tower fit (four numbers per tower) says how far the calibrated
model is from (1) at all; the projection measures the format's own numbers.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import ClassVar

import numpy as np

from pincal.errors import ExportError
from pincal.export._delta import (
    Array,
    actuator_signs,
    check_delta,
    fit,
    lowest_intersection,
    points,
)
from pincal.export._format import Built, ControllerFormat, fmt_number
from pincal.export._machine import CalibratedMachine

__all__ = ["KlipperDelta", "LinuxCncLinearDelta"]

#: lineardeltakins tower angles of joints 0, 1, 2 [rad] (joint 0 at (0, R), clockwise)
LINUXCNC_ANGLES = np.radians([90.0, -30.0, 210.0])
_TOL = 1e-9  # [m] a residual or spread below this is exact


def _w(x: float) -> float:
    return float(fmt_number(x))


def _spheres(P: Array, h: Array, tx: Array, ty: Array, L: Array) -> Array:
    """Residuals (m·3,) of (1) [m]."""
    d = np.sqrt((P[:, :1] - tx) ** 2 + (P[:, 1:2] - ty) ** 2 + (h - P[:, 2:]) ** 2)
    return (d - L).ravel()


class _LinearDelta(ControllerFormat):
    """The fit and the controller shared by the two linear-delta formats."""

    def _data(self, machine: CalibratedMachine, q_fit: Array) -> tuple[Array, Array, Array]:
        check_delta(machine, "prismatic", self.name)
        return points(machine, q_fit), np.asarray(q_fit, dtype=float), actuator_signs(machine)

    @staticmethod
    def free_fit(machine: CalibratedMachine, P: Array, Q: Array, s: Array) -> tuple[Array, float]:
        """Per tower (x_i, y_i, L_i, c_i) (4, 3) fitted freely, and the RMS [m].

        Starts from each carriage link's place at home (the rods' pivots are near it).
        """

        def res(v: Array) -> Array:
            x, y, L, c = v.reshape(4, 3)
            return _spheres(P, s * Q + c, x, y, L)

        mech = machine.calibrated
        q0 = mech.q_home
        links = np.array(
            [mech.frame_placement(q0, mech.tree.joints[j].child).translation for j in mech.actuated]
        )
        c = links[:, 2] - s * mech.actuators_of(q0)
        K = np.stack([np.broadcast_to(links[:, 0], Q.shape), np.broadcast_to(links[:, 1], Q.shape),
                      s * Q + c], axis=2)  # fmt: skip
        L = np.linalg.norm(K - P[:, None, :], axis=2).mean(axis=0)
        v, rms = fit(res, np.concatenate([links[:, 0], links[:, 1], L, c]), "linear delta")
        return v.reshape(4, 3), rms

    @staticmethod
    def top(machine: CalibratedMachine, s: Array) -> Array:
        """(3,) the reading with the carriage highest (its endstop) [m]."""
        lo, hi = np.asarray(machine.calibrated.actuator_limits, dtype=float).T
        end = np.where(s > 0, hi, lo)
        if not np.all(np.isfinite(end)):
            raise ExportError(
                "the endstop is the top of each carriage's range; declare the carriage "
                "joints' limits (URDF <limit> or sidecar workspace.joints)"
            )
        return end

    @staticmethod
    def controller(
        s: Array, c: Array, tx: Array, ty: Array, L: Array, R_home: Array
    ) -> Callable[[Array], Array]:
        """Readings (m, 3) → poses (m, 4, 4) by (1) (constant orientation R_home)."""

        def forward(q_act: Array) -> Array:
            h = s * np.asarray(q_act, dtype=float) + c
            centres = np.stack(
                [np.broadcast_to(tx, h.shape), np.broadcast_to(ty, h.shape), h], axis=2
            )
            out = np.tile(np.eye(4), (len(h), 1, 1))
            out[:, :3, :3] = R_home
            out[:, :3, 3] = lowest_intersection(centres, L)
            return out

        return forward

    @staticmethod
    def notes(free: Array, free_rms: float) -> list[str]:
        """What (1) cannot hold, from the free per-tower fit."""
        x, y = free[0], free[1]
        out = []
        if free_rms > _TOL:
            out.append(
                f"the towers are not vertical lines with rigid rods (tilt, unequal rods in "
                f"a parallelogram): per-tower fit RMS {free_rms * 1e6:.4g} um"
            )
        radii = np.hypot(x, y)
        if np.ptp(radii) > _TOL:
            out.append(f"tower radii differ by {np.ptp(radii) * 1e3:.4g} mm")
        return out


class KlipperDelta(_LinearDelta):
    """``klipper-delta``: Klipper printer.cfg [printer] and [stepper_a..c] delta options."""

    name: ClassVar[str] = "klipper-delta"
    suffix: ClassVar[str] = ".cfg"
    summary: ClassVar[str] = (
        "Klipper printer.cfg delta: delta_radius, per-stepper angle, arm_length, position_endstop"
    )

    def build(self, machine: CalibratedMachine, q_fit: np.ndarray) -> Built:
        P, Q, s = self._data(machine, q_fit)
        free, free_rms = self.free_fit(machine, P, Q, s)
        x, y, L0, c0 = free
        R0 = float(np.hypot(x, y).mean())

        def res(v: Array) -> Array:
            R, a, L, c = v[0], v[1:4], v[4:7], v[7:10]
            return _spheres(P, s * Q + c, R * np.cos(a), R * np.sin(a), L)

        v, _ = fit(res, np.concatenate([[R0], np.arctan2(y, x), L0, c0]), self.name)
        R, a, L, c = _w(v[0] * 1e3), v[1:4], v[4:7], v[7:10]
        ang = [_w(np.degrees(t) % 360.0) for t in a]
        arm = [_w(t * 1e3) for t in L]
        end = self.top(machine, s)
        stop = [_w((s[i] * end[i] + c[i]) * 1e3 - np.sqrt(arm[i] ** 2 - R**2)) for i in range(3)]
        # the controller, from the numbers as written [mm → m]
        a_w, L_w, R_w = np.radians(ang), np.array(arm) * 1e-3, R * 1e-3
        h_end = (np.array(stop) + np.sqrt(np.array(arm) ** 2 - R**2)) * 1e-3
        c_w = h_end - s * end
        home = machine.reference(machine.calibrated.actuators_of(machine.calibrated.q_home)[None])
        forward = self.controller(
            s, c_w, R_w * np.cos(a_w), R_w * np.sin(a_w), L_w, home[0, :3, :3]
        )
        mech = machine.calibrated
        lines = ["[printer]", "kinematics: delta", f"delta_radius: {fmt_number(R)}", ""]
        for i, stepper in enumerate("abc"):
            lines += [
                f"[stepper_{stepper}]",
                f"# {mech.actuated[i]}: carriage height = {s[i]:+.0f} * reading + "
                f"{fmt_number(c_w[i] * 1e3)} mm; endstop at reading {fmt_number(end[i] * 1e3)} mm",
                f"angle: {fmt_number(ang[i])}",
                f"arm_length: {fmt_number(arm[i])}",
                f"position_endstop: {fmt_number(stop[i])}",
                "",
            ]
        missing = self.notes(free, free_rms)
        missing += [f"joint term {t}" for t in machine.terms_not_held()]
        conventions = [
            "stepper_a, _b, _c = the model's actuated joints "
            + ", ".join(mech.actuated) + "; lengths mm, angles deg",
            "x y z = the model's world frame (z = 0: the bed); the endstop is the top of "
            "each carriage's range",
        ]  # fmt: skip
        return Built("\n".join(lines), forward, missing, conventions)


class LinuxCncLinearDelta(_LinearDelta):
    """``linuxcnc-lineardeltakins``: HAL ``lineardeltakins.R`` and ``.L``, home offsets."""

    name: ClassVar[str] = "linuxcnc-lineardeltakins"
    suffix: ClassVar[str] = ".hal"
    summary: ClassVar[str] = "LinuxCNC lineardeltakins R and L (HAL) + per-joint home offsets"

    def build(self, machine: CalibratedMachine, q_fit: np.ndarray) -> Built:
        P, Q, s = self._data(machine, q_fit)
        free, free_rms = self.free_fit(machine, P, Q, s)
        x, y, L0, c0 = free
        tower_angle = np.arctan2(y, x)
        # controller joint j ← the model's tower nearest its angle
        gap = np.abs(np.angle(np.exp(1j * (tower_angle[:, None] - LINUXCNC_ANGLES[None]))))
        order = np.argmin(gap, axis=0)  # order[j] = model tower of joint j
        if sorted(order.tolist()) != [0, 1, 2]:
            raise ExportError(
                f"{self.name}: the towers (at {np.degrees(tower_angle).round(1).tolist()} deg) "
                "do not match joints 0, 1, 2 at 90, -30, 210 deg one to one"
            )
        a = LINUXCNC_ANGLES[np.argsort(order)]  # the angle of each model tower

        def res(v: Array) -> Array:
            R, L, c = v[0], v[1], v[2:5]
            return _spheres(P, s * Q + c, R * np.cos(a), R * np.sin(a), np.full(3, L))

        start = np.concatenate([[np.hypot(x, y).mean(), L0.mean()], c0])
        v, _ = fit(res, start, self.name)
        R_mm, L_mm = _w(v[0] * 1e3), _w(v[1] * 1e3)
        c_mm = [_w(t * 1e3) for t in v[2:5]]
        end = self.top(machine, s)
        R_w, L_w, c_w = R_mm * 1e-3, L_mm * 1e-3, np.array(c_mm) * 1e-3
        home = machine.reference(machine.calibrated.actuators_of(machine.calibrated.q_home)[None])
        forward = self.controller(
            s, c_w, R_w * np.cos(a), R_w * np.sin(a), np.full(3, L_w), home[0, :3, :3]
        )
        mech = machine.calibrated
        lines = [
            "# lineardeltakins: h_i = z + sqrt(L^2 - (x - R cos a_i)^2 - (y - R sin a_i)^2), "
            "a = 90, -30, 210 deg; mm",
            f"setp lineardeltakins.R {fmt_number(R_mm)}",
            f"setp lineardeltakins.L {fmt_number(L_mm)}",
            "# joint j = carriage height h = sign * reading + offset [mm]; with the home "
            "switch at the top, [JOINT_j]HOME_OFFSET = h there",
        ]
        for j in range(3):
            k = int(order[j])
            h_end = s[k] * end[k] * 1e3 + c_mm[k]
            lines.append(
                f"# joint.{j} = {mech.actuated[k]}: sign {s[k]:+.0f}, offset "
                f"{fmt_number(c_mm[k])}, HOME_OFFSET {fmt_number(h_end)}"
            )
        missing = self.notes(free, free_rms)
        if np.ptp(L0) > _TOL:
            missing.append(f"rod lengths differ by {np.ptp(L0) * 1e3:.4g} mm (one L)")
        dev = np.abs(np.angle(np.exp(1j * (tower_angle - a))))
        if dev.max() > _TOL:
            missing.append(
                f"tower angles off 90/-30/210 deg by up to {np.degrees(dev.max()):.4g} deg"
            )
        missing += [f"joint term {t}" for t in machine.terms_not_held()]
        conventions = [
            "joint j = " + ", ".join(f"{j}={mech.actuated[int(order[j])]}" for j in range(3)),
            "x y z = the model's world frame; lengths mm",
        ]
        return Built("\n".join(lines) + "\n", forward, missing, conventions)

"""``rotary-delta``: a rotary (Clavel) delta as a per-arm table (YAML, mm and degrees).

Arm i swings its upper arm in the vertical plane of the direction
``u_i = (cos φ_i, sin φ_i, 0)``; the shoulder axis is horizontal, perpendicular to
``u_i``. With the effector's joint offset folded into an effective radius ``r_i``
(shoulder radius minus effector radius) and the controlled point's height below the
effector's joints into the shoulder height ``z_i``, the knee of arm i is::

    K_i = r_i u_i + z_i e_z + a_i (cos θ_i u_i − sin θ_i e_z),   θ_i = s_i q_i + θ0_i   (1)

(θ = 0: upper arm horizontal, outward; θ > 0: knee down), and the lower arm (a
parallelogram of rods ``b_i`` long) holds the controlled point p on the sphere::

    | p − K_i | = b_i                                                            (2)

The forward kinematics is the intersection of the three spheres (2) below the knees;
the inverse solves (1)–(2) per arm. Per arm the table gives φ_i [deg], r_i, z_i, a_i
(upper arm), b_i (lower arm) [mm], θ0_i [deg] and the reading's sign s_i, fitted by
least squares to the calibrated model's controlled points over workspace readings;
LinuxCNC ``rotarydeltakins`` and Smoothieware hold the symmetric special case (one
r, a, b and φ at 120° steps), which the table shows how far the machine is from.

What (1)–(2) cannot hold: a shoulder axis that is not horizontal or not perpendicular
to its arm's plane, unequal rods within a parallelogram (the effector then tilts), and
joint terms other than the zero offset.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from pincal.errors import ExportError
from pincal.export._delta import Array, check_delta, fit, lowest_intersection, points
from pincal.export._format import Built, ControllerFormat, fmt_number
from pincal.export._machine import CalibratedMachine

__all__ = ["RotaryDelta", "knees"]

_TOL = 1e-9  # [m] a fit residual below this is exact
_FIELDS = ("angle_deg", "radius_mm", "height_mm", "upper_arm_mm", "lower_arm_mm", "zero_deg")


def knees(v: Array, s: float, q: Array) -> Array:
    """(m, 3) knees (1) [m] of one arm: v = (φ, r, z, a, b, θ0) [rad, m]; q (m,)."""
    phi, r, z, a, _, t0 = v
    u = np.array([np.cos(phi), np.sin(phi), 0.0])
    th = s * np.asarray(q, dtype=float) + t0
    return (r + a * np.cos(th))[:, None] * u + (z - a * np.sin(th))[:, None] * np.array(
        [0.0, 0.0, 1.0]
    )


def _fit_arm(P: Array, q: Array, start: Array, s: float) -> tuple[Array, float]:
    return fit(lambda v: np.linalg.norm(P - knees(v, s, q), axis=1) - v[4], start, "rotary delta")


def _start(machine: CalibratedMachine, k: int, P: Array, s: float) -> Array:
    """(φ, r, z, a, b, θ0) of arm k from the model at home (shoulder, knee links)."""
    mech = machine.calibrated
    joint = mech.actuated[k]
    arm = mech.tree.joints[joint].child
    q0 = mech.q_home
    S = mech.frame_placement(q0, arm)
    kids = [j for j in mech.tree.joints.values() if j.parent == arm]
    if not kids:
        raise ExportError(f"rotary-delta: arm {joint!r} carries no joint (its elbow)")
    K = S.act(np.mean([j.origin.translation for j in kids], axis=0))
    phi = float(np.arctan2(S.translation[1], S.translation[0]))
    u = np.array([np.cos(phi), np.sin(phi), 0.0])
    rel = K - S.translation
    theta = float(np.arctan2(-rel[2], rel @ u))
    a = float(np.hypot(rel @ u, rel[2]))
    r = float(np.hypot(*S.translation[:2]))
    p0 = machine.reference(mech.actuators_of(q0)[None])[0, :3, 3]
    b = float(np.linalg.norm(p0 - K))
    return np.array([phi, r, S.translation[2], a, b, theta - s * mech.actuators_of(q0)[k]])


class RotaryDelta(ControllerFormat):
    """``rotary-delta``: per-arm angle, radius, height, arm lengths and zero (YAML)."""

    name: ClassVar[str] = "rotary-delta"
    suffix: ClassVar[str] = ".yaml"
    summary: ClassVar[str] = (
        "rotary delta per arm: angle, effective radius, shoulder height, upper/lower arm, zero"
    )

    def build(self, machine: CalibratedMachine, q_fit: np.ndarray) -> Built:
        check_delta(machine, "revolute", self.name)
        mech = machine.calibrated
        Q = np.asarray(q_fit, dtype=float)
        P = points(machine, Q)
        arms, signs, worst = [], [], 0.0
        for k in range(3):
            fits = {s: _fit_arm(P, Q[:, k], _start(machine, k, P, s), s) for s in (1.0, -1.0)}
            s = min(fits, key=lambda t: fits[t][1])
            v, rms = fits[s]
            v[0] = np.angle(np.exp(1j * v[0]))  # φ in (−π, π]
            arms.append(v)
            signs.append(s)
            worst = max(worst, rms)
        written = [
            [
                float(fmt_number(np.degrees(v[0]))), float(fmt_number(v[1] * 1e3)),
                float(fmt_number(v[2] * 1e3)), float(fmt_number(v[3] * 1e3)),
                float(fmt_number(v[4] * 1e3)), float(fmt_number(np.degrees(v[5]))),
            ]
            for v in arms
        ]  # fmt: skip
        used = [
            np.array([np.radians(w[0]), *(np.array(w[1:5]) * 1e-3), np.radians(w[5])])
            for w in written
        ]
        R_home = machine.reference(mech.actuators_of(mech.q_home)[None])[0, :3, :3]

        def forward(q_act: np.ndarray) -> np.ndarray:
            q = np.asarray(q_act, dtype=float)
            centres = np.stack([knees(used[k], signs[k], q[:, k]) for k in range(3)], axis=1)
            out = np.tile(np.eye(4), (len(q), 1, 1))
            out[:, :3, :3] = R_home
            out[:, :3, 3] = lowest_intersection(centres, np.array([u[4] for u in used]))
            return out

        lines = [
            "# K_i = r u_i + z e_z + a (cos t u_i - sin t e_z), t = sign * reading + zero,",
            "# u_i = (cos angle, sin angle, 0); controlled point p: |p - K_i| = lower_arm",
            "arms:",
        ]
        for k, w in enumerate(written):
            lines.append(f"- joint: {mech.actuated[k]}")
            lines += [f"  {f}: {fmt_number(x)}" for f, x in zip(_FIELDS, w, strict=True)]
            lines.append(f"  sign: {signs[k]:+.0f}")
        missing = []
        if worst > _TOL:
            missing.append(
                "the arms are not of the form (1)-(2) (tilted shoulder axis, unequal rods in "
                f"a parallelogram): worst per-arm fit RMS {worst * 1e6:.4g} um"
            )
        spread = np.ptp(np.array(written)[:, 1:5], axis=0)
        sym = np.abs(np.angle(np.exp(1j * np.radians(np.diff([w[0] for w in written])))))
        symmetric = (
            "a symmetric controller (rotarydeltakins, Smoothieware) would lose: arms differ by "
            + ", ".join(f"{n} {d:.4g}" for n, d in zip(_FIELDS[1:5], spread, strict=True))
            + f"; arm spacing off 120 deg by up to "
            f"{np.degrees(np.abs(sym - 2 * np.pi / 3).max()):.4g} deg"
        )
        missing += [f"joint term {t}" for t in machine.terms_not_held(("offset",))]
        conventions = [
            "x y z = the model's world frame; lengths mm, angles deg",
            "arms in the order of the model's actuated joints",
            symmetric,
        ]
        return Built("\n".join(lines) + "\n", forward, missing, conventions)

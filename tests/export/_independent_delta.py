"""Delta controllers' equations, written here from their documentation (not pincal's).

* Klipper ``kinematics: delta`` (Config Reference): towers at ``angle`` [deg] on the
  circle of radius ``delta_radius``; ``arm_length`` per stepper; ``position_endstop``:
  the nozzle's height above the bed, nozzle at the centre, when the carriage triggers
  its endstop — so the carriage is then at ``position_endstop + sqrt(arm² − radius²)``
  and moves one to one with the stepper. Effector at (x, y, z):
  ``(x − xt)² + (y − yt)² + (carriage − z)² = arm²``; the effector hangs below.
* LinuxCNC ``lineardeltakins(9)``: joint 0 at (0, R), joints 1, 2 at 120° steps
  clockwise; rod length L; joint value = carriage height.

The forward kinematics is solved here by Newton's method on the three sphere equations
from a point below the carriages (not the closed-form intersection pincal uses).
"""

from __future__ import annotations

import re

import numpy as np


def read_klipper(text: str) -> dict:
    """{"radius": mm, "steppers": [{"angle", "arm_length", "position_endstop"}] (a, b, c)}."""
    section, out = "", {"steppers": [{}, {}, {}]}
    for raw in text.splitlines():
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        m = re.fullmatch(r"\[(\w+)\]", line)
        if m:
            section = m.group(1)
            continue
        key, value = (s.strip() for s in line.split(":", 1))
        if section == "printer" and key == "delta_radius":
            out["radius"] = float(value)
        elif section.startswith("stepper_"):
            out["steppers"]["abc".index(section[-1])][key] = float(value)
    return out


def read_lineardeltakins(text: str) -> tuple[float, float]:
    """(R, L) [mm] from ``setp lineardeltakins.R|L`` lines."""
    vals = dict(re.findall(r"^setp lineardeltakins\.(\w) (\S+)$", text, re.M))
    return float(vals["R"]), float(vals["L"])


def spheres_forward(towers: np.ndarray, heights: np.ndarray, arms: np.ndarray) -> np.ndarray:
    """Effector (3,) [mm] with ``|p − (tower_i, h_i)| = arm_i``, the solution below.

    Args:
        towers: (3, 2) tower positions [mm]; heights: (3,) carriage heights [mm];
            arms: (3,) rod lengths [mm].
    """
    centres = np.column_stack([towers, heights])
    p = np.array([*towers.mean(axis=0), heights.min() - arms.min()])
    for _ in range(60):
        d = p - centres
        f = np.einsum("ij,ij->i", d, d) - arms**2
        step = np.linalg.solve(2 * d, -f)
        p = p + step
        if np.abs(step).max() < 1e-13:
            break
    return p


def klipper_forward(cfg: dict, readings_mm: np.ndarray, endstop_mm: np.ndarray) -> np.ndarray:
    """Effector (3,) [mm] for carriage readings, the endstops at ``endstop_mm`` readings."""
    R = cfg["radius"]
    towers, heights, arms = [], [], []
    for st, q, q_end in zip(cfg["steppers"], readings_mm, endstop_mm, strict=True):
        a = np.radians(st["angle"])
        towers.append([R * np.cos(a), R * np.sin(a)])
        L = st["arm_length"]
        heights.append(st["position_endstop"] + np.sqrt(L**2 - R**2) - (q_end - q))
        arms.append(L)
    return spheres_forward(np.array(towers), np.array(heights), np.array(arms))


def lineardeltakins_forward(R: float, L: float, joints_mm: np.ndarray) -> np.ndarray:
    """Effector (3,) [mm] for joint values (carriage heights) of joints 0, 1, 2."""
    ang = np.radians([90.0, 90.0 - 120.0, 90.0 - 240.0])  # 120° steps clockwise
    towers = np.column_stack([R * np.cos(ang), R * np.sin(ang)])
    return spheres_forward(towers, np.asarray(joints_mm, float), np.full(3, L))


def rotary_delta_forward(doc: dict, readings: np.ndarray) -> np.ndarray:
    """Controlled point (3,) [mm] of a rotary delta table for readings [rad].

    Knee of arm i: shoulder at radius r in direction (cos φ, sin φ, 0), height z; upper
    arm a at angle t = sign·reading + zero below the horizontal (outward); lower arm b.
    """
    centres, arms = [], []
    for arm, q in zip(doc["arms"], readings, strict=True):
        phi = np.radians(arm["angle_deg"])
        t = arm["sign"] * q + np.radians(arm["zero_deg"])
        reach = arm["radius_mm"] + arm["upper_arm_mm"] * np.cos(t)
        centres.append([reach * np.cos(phi), reach * np.sin(phi),
                        arm["height_mm"] - arm["upper_arm_mm"] * np.sin(t)])  # fmt: skip
        arms.append(arm["lower_arm_mm"])
    c = np.array(centres)
    L = np.array(arms)
    p = np.array([*c[:, :2].mean(axis=0), c[:, 2].min() - L.min()])
    for _ in range(60):
        d = p - c
        step = np.linalg.solve(2 * d, -(np.einsum("ij,ij->i", d, d) - L**2))
        p = p + step
        if np.abs(step).max() < 1e-13:
            break
    return p

"""The controllers' equations, written here from the published formulas (not pincal's).

* genhexkins (LinuxCNC ``genhexkins(9)``): strut length ``L_i = |R p_i + t − b_i|``.
* DH: standard ``A = Rz(θ) Tz(d) Tx(a) Rx(α)``, modified (Craig)
  ``A = Rx(α) Tx(a) Rz(θ) Tz(d)``, ``θ = q + θ_offset``.
* URDF placement ``xyz``/``rpy``: ``Tr(xyz) · Rz(yaw) Ry(pitch) Rx(roll)``.
"""

from __future__ import annotations

import math
import re

import numpy as np
import yaml


def rot(axis: str, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    R = {
        "x": [[1, 0, 0], [0, c, -s], [0, s, c]],
        "y": [[c, 0, s], [0, 1, 0], [-s, 0, c]],
        "z": [[c, -s, 0], [s, c, 0], [0, 0, 1]],
    }[axis]
    T = np.eye(4)
    T[:3, :3] = R
    return T


def trans(x: float = 0.0, y: float = 0.0, z: float = 0.0) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = (x, y, z)
    return T


def placement(xyz, rpy) -> np.ndarray:
    return trans(*xyz) @ rot("z", rpy[2]) @ rot("y", rpy[1]) @ rot("x", rpy[0])


def axis_rotation(axis, angle: float) -> np.ndarray:
    """Rodrigues: rotation by ``angle`` about unit ``axis``."""
    k = np.asarray(axis, dtype=float)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    T = np.eye(4)
    T[:3, :3] = np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K
    return T


def read_hal(text: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(base (6, 3), platform (6, 3), offsets (6,)) from a genhexkins HAL export."""
    base, plat, off = np.full((6, 3), np.nan), np.full((6, 3), np.nan), np.full(6, np.nan)
    for kind, n, ax, v in re.findall(
        r"^setp genhexkins\.(base|platform)\.(\d)\.([xyz]) (\S+)$", text, re.M
    ):
        (base if kind == "base" else plat)[int(n), "xyz".index(ax)] = float(v)
    for n, v in re.findall(r"^# joint\.(\d)\.offset = (\S+)", text, re.M):
        off[int(n)] = float(v)
    assert np.isfinite(base).all() and np.isfinite(plat).all() and np.isfinite(off).all()
    return base, plat, off


def genhexkins_inverse(base, plat, offsets, pose: np.ndarray) -> np.ndarray:
    """Joint positions (readings) of the 6 struts for a platform pose (4, 4)."""
    R, t = pose[:3, :3], pose[:3, 3]
    lengths = np.array([np.linalg.norm(R @ plat[i] + t - base[i]) for i in range(6)])
    return lengths - offsets


def read_yaml_body(text: str) -> dict:
    return yaml.safe_load(text)


def dh_forward(doc: dict, q) -> np.ndarray:
    """Tool pose of a DH export at readings ``q``."""
    T = placement(doc["base"]["xyz"], doc["base"]["rpy"])
    for row, qi in zip(doc["rows"], q, strict=True):
        th = qi + row["theta_offset"]
        if doc["convention"] == "standard":
            T = T @ rot("z", th) @ trans(z=row["d"]) @ trans(x=row["a"]) @ rot("x", row["alpha"])
        else:
            T = T @ rot("x", row["alpha"]) @ trans(x=row["a"]) @ rot("z", th) @ trans(z=row["d"])
    return T @ placement(doc["tool"]["xyz"], doc["tool"]["rpy"])


def table_forward(doc: dict, q, frame_link: str) -> np.ndarray:
    """World pose of ``frame_link`` of a serial machine table at readings ``q``."""
    act = {
        a["joint"]: (i, a.get("scale", 1.0), a["zero_offset"])
        for i, a in enumerate(doc["actuated"])
    }
    by_child = {j["child"]: j for j in doc["joints"]}
    chain = []
    link = frame_link
    while link in by_child:
        chain.append(by_child[link])
        link = by_child[link]["parent"]
    T = np.eye(4)
    for j in reversed(chain):
        T = T @ placement(j["calibrated"]["xyz"], j["calibrated"]["rpy"])
        if j["name"] in act:
            i, scale, offset = act[j["name"]]
            value = scale * q[i] + offset
            if j["type"] == "prismatic":
                T = T @ trans(*(value * np.asarray(j["axis"])))
            else:
                T = T @ axis_rotation(j["axis"], value)
    return T


def pose_error(A: np.ndarray, B: np.ndarray) -> tuple[float, float]:
    """(position [m], orientation [rad]) difference of two poses."""
    dR = A[:3, :3].T @ B[:3, :3]
    angle = math.acos(max(-1.0, min(1.0, (np.trace(dR) - 1) / 2)))
    return float(np.linalg.norm(A[:3, 3] - B[:3, 3])), angle

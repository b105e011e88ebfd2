"""DH frames fitted to a serial arm's joint axes: the classic common-normal construction.

Input: the n joint axes at zero readings as lines ``(p_i, w_i)`` in the world frame
(point [m], unit direction), and the tool pose ``T_t`` at zero readings. Each row's
frame is placed on the common normal of successive axes (closest points of two lines:
``o + s z`` and ``p + u w`` with ``s = (r·z − c r·w)/(1 − c²)``,
``u = (c r·z − r·w)/(1 − c²)``, ``r = p − o``, ``c = z·w``); ``x`` points along the
normal from the first line to the second, or along ``z × w`` when they intersect.

Conventions (named in the export's header):

* frame 0 (standard) / the first axis point (modified): the point of axis 1 nearest the
  world origin; standard ``x_0``: world x projected on the plane normal to axis 1
  (world y when x is along the axis); the world → frame 0 transform is the ``base``.
* parallel axes (the normal is not unique): the normal through the previous origin
  (standard: ``d_i = 0``, Spong's choice; modified: ``d_i = 0`` likewise). Axes whose
  common normal lies farther than ``PARALLEL_REACH`` arm sizes away are treated as
  parallel too: DH can only place such a normal kilometres away (the ill-conditioning
  Hayati pointed out); their tilt is then not expressed and the projection shows it.
* last frame: ``a_n = α_n = 0``, ``θ`` offset 0 (``x_n = x_{n-1}``), origin on axis n
  nearest the tool origin; the frame n → tool transform is the ``tool``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["DHFit", "fit_dh"]

#: a common normal farther than this many arm sizes is treated as parallel axes
PARALLEL_REACH = 10.0


@dataclass(frozen=True)
class DHFit:
    """A fitted DH table.

    Attributes:
        base: (4, 4) world → frame 0; tool: (4, 4) frame n → tool.
        rows: (n, 4) ``a, alpha, theta_offset, d`` [m, rad] (modified: row i holds
            ``a_{i-1}, α_{i-1}``).
        parallel: per successive axis pair (n − 1,) the angle between the axes where
            the parallel convention was used [rad], NaN elsewhere.
    """

    base: np.ndarray
    tool: np.ndarray
    rows: np.ndarray
    parallel: np.ndarray


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v)


def _normal(
    o: np.ndarray,
    z: np.ndarray,
    p: np.ndarray,
    w: np.ndarray,
    size: float,
    x_prev: np.ndarray,
) -> tuple[float, np.ndarray, float, np.ndarray, np.ndarray, float]:
    """Common normal from line (o, z) to line (p, w).

    Returns ``(s, x, a, foot2, w2, tilt)``: foot on the first line ``o + s z``, unit
    ``x`` (⟂ z and ⟂ w2), length ``a`` along x, foot on the second line, its direction
    made ⟂ x (``w`` itself unless the parallel convention was used), and the angle
    between the lines when the parallel convention was used (else NaN).
    """
    r, c = p - o, float(z @ w)
    den = 1.0 - c * c
    if den > 1e-24:
        s = (r @ z - c * (r @ w)) / den
        u = (c * (r @ z) - r @ w) / den
        if abs(s) <= PARALLEL_REACH * size and abs(u) <= PARALLEL_REACH * size:
            v = (p + u * w) - (o + s * z)
            a = float(np.linalg.norm(v))
            x = v / a if a > 1e-12 * size else _unit(np.cross(z, w))
            if a <= 1e-12 * size:
                a = 0.0
            return s, x, a, o + s * z + a * x, w, np.nan
    tilt = float(np.arccos(min(1.0, abs(c))))
    v = p + ((o - p) @ w) * w - o
    v = v - (v @ z) * z
    a = float(np.linalg.norm(v))
    x = v / a if a > 1e-12 * size else x_prev
    w2 = _unit(w - (w @ x) * x)
    return 0.0, x, a if a > 1e-12 * size else 0.0, o + a * x, w2, tilt


def _frame(o: np.ndarray, x: np.ndarray, z: np.ndarray) -> np.ndarray:
    T = np.eye(4)
    T[:3, 0], T[:3, 1], T[:3, 2], T[:3, 3] = x, np.cross(z, x), z, o
    return T


def _angle(u: np.ndarray, v: np.ndarray, axis: np.ndarray) -> float:
    """Angle from u to v about ``axis`` [rad]."""
    return float(np.arctan2(np.cross(u, v) @ axis, u @ v))


def fit_dh(points: np.ndarray, dirs: np.ndarray, tool: np.ndarray, modified: bool) -> DHFit:
    """Fit the DH table of the module doc to ``n`` axes ``points``/``dirs`` (n, 3)."""
    n = len(points)
    size = max(1.0, float(np.linalg.norm(np.vstack([points, tool[None, :3, 3]]), axis=1).max()))
    z = _unit(dirs[0])
    o = points[0] - (points[0] @ z) * z
    x = np.array([1.0, 0.0, 0.0]) - z[0] * z
    x = _unit(x) if np.linalg.norm(x) > 1e-6 else _unit(np.array([0.0, 1.0, 0.0]) - z[1] * z)
    tilts = np.full(max(n - 1, 0), np.nan)
    frames = []
    if not modified:
        frames.append(_frame(o, x, z))
        for i in range(1, n):
            _, x, _, o, z, tilts[i - 1] = _normal(o, z, points[i], _unit(dirs[i]), size, x)
            frames.append(_frame(o, x, z))
    else:  # o, z: a point of axis i and its direction; frame i sits on the normal to i+1
        for i in range(1, n):
            s, x_new, _, foot, z_next, tilts[i - 1] = _normal(
                o, z, points[i], _unit(dirs[i]), size, x
            )
            x = x_new
            frames.append(_frame(o + s * z, x, z))
            o, z = foot, z_next
        frames.append(_frame(o, x, z))  # axis n, x_n = x_{n-1}; moved along z below
    last = frames[-1]
    along = (tool[:3, 3] - last[:3, 3]) @ last[:3, 2]
    end = last.copy()
    end[:3, 3] += along * last[:3, 2]
    if modified:
        frames[-1] = end
        frames.insert(0, frames[0])  # base = frame 1 at zero readings
    else:
        frames.append(end)
    rows = np.empty((n, 4))
    for i in range(n):
        A, B = frames[i], frames[i + 1]
        xa, za, xb, zb = A[:3, 0], A[:3, 2], B[:3, 0], B[:3, 2]
        dp = B[:3, 3] - A[:3, 3]
        if modified:  # Rx(α_{i-1}) Tx(a_{i-1}) Rz(θ_i) Tz(d_i)
            rows[i] = (dp @ xa, _angle(za, zb, xa), _angle(xa, xb, zb), dp @ zb)
        else:  # Rz(θ_i) Tz(d_i) Tx(a_i) Rx(α_i)
            rows[i] = (dp @ xb, _angle(za, zb, xb), _angle(xa, xb, za), dp @ za)
    return DHFit(frames[0], np.linalg.inv(frames[-1]) @ tool, rows, tilts)

"""Batched kinematics of the two-axis joints: universal and planar (Pinocchio conventions).

The grouped tree walk (:func:`pincal.model.batch._batch_ops.walk`) hands each group of these
joints its product ``X = R_parent · [R0, R0·K, R0·K², R0·a, p0]`` (G, N, 3, 11), with a
the first axis (universal) or z (planar), and K = skew(a); the functions here finish
the joints' world placements and WORLD Jacobian columns ``[v_o; ω]`` (the linear part
is the velocity of the point at the world origin, ``p × ω`` for an axis through p).
Conventions, found by comparison with Pinocchio 4.1 on random configurations:

* ``JointModelUniversal(a, b)`` (unit axes, not necessarily perpendicular), q = (q1, q2)
  [rad]: ``M(q) = (exp(q1·a)·exp(q2·b), 0)``; the motion subspace's angular columns,
  seen from the world, are the parent-side axis ``R_parent·R0·a`` and the child-side
  axis ``oR_i·b``; tangent space = configuration space (``integrate`` is q + v).
* ``JointModelPlanar``, q = (x, y, cos θ, sin θ), v = (vx, vy, ω) in the joint frame:
  ``M(q) = (Rz(θ), (x, y, 0))`` with Rz built from the stored (cos θ, sin θ) as given
  (not renormalised); the columns are the joint frame's x and y axes (linear) and its
  z axis (angular); ``integrate`` is ``M · exp_SE2(v)``, again without renormalising.
"""

from __future__ import annotations

import numpy as np

__all__ = ["cross3", "planar_integrate", "planar_step", "universal_factors", "universal_step"]


def cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross products of stacked vectors (…, 3) (without ``np.cross``'s overhead)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def universal_factors(b: np.ndarray, Kb: np.ndarray) -> np.ndarray:
    """(G, 3, 7) right factors ``[b, Kb, Kb²]`` of the universal joints' second axes b (G, 3).

    ``Kb`` (G, 3, 3) holds skew(b).
    """
    return np.concatenate([b[..., None], Kb, Kb @ Kb], axis=2)


def _turn(
    A: np.ndarray, AK: np.ndarray, AK2: np.ndarray, c: np.ndarray, s: np.ndarray
) -> np.ndarray:
    """``A·exp(θK) = A + sin θ·AK + (1 − cos θ)·AK²`` for stacked (…, 3, 3) and (c, s) (…)."""
    return A + s[..., None, None] * AK + (1.0 - c)[..., None, None] * AK2


def universal_step(
    X: np.ndarray,
    D: np.ndarray,
    q: np.ndarray,
    pp: np.ndarray,
    iv: np.ndarray,
    Jt: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """World rotations (G, N, 3, 3) and positions (G, N, 3) of a group of universal joints.

    Args:
        X: (G, N, 3, 11) ``R_parent · [R0, R0·Ka, R0·Ka², R0·a, p0]``.
        D: (G, 3, 7) :func:`universal_factors` of the second axes.
        q: (2, G, N) joint angles [rad] (first axis, second axis).
        pp: (G, N, 3) parents' world positions [m].
        iv: (G,) first tangent index of each joint.
        Jt: (nv, N, 6) WORLD Jacobian columns, written at ``iv`` and ``iv + 1``.
    """
    G, N = X.shape[:2]
    Rm = _turn(X[..., 0:3], X[..., 3:6], X[..., 6:9], np.cos(q[0]), np.sin(q[0]))
    Y = (Rm.reshape(G, N * 3, 3) @ D).reshape(G, N, 3, 7)  # Rm · [b, Kb, Kb²]
    Ri = _turn(Rm, Y[..., 1:4], Y[..., 4:7], np.cos(q[1]), np.sin(q[1]))
    pi = pp + X[..., 10]
    for k, w in ((0, X[..., 9]), (1, Y[..., 0])):
        Jt[iv + k, :, 3:] = w
        Jt[iv + k, :, :3] = cross3(pi, w)
    return Ri, pi


def planar_step(
    X: np.ndarray, q: np.ndarray, pp: np.ndarray, iv: np.ndarray, Jt: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """World rotations (G, N, 3, 3) and positions (G, N, 3) of a group of planar joints.

    Args:
        X: (G, N, 3, 11) ``R_parent · [R0, R0·Kz, R0·Kz², R0·z, p0]``.
        q: (4, G, N) the joints' x, y [m], cos θ, sin θ.
        pp: (G, N, 3) parents' world positions [m].
        iv: (G,) first tangent index of each joint.
        Jt: (nv, N, 6) WORLD Jacobian columns, written at ``iv`` … ``iv + 2``.
    """
    Ri = _turn(X[..., 0:3], X[..., 3:6], X[..., 6:9], q[2], q[3])
    pi = pp + X[..., 10] + q[0][..., None] * X[..., 0] + q[1][..., None] * X[..., 1]
    w = X[..., 9]
    Jt[iv, :, :3] = Ri[..., 0]
    Jt[iv + 1, :, :3] = Ri[..., 1]
    Jt[iv + 2, :, 3:] = w
    Jt[iv + 2, :, :3] = cross3(pi, w)
    return Ri, pi


def planar_integrate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``pin.integrate`` of planar joint configurations (N, 4) by tangent steps (N, 3).

    ``q ⊕ v = M(q)·exp(v)``: exp(v) turns by ω and moves by ``V(ω)·(vx, vy)`` with
    ``V = [[sin ω/ω, −(1 − cos ω)/ω], [(1 − cos ω)/ω, sin ω/ω]]`` (series near ω = 0).
    """
    x, y, c, s = q.T
    vx, vy, w = v.T
    small = np.abs(w) < 1e-4
    t = np.where(small, 1.0, w)
    w2 = w * w
    sinc = np.where(small, 1.0 - w2 / 6.0, np.sin(t) / t)
    cosc = np.where(small, w * (0.5 - w2 / 24.0), (1.0 - np.cos(t)) / t)
    tx, ty = sinc * vx - cosc * vy, cosc * vx + sinc * vy
    cw, sw = np.cos(w), np.sin(w)
    return np.stack([x + c * tx - s * ty, y + s * tx + c * ty, c * cw - s * sw, s * cw + c * sw], 1)

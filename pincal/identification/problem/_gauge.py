"""What a fit cannot see: its gauge, in words, and the directions it sees too weakly.

A measurement that sees less than a full pose (a ballbar, a probe, a plane) leaves
directions of the parameters unobserved: moving along them changes no reading. The
identification holds them at their nominal values (the base set); this module says
which they are physically. Each null direction of the joint machine + instrument
Jacobian moves the tool points by a field ``δp_i = J_p,i δx``; fields that are rigid
motions ``v + ω × p_i`` are named (translations along directions, rotations about axes
through a point), split into motions the instruments cannot see at all and motions
their own parameters absorb (e.g. a ballbar cannot see a rotation of the whole machine
about its pivot, and its pivot absorbs a translation: the absolute tool position is
not observed).

:func:`weak_parameters` finds the directions the data see, but too weakly to place
within a bound (1σ beyond 20 mm / 0.1 rad by default): with random poses a ballbar
sees some combinations only through curvature, and fitting them moves parameters tens
of millimetres for no significant change of the residuals. They are held as well.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pincal.measure import DeclaredConstant
from pincal.sensitivity import PLACEMENT_BOUND, Identifiability, placement_limits

__all__ = ["NullMotions", "constant_line", "constant_std", "null_motions", "weak_parameters"]


@dataclass(frozen=True)
class NullMotions:
    """The null directions of a fit as motions of the tool points, in words.

    Attributes:
        invisible: motions no measurement sees at all.
        absorbed: motions the instruments' own parameters absorb (those named).
        n_still: null directions that do not move the tool point at all.
    """

    invisible: tuple[str, ...] = ()
    absorbed: tuple[str, ...] = ()
    n_still: int = 0

    def lines(self) -> list[str]:
        """One line per motion (empty when the fit sees every direction)."""
        out = [f"not observed: {w}" for w in self.invisible]
        out += [f"absorbed by the instrument parameters: {w}" for w in self.absorbed]
        if self.n_still:
            out.append(f"not observed: {self.n_still} direction(s) that do not move the tool "
                       "point (tool orientation about the tool point)")  # fmt: skip
        return out


def _span(M: np.ndarray, tol: float = 1e-6, absolute: bool = False) -> np.ndarray:
    """Orthonormal basis (columns) of the column span of M.

    Keeps the singular directions with singular values above ``tol``, relative to the
    largest unless ``absolute``.
    """
    if M.size == 0:
        return np.zeros((M.shape[0], 0))
    u, s, _ = np.linalg.svd(M, full_matrices=False)
    return u[:, s > tol * (1.0 if absolute else max(float(s.max(initial=0.0)), 1e-300))]


def _point(p: np.ndarray) -> str:
    """A point as text (no "-0.000")."""
    p = np.where(np.abs(np.asarray(p, dtype=float)) < 5e-4, 0.0, p)
    return "(" + ", ".join(f"{x:+.3f}" for x in p) + ")"


def _vec(v: np.ndarray) -> str:
    """A direction as text, its sign fixed so the largest component is positive."""
    v = np.asarray(v, dtype=float)
    if v.size and v[np.argmax(np.abs(v))] < 0:
        v = -v
    v = np.where(np.abs(v) < 5e-4, 0.0, v)  # no "-0.000"
    return "(" + ", ".join(f"{x:+.3f}" for x in v) + ")"


def _rigid(F: np.ndarray, P: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rigid-motion content of tool-point fields F (3m, k).

    Fits ``δp_i = v + ω × (p_i − p̄)`` per column (ω scaled by the RMS radius L of the
    points so both parts are in metres).

    Returns:
        rotation axes (3, r) (orthonormal), translation directions (3, t) of the
        rotation-free combinations, rotation centre (3,) [m] (NaN when r = 0).
    """
    mean = P.mean(axis=0)
    Pc = P - mean
    L = max(float(np.sqrt(np.mean(np.sum(Pc**2, axis=1)))), 1e-9)
    A = np.vstack([np.hstack([np.eye(3), -pin.skew(p) / L]) for p in Pc])
    C, *_ = np.linalg.lstsq(A, F, rcond=None)
    tol = 1e-6 * max(float(np.abs(C).max(initial=0.0)), 1e-300)
    u, sw, vw = np.linalg.svd(C[3:], full_matrices=True)
    r = int(np.count_nonzero(sw > tol))
    axes = u[:, :r]
    trans = _span(C[:3] @ vw[r:].T, 1e-6) if vw[r:].size else np.zeros((3, 0))
    centre = np.full(3, np.nan)
    if r:
        W = C[:, :] @ vw[:r].T  # combinations with rotation: v = −ω × (c − p̄)
        M = np.vstack([-pin.skew(W[3:, j] / L) for j in range(r)])
        centre = mean + np.linalg.lstsq(M, W[:3].T.reshape(-1), rcond=None)[0]
    return axes, trans, centre


def _complement(B: np.ndarray, A: np.ndarray) -> np.ndarray:
    """Orthonormal basis of the part of span(B) orthogonal to span(A) (both (3, ·))."""
    if B.shape[1] == 0:
        return B
    Q = _span(A) if A.shape[1] else np.zeros((3, 0))
    return _span(B - Q @ (Q.T @ B), 1e-6, absolute=True)


def _words(axes: np.ndarray, trans: np.ndarray, centre: np.ndarray | None) -> list[str]:
    out = []
    if axes.shape[1]:
        where = "" if centre is None else f" through the point {_point(centre)} m"
        out.append(
            f"{axes.shape[1]} rotation(s) of every tool point about the "
            f"{'axes' if axes.shape[1] > 1 else 'axis'} "
            + ", ".join(_vec(axes[:, j]) for j in range(axes.shape[1]))
            + where
        )
    if trans.shape[1] == 3:
        out.append("the absolute tool position: 3 translations of every tool point")
    elif trans.shape[1]:
        out.append(
            f"{trans.shape[1]} translation(s) of every tool point along "
            + ", ".join(_vec(trans[:, j]) for j in range(trans.shape[1]))
        )
    return out


def null_motions(
    J: np.ndarray,
    Jp: np.ndarray,
    P: np.ndarray,
    n: int,
    ident: Identifiability,
    order: np.ndarray,
    own_names: tuple[str, ...],
) -> NullMotions:
    """The null directions of ``J`` as rigid motions of the tool points, in words.

    Args:
        J: (N, n + k) Jacobian of the readings w.r.t. machine then instrument parameters
            (rows may be whitened).
        Jp: (m, 3, n) tool-point position sensitivities to the machine parameters.
        P: (m, 3) tool points [m].
        n: the number of machine parameters.
        ident: the analysis of ``J[:, order]`` (its rank and column scale).
        order: the column order ``ident`` was computed in.
        own_names: the k instrument parameter names.
    """
    scale = np.where(ident.column_scale > 0, ident.column_scale, 1.0)
    _, _, vt = np.linalg.svd(J[:, order] / scale, full_matrices=True)
    null = (vt[ident.rank :] / scale).T  # (n + k, d) in the `order` columns
    null_x = np.empty_like(null)
    null_x[order] = null
    machine, inst_part = null_x[:n], null_x[n:]
    # machine-only motions: combinations with no instrument part
    if inst_part.shape[0]:
        _, si, vi = np.linalg.svd(inst_part, full_matrices=True)
        r_i = int(np.count_nonzero(si > 1e-9 * max(float(si.max(initial=0.0)), 1e-300)))
    else:
        vi, r_i = np.eye(null.shape[1]), 0
    pure, mixed = vi[r_i:].T, vi[:r_i].T
    def fields(V: np.ndarray) -> np.ndarray:
        return np.einsum("mij,jk->mik", Jp, machine @ V).reshape(3 * len(Jp), V.shape[1])

    F0, F1 = fields(pure), fields(mixed)
    Q0 = _span(F0)
    still = F0.shape[1] - Q0.shape[1]
    ax0, tr0, c0 = _rigid(Q0, P)
    Qu = _span(np.hstack([F0, F1]))
    axu, tru, _ = _rigid(Qu, P)
    invisible = _words(ax0, tr0, c0 if ax0.shape[1] else None)
    absorbed = _words(_complement(axu, ax0), _complement(tru, tr0), None)
    if absorbed:
        used = [own_names[i] for i in range(len(own_names)) if np.any(np.abs(inst_part[i]) > 1e-9)]
        absorbed = [f"{w} ({', '.join(used)})" for w in absorbed]
    return NullMotions(tuple(invisible), tuple(absorbed), int(still))


def weak_parameters(
    Jw: np.ndarray, free: np.ndarray, units: tuple[str, ...], n: int,
    bounds: tuple[float, float] = PLACEMENT_BOUND,
) -> np.ndarray:  # fmt: skip
    """The members of ``free`` to hold because the data place them only beyond a bound.

    With every column scaled by its bound (``bounds`` = (length [m], angle [rad]) per
    parameter unit), a singular value below 1 of the whitened Jacobian is a direction
    whose 1σ exceeds the bound. One parameter per such direction is held: the machine
    parameter (index < ``n``) with the largest share of the weakest direction, until
    none is left.

    Args:
        Jw: (N, p) whitened Jacobian over all parameters.
        free: indices of the parameters fitted so far (the base set).
        units: per parameter ``"m"`` or ``"rad"``.
        n: the number of machine parameters (held first).
        bounds: (length [m], angle [rad]) (default: the one placement rule,
            :data:`pincal.sensitivity.PLACEMENT_BOUND`).

    Returns:
        Indices (sorted) of the parameters held, a subset of ``free``.
    """
    keep = [int(i) for i in free]
    held: list[int] = []
    b = placement_limits(units, bounds)
    while keep:
        A = Jw[:, keep] * b[keep]
        _, s, vt = np.linalg.svd(A, full_matrices=False)
        if s.size == 0 or s[-1] >= 1.0:
            break
        v = np.abs(vt[-1])
        machine = np.array([i < n for i in keep])
        if np.any(machine) and v[machine].max() > 1e-3 * v.max():
            v = np.where(machine, v, -1.0)
        held.append(keep.pop(int(np.argmax(v))))
    return np.array(sorted(held), dtype=int)


def constant_std(Jf: np.ndarray, column: np.ndarray) -> float:
    """1σ of a trusted constant, as the fit can tell it apart from its parameters [unit].

    An error δ of a constant the fit does not fit (a bar's length scale, a sphere's
    radius) adds ``δ · c`` to the whitened readings, ``c`` its whitened Jacobian column;
    the fit absorbs the part of ``c`` in the span of its whitened Jacobian ``Jf`` (N, p).
    What is left, ``‖(I − Π_J) c‖``, is the information on δ: its inverse is δ's 1σ.
    Large (e.g. a 1 % bar scale on an all-revolute machine, whose length scale only the
    instrument sets) means an error of the constant passes into the calibrated machine
    unseen.

    Args:
        Jf: (N, p) whitened Jacobian of the fitted parameters.
        column: (N,) whitened derivative of the residual rows with respect to the
            constant (0 on rows of other measurements); for a relative scale of the
            readings, the readings ``v/σ``.

    Returns:
        The 1σ (0 for a zero column, inf when the fit absorbs it wholly).
    """
    y = np.asarray(column, dtype=float)
    if not np.any(y):
        return 0.0
    Q = np.zeros((y.size, 0))
    if Jf.size:
        u, sv, _ = np.linalg.svd(Jf, full_matrices=False)
        Q = u[:, sv > 1e-10 * sv[0]] if sv[0] > 0 else Q
    rest = float(np.linalg.norm(y - Q @ (Q.T @ y)))
    return float("inf") if rest <= 1e-12 * float(np.linalg.norm(y)) else 1.0 / rest


def _sig2(x: float) -> str:
    """A positive number with at least two significant digits, never in exponent form."""
    if not np.isfinite(x) or x <= 0:
        return f"{x:g}"
    return f"{x:.{max(0, 1 - int(np.floor(np.log10(x))))}f}"


def constant_line(c: DeclaredConstant, std: float, label: str | None = None) -> str:
    """The gauge line of a trusted constant the data tell only to ``std`` (1σ) [unit].

    Args:
        c: the constant.
        std: its 1σ from :func:`constant_std` [its unit].
        label: its dataset's name, said when a fit has several instrument datasets.
    """
    if c.unit == "1":
        told = f"{std * 100:.2g} % (1σ)"
    else:
        told = f"±{_sig2(std * 1e6)} µm (1σ) of its declared {c.value * 1e3:g} mm"
    told = f"tell it only to {told}" if np.isfinite(std) else "do not tell it at all"
    where = f" of {label}" if label else ""
    return (f"{c.name}{where}: {c.error} passes into the calibrated machine — the data "
            f"{told}; {c.rests_on}")  # fmt: skip

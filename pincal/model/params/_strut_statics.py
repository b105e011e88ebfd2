"""The statics of fixed-length struts: which they are, their forces, their joint change.

* **Strut.** A fixed URDF joint whose origin translation ``t_j`` is the strut (its
  length ``L_j = |t_j|``, e.g. a hexaslide's ``leg1_tip_joint``): its child link (or a
  link fixed to it) carries a loop-closure frame, and its parent link hangs from a
  passive joint that is not a floating base and does not carry the measured frame.
  The elongation is a placement translation along the strut: ``t_j ← t_j + δL_j t̂_j``.
* **Force.** ``F_j = dV/dL_j`` [N], the derivative of the potential energy along the
  closed configurations with the actuators held (virtual work):
  ``F_j = ∂V/∂L_j − λᵀ ∂c/∂L_j`` with ``λ`` the loop-closure constraint forces of the
  equilibrium ``g(q) = S τ + J_cᵀ λ`` and ``∂c/∂L_j`` the closure residuals' change
  under the elongation. ``F_j > 0`` when the load compresses the strut. A payload
  (:func:`pincal.model.with_payload`) is part of the load.
* **Joint change.** ``e_j = ∂q_act/∂L_j`` at a closed configuration (the rigid loops
  closed, the measured frame's motion matched in its measured components). A strut
  whose elongation the actuators cannot reproduce in the measured components (a
  parallelogram strut of a delta measured in orientation) is refused.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from pincal.errors import ParameterError
from pincal.model.files import COMPONENTS
from pincal.model.loops import six_by_nv
from pincal.model.params._term_compliance import equilibrium, gravity_model

if TYPE_CHECKING:
    from pincal.model._mechanism import Mechanism

__all__ = ["link_masses", "pose_loads", "strut_forces", "strut_loads", "struts"]

_MIN_LENGTH = 1e-9  # [m]: a shorter origin translation is not a strut
_CONSISTENT = 1e-6  # relative residual above which the actuators cannot reproduce δL
_PASSIVE_EXCLUDED = ("floating", "planar")


def struts(mech: Mechanism) -> tuple[str, ...]:
    """The fixed-length struts of a closed-loop mechanism (fixed joints), URDF order."""
    if not mech.closures:
        return ()
    tree = mech.tree
    loop_links = {c.frame_a for c in mech.closures} | {c.frame_b for c in mech.closures}
    frames, fid = mech.model.frames, mech.frame_id
    measured_body = frames[fid(mech.measured_frame)].parentJoint
    actuated = set(mech.actuated)
    out = []
    for name, uj in tree.joints.items():
        if uj.type != "fixed" or np.linalg.norm(uj.origin.translation) <= _MIN_LENGTH:
            continue
        rigid = _rigid_links(mech, uj.child)
        if not rigid & loop_links or frames[fid(uj.parent)].parentJoint == measured_body:
            continue  # no loop through it, or it hangs from the measured body (a platform)
        mover = _moving_joint(mech, uj.parent)
        if mover is None or mover in actuated or tree.joints[mover].type in _PASSIVE_EXCLUDED:
            continue
        out.append(name)
    return tuple(out)


def strut_loads(
    mech: Mechanism, q_act: np.ndarray, names: tuple[str, ...] | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Strut forces and their actuator equivalents at commanded values.

    Args:
        mech: the nominal mechanism (its link inertias, payload included).
        q_act: (m, n_act) commanded actuator values [rad, m].
        names: struts (default :func:`struts`).

    Returns:
        ``F`` (m, n_struts): ``dV/dL`` [N] (> 0 compressing); ``E`` (m, n_struts, n_act):
        the actuator change that moves the measured frame as a unit elongation does
        [rad/m, m/m].

    Raises:
        ParameterError: a pose the actuators and closures do not hold, or whose strut
            elongation the actuators cannot reproduce.
    """
    names = struts(mech) if names is None else names
    q_act = np.atleast_2d(np.asarray(q_act, dtype=float))
    F = np.empty((q_act.shape[0], len(names)))
    E = np.empty((q_act.shape[0], len(names), len(mech.actuated)))
    masses, model = link_masses(mech), gravity_model(mech)
    for k, q in enumerate(mech.configurations(q_act)):
        F[k], E[k] = pose_loads(mech, model, q, names, masses, k)
    return F, E


def strut_forces(
    mech: Mechanism,
    model: pin.Model,
    q: np.ndarray,
    names: tuple[str, ...],
    masses: Mapping[str, float],
    k: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, pin.Data]:
    """Strut forces at a closed configuration, by virtual work.

    Args:
        mech: the mechanism (its geometry: the forces' machine).
        model: its model with gravity (:func:`gravity_model`; with the gravity of the
            mechanism it is derived from, for a derived one).
        q: (nq,) closed configuration.
        names: the struts.
        masses: {link: mass [kg]} (:func:`link_masses`).
        k: the pose's index, for messages.

    Returns:
        ``F`` (n,) [N] (> 0 compressing), the closure change per unit elongation
        ``∂c/∂L`` (n_closure_rows, n), the actuators' selection ``S`` (nv, n_act) and the
        data at ``q`` (frames placed).

    Raises:
        ParameterError: the actuators and closures do not hold the load at ``q``.
    """
    data = model.createData()
    cols = [model.idx_vs[model.getJointId(a)] for a in mech.actuated]
    S = np.zeros((model.nv, len(cols)))
    S[cols, np.arange(len(cols))] = 1.0
    lam = equilibrium(mech, model, data, S, q, k)[len(cols) :]
    pin.framesForwardKinematics(model, data, q)
    gravity = model.gravity.linear
    dc = np.empty((mech.n_closure_rows, len(names)))
    F = np.empty(len(names))
    for i, strut in enumerate(names):
        uj = mech.tree.joints[strut]
        t = uj.origin.translation
        v = data.oMf[mech.frame_id(uj.parent)].rotation @ (t / np.linalg.norm(t))
        rigid = _rigid_links(mech, uj.child)
        dc[:, i] = _closure_change(mech, model, data, rigid, v)
        mass = sum(masses.get(link, 0.0) for link in rigid)  # lifted with the elongation
        F[i] = -mass * float(gravity @ v) - float(lam @ dc[:, i])
    return F, dc, S, data


def pose_loads(
    mech: Mechanism,
    model: pin.Model,
    q: np.ndarray,
    names: tuple[str, ...],
    masses: Mapping[str, float],
    k: int,
) -> tuple[np.ndarray, np.ndarray]:
    """(F (n,) [N], E (n, n_act)) of the struts ``names`` at a closed configuration ``q``.

    ``model``: the mechanism's model with gravity (:func:`gravity_model`).
    """
    F, dc, S, data = strut_forces(mech, model, q, names, masses, k)
    cols = S.argmax(axis=0)  # each actuator's velocity index, in actuated order
    Jc = mech.closure_jacobian(q)
    Jm = _measured_jacobian(mech, model, data, q)
    _check_determined(mech, np.hstack([S, Jc.T]), dc, names)
    # the loops with a strut elongated and the actuators held: J_c δq = −∂c/∂L, Sᵀ δq = 0
    rhs = np.vstack([-dc, np.zeros((S.shape[1], len(names)))])
    held = np.linalg.lstsq(np.vstack([Jc, S.T]), rhs, rcond=None)[0]
    dx = Jm @ held
    # the rigid loops closed with the same measured motion: J_c δq' = 0, J_m δq' = δx
    A = np.vstack([Jc, Jm])
    b = np.vstack([np.zeros((Jc.shape[0], len(names))), dx])
    rigid_dq = np.linalg.lstsq(A, b, rcond=None)[0]
    miss = np.linalg.norm(A @ rigid_dq - b, axis=0)
    bad = np.flatnonzero(miss > _CONSISTENT * np.maximum(np.linalg.norm(dx, axis=0), 1e-12))
    if bad.size:
        raise ParameterError(
            f"{mech.name!r} at pose {k}: the actuators cannot move the measured frame as "
            f"strut {names[bad[0]]!r} elongating does in its measured components "
            f"{list(mech.measured_components)} (miss {miss[bad[0]]:.3g}); a strut "
            f"compliance needs actuators that control what is measured"
        )
    return F, rigid_dq[cols].T


def _check_determined(
    mech: Mechanism, A: np.ndarray, dc: np.ndarray, names: tuple[str, ...]
) -> None:
    """Refuse a strut whose force the statics leave open (an over-constrained loop).

    ``F`` depends on λ through ``∂c/∂L``; λ is free along the null space of
    ``A = [S, J_cᵀ]`` (redundant closure rows), and ``F`` is determined only when
    ``∂c/∂L`` is orthogonal to that freedom.
    """
    _, sv, Vt = np.linalg.svd(A)
    rank = int(np.sum(sv > 1e-9 * sv[0]))
    free = Vt[rank:, A.shape[1] - dc.shape[0] :]  # λ directions the equilibrium leaves open
    if not free.size:
        return
    open_ = np.linalg.norm(free @ dc, axis=0)
    bad = np.flatnonzero(open_ > 1e-6 * np.maximum(np.linalg.norm(dc, axis=0), 1e-12))
    if bad.size:
        raise ParameterError(
            f"{mech.name!r}: strut {names[bad[0]]!r} closes an over-constrained loop (e.g. "
            f"a parallelogram bar): the statics do not determine its axial force, so a "
            f"strut compliance is not defined for it"
        )


def _measured_jacobian(
    mech: Mechanism, model: pin.Model, data: pin.Data, q: np.ndarray
) -> np.ndarray:
    """(k, nv) Jacobian of the measured components.

    Positions in world axes, rotations in the measured frame: the axes of the
    measurement residual.
    """
    fid = mech.frame_id(mech.measured_frame)
    world = six_by_nv(pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED))
    local = six_by_nv(pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL))
    rows = [COMPONENTS.index(c) for c in mech.measured_components]
    return np.vstack([world[:3], local[3:]])[rows]


def _closure_change(
    mech: Mechanism, model: pin.Model, data: pin.Data, rigid: set[str], v: np.ndarray
) -> np.ndarray:
    """(n_closure_rows,) closure residuals' change per unit elongation (world velocity v)."""

    def local(frame: str, oMf: pin.SE3) -> np.ndarray:
        moved = np.concatenate([oMf.rotation.T @ v, np.zeros(3)]) if frame in rigid else np.zeros(6)
        return moved[:, None]

    blocks = []
    for c in mech.closures:
        oMa = data.oMf[mech.frame_id(c.frame_a)]
        oMb = data.oMf[mech.frame_id(c.frame_b)]
        blocks.append(c.jacobian(oMa, oMb, local(c.frame_a, oMa), local(c.frame_b, oMb))[:, 0])
    return np.concatenate(blocks)


def link_masses(mech: Mechanism) -> dict[str, float]:
    """{link: mass [kg]} of the URDF's links with an ``<inertial>``."""
    out = {}
    for link in ET.fromstring(mech.urdf_xml).iter("link"):
        mass = link.find("inertial/mass")
        if mass is not None:
            out[link.get("name", "")] = float(mass.get("value", "0"))
    return out


def _rigid_links(mech: Mechanism, link: str) -> set[str]:
    """``link`` and the links fixed to it below (through fixed joints)."""
    out, stack = {link}, [link]
    while stack:
        parent = stack.pop()
        for uj in mech.tree.joints.values():
            if uj.parent == parent and uj.type == "fixed" and uj.child not in out:
                out.add(uj.child)
                stack.append(uj.child)
    return out


def _moving_joint(mech: Mechanism, link: str) -> str | None:
    """The nearest movable joint above ``link`` (None: fixed to the root)."""
    tree = mech.tree
    while link in tree.parent_joint:
        joint = tree.parent_joint[link]
        if tree.joints[joint].type != "fixed":
            return joint
        link = tree.joints[joint].parent
    return None

"""The Pinocchio model of a URDF + sidecar: joint kinds the URDF cannot express, ranges.

* ``joint_name`` / ``joint_type`` (the robot.yaml convention): each listed URDF joint
  (a placeholder such as a revolute or fixed joint) becomes a spherical joint
  (Pinocchio ``JointModelSpherical``, a ball joint about the joint origin) or a
  universal joint (``JointModelUniversal``, two intersecting perpendicular revolute axes
  at the joint origin, q = the two angles [rad], first axis turned first). A universal
  joint's placeholder must be a revolute joint: its URDF ``<axis>`` a is the first
  axis; the second is the joint-frame unit vector e that follows a's largest component
  in the cycle x → y → z → x, made perpendicular to a (e − (e·a)a, normalised) — for
  a = z it is x, for x it is y, for y it is z. Rotate the joint ``<origin>`` to orient it.
  ``ujoint_<a><b>`` (``UJOINT_XY``, ``UJOINT_YZ``, ``UJOINT_ZY``…, the robot.yaml
  collection's names) is the universal joint of two revolutes about the joint frame's
  unit axes a, then b (b turned with the first angle), both at the joint origin:
  ``R = R_a(q1) R_b(q2)`` — the axes are named, the placeholder's ``<axis>`` is not used
  (so ``ujoint_zy`` differs from ``universal`` on a z axis, whose second axis is x).
  Its placeholder is any one-dof joint. ``fixed`` locks a one-dof joint at 0: the
  URDF text is rewritten with the joint ``fixed`` (:func:`lock_joints`), so the child
  hangs at the joint origin, the joint has the six origin parameters of a fixed joint
  and the exported calibrated URDF keeps it fixed.
* A revolute or prismatic joint whose ``<limit>`` has no ``lower``/``upper`` gets the
  URDF default 0/0: a zero-width range means "no range given" and is made unlimited.
  Each such joint yields a note (``Mechanism.notes``, printed by ``pincal info``).
"""

from __future__ import annotations

import logging

import numpy as np
import pinocchio as pin

from pincal._limits import active_limits
from pincal.errors import ModelFileError, UnknownNameError, clip
from pincal.model.files._sidecar import Sidecar
from pincal.model.files._urdf import MOVABLE_TYPES, UrdfTree
from pincal.model.files._urdf_check import captured_stderr

__all__ = ["build_model", "lock_joints"]

log = logging.getLogger(__name__)


def build_model(urdf_xml: str, tree: UrdfTree, sidecar: Sidecar) -> tuple[pin.Model, list[str]]:
    """Build the Pinocchio model and the notes about it.

    Args:
        urdf_xml: URDF text.
        tree: the parsed URDF (for joint types and names).
        sidecar: the typed sidecar (joint kinds and workspace ranges).

    Returns:
        (model, notes): the model (limits widened where the URDF gave none) and
        human-readable notes, one per adjusted joint.

    Raises:
        ModelFileError: Pinocchio cannot build the URDF, or a joint kind is unsupported.
        UnknownNameError: ``joint_name`` lists a joint the URDF does not have.
    """
    built, printed, error = captured_stderr(lambda: pin.buildModelFromXML(urdf_xml))
    lines = [line.strip() for line in printed.splitlines()]
    said = " ".join(line for line in lines if line.startswith("Error"))
    if error is not None or built is None:
        why = f"; the URDF parser said: {clip(said, 400)}" if said else ""
        raise ModelFileError(f"Pinocchio cannot build the URDF model: {clip(str(error))}{why}")
    if said:
        log.warning("the URDF parser reports for %r: %s", tree.name, clip(said, 2000))
    model = built
    notes: list[str] = []
    if any(k != "fixed" for k in sidecar.joint_type):
        model = _replace_joints(model, tree, sidecar)
        limits = active_limits()
        limits.check(
            "degrees of freedom (with the sidecar's spherical joints)",
            model.nv,
            limits.dof,
            "PINCAL_MAX_DOF",
            f"URDF robot '{clip(tree.name)}'",
        )
    notes += [
        f"joint {n!r} is locked at 0 (sidecar joint_type FIXED)"
        if k == "fixed"
        else f"joint {n!r} is a {k.upper() if k.startswith('ujoint_') else k} joint "
        "(sidecar joint_type)"
        for n, k in zip(sidecar.joint_name, sidecar.joint_type, strict=True)
    ]
    notes += _open_zero_ranges(model, sidecar)
    notes += _mimic_notes(urdf_xml, tree, list(model.names)[1:])
    return model, notes


_mimics_told: set[tuple[str, str]] = set()  # (robot, joint) already warned about


def _mimic_notes(urdf_xml: str, tree: UrdfTree, movable: list[str]) -> list[str]:
    """A note (and one warning per process) per movable joint with a ``<mimic>``.

    Pinocchio builds it as an independent joint: the coupling is not modelled.
    """
    if "<mimic" not in urdf_xml:
        return []
    import xml.etree.ElementTree as ET

    notes = []
    for e in ET.fromstring(urdf_xml).iter("joint"):
        mimic = e.find("mimic")
        name = e.get("name", "")
        if mimic is None or name not in movable:
            continue
        note = (
            f"joint {name!r} mimics {mimic.get('joint')!r} in the URDF; pincal moves it as an "
            "independent joint (the <mimic> coupling is not modelled): its value is needed "
            "in every pose like any other joint's"
        )
        notes.append(note)
        if (tree.name, name) not in _mimics_told:
            _mimics_told.add((tree.name, name))
            log.warning("%s", note)
    return notes


def lock_joints(urdf_xml: str, tree: UrdfTree, sidecar: Sidecar) -> tuple[str, UrdfTree]:
    """The URDF text and tree with the sidecar's ``fixed`` joints locked.

    Unchanged when there are none or they are fixed already.

    Raises:
        UnknownNameError: a ``fixed`` joint the URDF does not have.
        ModelFileError: a ``fixed`` joint that is not a one-dof joint.
    """
    kinds = zip(sidecar.joint_name, sidecar.joint_type, strict=True)
    names = [n for n, k in kinds if k == "fixed"]
    if all(n in tree.joints and tree.joints[n].type == "fixed" for n in names):
        return urdf_xml, tree
    return tree.locked(names)


def _replace_joints(model: pin.Model, tree: UrdfTree, sidecar: Sidecar) -> pin.Model:
    kinds = {
        n: k for n, k in zip(sidecar.joint_name, sidecar.joint_type, strict=True) if k != "fixed"
    }
    movable = list(model.names)[1:]
    for name, kind in kinds.items():
        if name not in tree.joints:
            raise UnknownNameError("joint", name, list(tree.joints))
        if name not in movable:
            raise ModelFileError(
                f"sidecar joint_name {name!r} is a {tree.joints[name].type} URDF joint, which "
                f"Pinocchio merges away; declare it as a revolute (any axis) placeholder to make "
                f"it {kind}"
            )
        if kind.startswith("ujoint_") and tree.joints[name].type not in MOVABLE_TYPES:
            raise ModelFileError(
                f"sidecar joint_type {kind.upper()!r} for {name!r}: the placeholder must be a "
                f"one-dof joint (revolute, continuous or prismatic; its <axis> is not used), "
                f"got a {tree.joints[name].type} joint"
            )
        if kind == "universal" and tree.joints[name].type not in ("revolute", "continuous"):
            raise ModelFileError(
                f"sidecar joint_type 'universal' for {name!r}: the placeholder must be a "
                f"revolute joint whose <axis> is the first axis of the universal joint, got a "
                f"{tree.joints[name].type} joint"
            )
    new = pin.Model()
    new.name = model.name
    for j in range(1, model.njoints):
        name = model.names[j]
        placement = model.jointPlacements[j]
        if name in kinds:
            kind = kinds[name]
            if kind == "universal":
                joint = _universal(tree.joints[name].axis)
            elif kind.startswith("ujoint_"):
                a, b = (np.eye(3)["xyz".index(c)] for c in kind[-2:])
                joint = pin.JointModelUniversal(a, b)
            else:
                joint = pin.JointModelSpherical()
            jid = new.addJoint(model.parents[j], joint, placement, name)
        else:
            qi, nq, vi, nv = model.idx_qs[j], model.nqs[j], model.idx_vs[j], model.nvs[j]
            jid = new.addJoint(
                model.parents[j],
                model.joints[j],
                placement,
                name,
                model.effortLimit[vi : vi + nv],
                model.velocityLimit[vi : vi + nv],
                model.lowerPositionLimit[qi : qi + nq],
                model.upperPositionLimit[qi : qi + nq],
            )
        new.appendBodyToJoint(jid, model.inertias[j], pin.SE3.Identity())
    for f in list(model.frames)[1:]:
        frame = pin.Frame(f.name, f.parentJoint, f.parentFrame, f.placement, f.type, f.inertia)
        new.addFrame(frame, False)
    return new


def _universal(axis: np.ndarray) -> pin.JointModel:
    """Universal joint whose first axis is ``axis`` (see the module doc for the second)."""
    a = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    e = np.eye(3)[(int(np.argmax(np.abs(a))) + 1) % 3]
    b = e - float(e @ a) * a
    return pin.JointModelUniversal(a, b / np.linalg.norm(b))


def _open_zero_ranges(model: pin.Model, sidecar: Sidecar) -> list[str]:
    notes = []
    lower, upper = model.lowerPositionLimit.copy(), model.upperPositionLimit.copy()
    for j in range(1, model.njoints):
        if model.nqs[j] != 1:
            continue
        qi, name = model.idx_qs[j], model.names[j]
        if lower[qi] != upper[qi]:
            continue
        given = sidecar.workspace.joints.get(name)
        lower[qi], upper[qi] = given if given else (-np.inf, np.inf)
        where = (
            f"the sidecar workspace range [{given[0]:.6g}, {given[1]:.6g}] is its range"
            if given
            else "treated as unlimited"
        )
        notes.append(f"joint {name!r} has a zero-width URDF <limit> (no lower/upper); {where}")
    model.lowerPositionLimit, model.upperPositionLimit = lower, upper
    return notes

"""Loading a mechanism from a model spec (directory, URDF, MJCF, bundled or robot name)."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from pincal._files import read_text
from pincal.errors import MobilityError, ModelFileError
from pincal.model._mechanism import Mechanism
from pincal.model.files import UrdfTree
from pincal.model.loading._lock_values import lock_values_at_home
from pincal.model.loading._mjcf import load_mjcf
from pincal.model.loading._model_files import read_sidecar
from pincal.model.loading._named import NamedModel, resolve_named, turn_note
from pincal.model.loading._serial import lock_joints
from pincal.model.loops import SolverOptions, six_by_nv

__all__ = ["load_mechanism"]

def load_mechanism(
    spec: str | Path,
    measured_frame: str | None = None,
    options: SolverOptions | None = None,
    *,
    sidecar: str | Path | Mapping[str, Any] | None = None,
    lock: Mapping[str, float | str] | None = None,
) -> Mechanism:
    """Load a mechanism from a model directory, a ``.urdf`` or MJCF ``.xml`` path or a name.

    Names are bundled models (:func:`bundled_models`) or example-robot-data robots.
    An MJCF file is converted to URDF + sidecar first (:func:`pincal.model.load_mjcf`).
    A ``.yaml`` file (or a directory holding one) whose key ``robot`` names a robot is
    a local sidecar for it (see :mod:`pincal.model.loading._named`).

    A sidecar ``<name>.yaml`` beside the URDF declares closures, actuation, measured
    frame and presets (see docs/sidecar.md). A bare serial URDF needs none: its 1-dof
    joints that move the measured frame are actuated and the measured frame is chosen
    by name (effector, ee, tcp, tool, flange, platform...) or as the deepest leaf link
    without a closure. An example-robot-data robot without a sidecar takes its home
    from the package's SRDF, else a searched regular one, and an open chain standing on
    its base a floor (:mod:`pincal.model.reach._home_search`, :mod:`pincal.model.reach._floor`);
    ``mech.notes`` says what was loaded and assumed.

    Args:
        spec: the model.
        measured_frame: the measured frame (wins over the sidecar's).
        options: solver options.
        sidecar: a sidecar file for the model (its keys replace the model's own), or
            its keys already read (a mapping; a ``robot`` key in it is ignored).
        lock: joints made fixed ``{name: value}`` [rad or m] or ``"home"`` (the home
            value: sidecar, SRDF or searched, else 0) (wins over the sidecar's ``lock``);
            joints that mimic them are locked too. A lock does not move the home: a
            robot by name's searched home is searched with the chain's joints free, the
            home ``pincal info MODEL --frame FRAME`` prints.

    Raises:
        ModelFileError, UnknownNameError, ClosureError, MobilityError.
    """
    if Path(spec).suffix.lower() == ".xml":

        if sidecar is not None or lock:
            raise ModelFileError(
                "--sidecar and --lock apply to URDF models, not to MJCF files: write the "
                "keys (e.g. 'lock: {joint: 0}') in the sidecar <stem>.yaml beside the MJCF"
            )
        return load_mjcf(spec, measured_frame, options=options)

    named = resolve_named(spec, sidecar, lock)
    urdf = named.urdf
    urdf_xml = read_text(urdf, "URDF", error=ModelFileError)
    UrdfTree(urdf_xml, source=urdf)  # checked first, so that a bad URDF's messages name the file
    side = dict(named.sidecar)
    home_notes: list[str] = []
    if named.erd_defaults and named.lock and "home" not in side:
        # one home with or without locks: the one searched with the chain's joints free
        free_side, home_notes = _free_home(named, urdf, urdf_xml, measured_frame, options)
        if isinstance(free_side.get("home"), Mapping):
            side["home"] = dict(free_side["home"])
    locks = lock_values_at_home(named.lock, side.get("home"))
    mech, extra = _defaults(named, urdf, urdf_xml, side, measured_frame, options)
    notes = list(named.notes)
    if locks:
        notes.append(f"locked: {', '.join(f'{k} = {v:.6g}' for k, v in locks.items())}")
    notes.extend(home_notes)
    notes.extend(extra)
    singular = _singular_home(mech) if named.erd_defaults or named.local else None
    if singular:
        notes.append(singular)
    return mech.with_notes(before=notes)


def _free_home(named: NamedModel, urdf: Path, urdf_xml: str, measured_frame: str | None,
               options: SolverOptions | None) -> tuple[dict[str, Any], list[str]]:  # fmt: skip
    """The sidecar (its searched ``home``) and notes of the model, its chain's joints free.

    Locks of joints off the chain to the measured frame stay (they do not move its
    home; a 50-joint robot's search is ten times faster without them).
    """
    full = Mechanism(urdf_xml, dict(named.sidecar), name=urdf.stem, source=urdf,
                     measured_frame=measured_frame, options=options)  # fmt: skip
    off = {k: v for k, v in named.lock.items() if k not in full.actuated}
    if len(off) == len(named.lock):
        return {}, []  # no lock on the chain: the locked search is the same
    free = dataclasses.replace(named, lock=off)
    side = dict(named.sidecar)
    _, extra = _defaults(free, urdf, urdf_xml, side, measured_frame, options)
    return side, [n for n in extra if n.startswith("home")]


def _defaults(named: NamedModel, urdf: Path, urdf_xml: str, side: dict[str, Any],
              measured_frame: str | None,
              options: SolverOptions | None) -> tuple[Mechanism, list[str]]:  # fmt: skip
    """The mechanism with ``named.lock`` applied and the defaults of a robot by name.

    ``side`` (the sidecar mapping) is updated in place with the searched ``home``, the
    floor and the one-turn joint ranges. Returns the mechanism and the notes.
    """
    locks = lock_values_at_home(named.lock, side.get("home"))
    if locks:
        urdf_xml = lock_joints(urdf_xml, locks)
        gone = set(locks) | {n for n, j in UrdfTree(urdf_xml).joints.items() if not j.movable}
        if side.get("name_mot") is not None:
            side["name_mot"] = [n for n in side["name_mot"] if n not in gone]
        if isinstance(side.get("home"), Mapping):
            side["home"] = {k: v for k, v in side["home"].items() if k not in gone}
    mech = Mechanism(
        urdf_xml, side, name=urdf.stem, source=urdf, measured_frame=measured_frame, options=options
    )
    if not mech.actuated and not mech.closures:
        raise MobilityError(
            f"nothing moves frame {mech.measured_frame!r} of {urdf.stem!r}: no unlocked joint "
            f"between the root and it (locked: {', '.join(sorted(locks)) or 'none'}); measure "
            "a frame further along the chain (--frame, the sidecar's measured_frame) or lock "
            "fewer joints"
        )
    kept = {k: v for k, v in named.turns.items() if k in mech.actuated}
    if kept:  # the defaults' one-turn ranges, for the actuated joints only
        side["workspace"] = {**(side.get("workspace") or {}), "joints": kept}
        mech = Mechanism(
            urdf_xml, side, name=urdf.stem, source=urdf, measured_frame=measured_frame,
            options=options,
        )  # fmt: skip
    extra: list[str] = [turn_note(list(kept))] if kept else []
    if named.erd_defaults:  # floor and a regular home (see pincal.model.reach._home_search)
        from pincal.model.reach import by_name_defaults

        user_ws = read_sidecar(named.local).get("workspace") if named.local else None
        new, said = by_name_defaults(mech, side, user_ws)
        side.clear()
        side.update(new)
        extra += said
        if said:
            mech = Mechanism(
                urdf_xml, side, name=urdf.stem, source=urdf, measured_frame=measured_frame,
                options=options,
            )  # fmt: skip
    return mech, extra


def _singular_home(mech: Mechanism) -> str | None:
    """A note when an open chain's home is singular for its measured frame, else None.

    Inverse kinematics started there (acceptance, compensation) may not move.
    """
    if mech.closures:
        return None
    import numpy as np
    import pinocchio as pin

    from pincal.model.files import COMPONENTS

    data = mech.model.createData()
    fid = mech.frame_id(mech.measured_frame)
    J = six_by_nv(pin.computeFrameJacobian(mech.model, data, mech.q_home, fid, pin.LOCAL))
    rows = [COMPONENTS.index(c) for c in mech.measured_components]
    cols = [mech.model.idx_vs[mech.model.getJointId(n)] for n in mech.actuated]
    G = J[np.ix_(rows, cols)]
    rank = int(np.linalg.matrix_rank(G, tol=1e-9 * max(float(np.abs(G).max()), 1e-300)))
    if rank >= min(G.shape):
        return None
    return (
        f"home is a singular configuration of the measured frame {mech.measured_frame!r} "
        f"(its actuators move it in {rank} of {min(G.shape)} directions there): inverse "
        f"kinematics from home may not move (acceptance, compensation); give a home away "
        f"from it in a sidecar ('home: {{joint: value}}', with --sidecar FILE or in a YAML "
        f"file with 'robot: {mech.name}')"
    )

"""The model catalogue: bundled models, model paths, sidecar files, loading."""

from __future__ import annotations

import difflib
import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from pincal._files import read_text
from pincal._yaml import load_yaml
from pincal.errors import ModelFileError, UnknownNameError, clip
from pincal.model._mechanism import Mechanism
from pincal.model._newton import SolverOptions
from pincal.model._urdf import UrdfTree

__all__ = ["MODELS_DIR", "bundled_models", "load_mechanism", "read_sidecar", "resolve_model_path"]

#: the bundled models (pincal/models links to the checkout's top-level models/; the wheel
#: ships them as package data)
MODELS_DIR = Path(__file__).resolve().parents[1] / "models"


def read_sidecar(path: Path) -> dict[str, Any]:
    """Parse a sidecar YAML file safely (see :func:`pincal._yaml.load_yaml`).

    No code execution, a size cap, bounded alias expansion, duplicate keys refused.

    Raises:
        ModelFileError: unreadable, not UTF-8, not YAML, a duplicate key, not a mapping.
        InputLimitError: too large, an alias bomb or nesting too deep.
    """
    data = load_yaml(path, "sidecar", ModelFileError)
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise ModelFileError(
            f"sidecar {clip(str(path))} must be a mapping of keys (closed_loop, name_mot, ...), "
            f"got a {type(data).__name__}"
        )
    return data


def bundled_models() -> list[str]:
    """Names of the models shipped in ``models/``."""
    if not MODELS_DIR.is_dir():
        return []
    return sorted(p.name for p in MODELS_DIR.iterdir() if (p / f"{p.name}.urdf").is_file())


def resolve_model_path(spec: str | Path, by_name: bool = False) -> tuple[Path, Path | None]:
    """Find the URDF (and sidecar, if any) for a model spec.

    The spec is a model directory, a URDF path, a bundled model name or an
    example-robot-data robot name (e.g. ``ur10``). With ``by_name`` it is a name only
    (a local path of that name is not looked at).
    """
    path = Path(spec)
    if by_name and (MODELS_DIR / str(spec)).is_dir():
        return resolve_model_path(MODELS_DIR / str(spec))
    if by_name:
        urdf = _named_urdf(str(spec))
    elif path.is_dir():
        urdf = path / f"{path.name}.urdf"
        if not urdf.is_file():
            candidates = sorted(path.glob("*.urdf"))
            if len(candidates) != 1:
                raise ModelFileError(f"model directory {str(path)!r} must hold {path.name}.urdf")
            urdf = candidates[0]
    elif path.suffix.lower() == ".urdf":
        urdf = path
        if not urdf.exists():  # a FIFO or device is refused by the bounded reader
            raise ModelFileError(f"URDF file {str(path)!r} does not exist")
    elif (MODELS_DIR / str(spec)).is_dir():
        return resolve_model_path(MODELS_DIR / str(spec))
    elif path.exists() or os.sep in str(spec):
        if not path.exists():
            what = "does not exist"
        elif not path.is_file():
            what = "is not a regular file"
        else:
            what = "is neither a model directory nor a .urdf or MJCF .xml file"
        raise ModelFileError(
            f"model {clip(str(spec))} {what}; give a model directory, a .urdf or an MJCF "
            ".xml file, or a model name (pincal --help lists them)"
        )
    else:
        urdf = _named_urdf(str(spec))
    sidecar = urdf.with_suffix(".yaml")
    return urdf, sidecar if sidecar.is_file() else None


def _named_urdf(name: str) -> Path:
    """The URDF of an example-robot-data robot name (UnknownNameError lists the names)."""
    from pincal.model._robots import example_robot_names, example_robot_urdf

    robots = example_robot_names()
    if name not in robots:
        close = difflib.get_close_matches(name, robots, n=3)
        raise UnknownNameError(
            "model",
            name,
            bundled_models() + [f"{n} (example-robot-data)" for n in close],
            f" or one of {len(robots)} example-robot-data robots (e.g. ur10, panda)",
        )
    return example_robot_urdf(name)


def load_mechanism(
    spec: str | Path,
    measured_frame: str | None = None,
    options: SolverOptions | None = None,
    *,
    sidecar: str | Path | None = None,
    lock: Mapping[str, float | str] | None = None,
) -> Mechanism:
    """Load a mechanism from a model directory, a ``.urdf`` or MJCF ``.xml`` path or a name.

    Names are bundled models (:func:`bundled_models`) or example-robot-data robots.
    An MJCF file is converted to URDF + sidecar first (:func:`pincal.model.load_mjcf`).
    A ``.yaml`` file (or a directory holding one) whose key ``robot`` names a robot is
    a local sidecar for it (see :mod:`pincal.model._named`).

    A sidecar ``<name>.yaml`` beside the URDF declares closures, actuation, measured
    frame and presets (see models/README.md). A bare serial URDF needs none: its 1-dof
    joints that move the measured frame are actuated and the measured frame is chosen
    by name (effector, ee, tcp, tool, flange, platform...) or as the deepest leaf link
    without a closure. An example-robot-data robot without a sidecar takes its home
    from the package's SRDF, else a searched regular one, and an open chain standing on
    its base a floor (:mod:`pincal.model._home_search`, :mod:`pincal.model._floor`);
    ``mech.notes`` says what was loaded and assumed.

    Args:
        spec: the model.
        measured_frame: the measured frame (wins over the sidecar's).
        options: solver options.
        sidecar: a sidecar file for the model (its keys replace the model's own).
        lock: joints made fixed ``{name: value}`` [rad or m] or ``"home"`` (the home
            value: sidecar or SRDF, else 0) (wins over the sidecar's ``lock``); joints
            that mimic them are locked too.

    Raises:
        ModelFileError, UnknownNameError, ClosureError, MobilityError.
    """
    if Path(spec).suffix.lower() == ".xml":
        from pincal.model._mjcf import load_mjcf

        if sidecar is not None or lock:
            raise ModelFileError(
                "--sidecar and --lock apply to URDF models, not to MJCF files: write the "
                "keys (e.g. 'lock: {joint: 0}') in the sidecar <stem>.yaml beside the MJCF"
            )
        return load_mjcf(spec, measured_frame, options=options)
    from pincal.model._named import resolve_named, turn_note
    from pincal.model._serial import lock_joints

    named = resolve_named(spec, sidecar, lock)
    urdf = named.urdf
    urdf_xml = read_text(urdf, "URDF", error=ModelFileError)
    UrdfTree(urdf_xml, source=urdf)  # checked first, so that a bad URDF's messages name the file
    side = dict(named.sidecar)
    locks = _lock_values_at_home(named.lock, side.get("home"))
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
    kept = {k: v for k, v in named.turns.items() if k in mech.actuated}
    if kept:  # the defaults' one-turn ranges, for the actuated joints only
        side["workspace"] = {**(side.get("workspace") or {}), "joints": kept}
        mech = Mechanism(
            urdf_xml, side, name=urdf.stem, source=urdf, measured_frame=measured_frame,
            options=options,
        )  # fmt: skip
    extra: list[str] = []
    if named.erd_defaults:  # floor and a regular home (see pincal.model._home_search)
        from pincal.model._home_search import by_name_defaults

        user_ws = read_sidecar(named.local).get("workspace") if named.local else None
        side, extra = by_name_defaults(mech, side, user_ws)
        if extra:
            mech = Mechanism(
                urdf_xml, side, name=urdf.stem, source=urdf, measured_frame=measured_frame,
                options=options,
            )  # fmt: skip
    notes = list(named.notes)
    if locks:
        notes.append(f"locked: {', '.join(f'{k} = {v:.6g}' for k, v in locks.items())}")
    if kept:
        notes.append(turn_note(list(kept)))
    notes.extend(extra)
    singular = _singular_home(mech) if named.erd_defaults or named.local else None
    if singular:
        notes.append(singular)
    mech.notes = tuple(notes) + mech.notes
    return mech


def _lock_values_at_home(lock: Mapping[str, float | str], home: Any) -> dict[str, float]:
    """Lock values with ``"home"`` replaced by the joint's home value (else 0) [rad or m]."""
    home = home if isinstance(home, Mapping) else {}
    out = {}
    for name, value in lock.items():
        if value == "home":
            h = home.get(name, 0.0)
            value = h[0] if isinstance(h, list | tuple) else h
        out[name] = float(value)
    return out


def _singular_home(mech: Mechanism) -> str | None:
    """A note when an open chain's home is singular for its measured frame, else None.

    Inverse kinematics started there (acceptance, compensation) may not move.
    """
    if mech.closures:
        return None
    import numpy as np
    import pinocchio as pin

    from pincal.model._closures import COMPONENTS

    data = mech.model.createData()
    fid = mech.frame_id(mech.measured_frame)
    J = pin.computeFrameJacobian(mech.model, data, mech.q_home, fid, pin.LOCAL)
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

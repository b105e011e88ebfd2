"""The pose-design files: selected poses, their actuator commands and the design record."""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from pincal._version import __version__
from pincal.io._atomic import atomic_write_text
from pincal.io._commands_file import write_commands
from pincal.io._poses_file import write_poses

if TYPE_CHECKING:
    from pincal.design import PoseDesign

__all__ = ["write_pose_design"]


def write_pose_design(
    design: PoseDesign,
    path: str | Path,
    extra: dict | None = None,
    actuator_units: Sequence[str] | None = None,
) -> tuple[Path, Path, Path]:
    """Write the selected poses, their actuator commands and the design record.

    Files (each written atomically):

    * ``path``: the nominal measured-frame poses with their actuator values as a pincal
      pose file (:func:`pincal.io.write_poses`; read by ``pincal view --poses``,
      ``pincal simulate --poses`` and ``pincal compensate --targets``);
    * ``<stem>.commands.csv``: the selected actuator values alone (a pincal command
      file);
    * ``<stem>.json``: index, its history, all indices, the scaling, the candidate
      source, plus ``extra`` entries.

    Args:
        design: the selection (:func:`pincal.design.select_poses`).
        path: the pose file to write (CSV); the other two files sit beside it.
        extra: further JSON entries (e.g. the command line).
        actuator_units: unit per actuator column (see :func:`pincal.io.si_actuator_units`);
            None writes SI values without a unit.

    Returns:
        (poses path, commands path, json path).
    """
    out = Path(path)
    c = design.candidates
    poses = [pin.SE3(R, p) for p, R in zip(c.positions, c.rotations, strict=True)]
    csv_path = write_poses(
        out, poses, actuated=c.actuated, q_act=c.q_act, actuator_units=actuator_units
    )
    cmd_path = write_commands(
        out.with_suffix(".commands.csv"), c.actuated, c.q_act, actuator_units=actuator_units
    )
    sel = design.selection
    record = {
        "written_by": f"pincal {__version__}",  # recognised as pincal's when replaced
        "units": "SI (m, rad)",
        "actuated": list(c.actuated),
        "count": len(c),
        "index": sel.index_name,
        "value": sel.value,
        "method": sel.method,
        "iterations": sel.iterations,
        "converged": sel.converged,
        "restarts": design.restarts,
        "history": list(sel.history),
        "indices": design.indices_all.as_dict(),
        "condition_number": (
            None if not np.isfinite(cond := design.indices_all.condition_number) else cond
        ),
        "scaling": design.scaling.describe(),
        "candidates": {
            "source": c.source,
            "searched": design.n_candidates,
            "tried": c.tried,
            "rejected": c.rejected,
        },
        "candidate_indices": [int(i) for i in design.indices],
        "parameters": list(c.param_names),
    }
    record.update(extra or {})
    json_path = atomic_write_text(out.with_suffix(".json"), json.dumps(record, indent=2))
    return csv_path, cmd_path, json_path

"""A targets file compensated as ``pincal compensate --targets`` does it, without the CLI.

:func:`compensate_targets` reads the target poses, checks that they give the components
the compensation imposes, starts each target's inverse kinematics from its nominal
command when the file carries one, compensates (:func:`pincal.compensation.compensate`,
joint terms included) and returns a :class:`TargetCompensation`: the commands to write,
the ``--json`` document and the text lines of the command. Nothing is written.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from pincal.compensation import (
    Compensation,
    JointTermCorrection,
    compensate,
    compensation_components,
)
from pincal.errors import ColumnError, UnreachablePoseError
from pincal.io import PoseFile, read_pose_file
from pincal.model import Mechanism

__all__ = ["TargetCompensation", "compensate_targets", "nominal_starts"]


@dataclass(frozen=True)
class TargetCompensation:
    """The commands :func:`compensate_targets` found, and what the command says of them.

    Attributes:
        mechanism: the calibrated mechanism compensated with.
        origin: where it came from, in words (``"calibration DIR"``, ``"model NAME"``).
        result: the compensation (:class:`pincal.compensation.Compensation`).
        start_note: where each target's inverse kinematics started, in words.
        allow_branch_change: whether commands on another branch were kept.
        joint_terms: the joint terms the commands include (``line``, ``terms``,
            ``largest_deflection`` {"rad": [rad], "m": [m]}), None without them.
    """

    mechanism: Mechanism
    origin: str
    result: Compensation
    start_note: str
    allow_branch_change: bool
    joint_terms: dict[str, Any] | None

    @property
    def reached(self) -> list[int]:
        """Indices of the targets whose commands are written (the reachable ones)."""
        return [i for i in range(len(self.result.reachable)) if self.result.reachable[i]]

    def largest_steps(self) -> dict[str, dict[str, Any]]:
        """Largest |Δq| from the start per actuator kind.

        Returns:
            {"rad"|"mm": {"value": [rad or mm], "target": index, "actuator": name}}.
        """
        out = {}
        for unit, shown, factor in (("rad", "rad", 1.0), ("m", "mm", 1e3)):
            step = self.result.largest_step(unit)
            if step is not None:
                value, i, k = step
                name = self.mechanism.actuated[k]
                out[shown] = {"value": value * factor, "target": i, "actuator": name}
        return out

    def summary(self, written: str) -> dict[str, Any]:
        """The ``--json`` document, the commands written to the file ``written``."""
        result = self.result
        return {
            "written": written,
            "source": self.origin,
            "model": self.mechanism.name,
            "components": list(result.components),
            "targets": len(result.reachable),
            "commands": len(self.reached),
            "unreachable": list(result.unreachable),
            "reasons": {str(k): v for k, v in result.reasons.items()},
            "starts": self.start_note,
            "branch_changes": {str(k): v for k, v in (result.branch_changes or {}).items()},
            "branch_changes_allowed": self.allow_branch_change,
            "largest_step": self.largest_steps(),
            "joint_terms": self.joint_terms,
        }

    def lines(self, written: str) -> list[str]:
        """The command's text output, the commands written to the file ``written``."""
        result, mech = self.result, self.mechanism
        out = [
            f"compensating {' '.join(result.components)} of the measured frame "
            f"{mech.measured_frame} ({mech.mobility} degrees of freedom) with the {self.origin}"
        ]
        msg = f"wrote {written}: {len(self.reached)} of {len(result.reachable)} targets"
        if result.unreachable:
            msg += f"; unreachable: {list(result.unreachable)}"
        out += [msg, f"starts: {self.start_note}"]
        if self.joint_terms:
            out.append(self.joint_terms["line"])
        out += [
            f"largest |Δq| from the start: {s['value']:.4g} {unit} "
            f"({s['actuator']}, target {s['target']})"
            for unit, s in self.largest_steps().items()
        ]
        out += [f"  target {k}: {result.reasons[k]}" for k in result.unreachable]
        if self.allow_branch_change and result.branch_changes:
            out.append(f"BRANCH CHANGES (allowed): targets {sorted(result.branch_changes)}")
            out += [f"  target {k}: {why}" for k, why in sorted(result.branch_changes.items())]
        return out


def nominal_starts(pf: PoseFile, mech: Mechanism) -> tuple[np.ndarray | None, str]:
    """The targets file's nominal commands in ``mech``'s actuator order, and a note.

    Returns:
        ((m, n_act) commands [m, rad], or None when the file has none or not the
        machine's actuators; where each target's inverse kinematics starts, in words).
    """
    if pf.q_act is None or not pf.actuated:
        return None, "no commands in the targets file: each target starts from the nearest solved"
    if sorted(pf.actuated) != sorted(mech.actuated):
        return None, (
            f"the targets file's actuator columns {list(pf.actuated)} are not the machine's "
            f"{list(mech.actuated)}: each target starts from the nearest solved one"
        )
    order = [list(pf.actuated).index(a) for a in mech.actuated]
    starts = np.asarray(pf.q_act, dtype=float)[:, order]
    return starts, f"the nominal command of each target ({len(starts)} in the targets file)"


def _terms_summary(
    result: Compensation, terms: JointTermCorrection | None, note: str
) -> dict[str, Any] | None:
    """The joint terms the commands include, and the largest deflection they undo."""
    if terms is None or result.deflection is None:
        return None
    d = np.abs(result.deflection[result.reachable])
    units = np.array(result.units)
    big = {
        "rad": float(d[:, units == "rad"].max(initial=0.0)) if d.size else 0.0,
        "m": float(d[:, units == "m"].max(initial=0.0)) if d.size else 0.0,
    }
    parts = [f"{big['rad'] * 1e3:.4f} mrad" if "rad" in units else "",
             f"{big['m'] * 1e3:.4f} mm" if "m" in units else ""]  # fmt: skip
    line = (f"commands include {note}: largest deflection undone "
            f"{' / '.join(p for p in parts if p)}")  # fmt: skip
    return {"line": line, "terms": terms.lines(), "largest_deflection": big}


def compensate_targets(
    mech: Mechanism,
    origin: str,
    targets: str | Path,
    components: str | None = None,
    terms: JointTermCorrection | None = None,
    terms_note: str = "",
    allow_branch_change: bool = False,
    skip_unreachable: bool = False,
    progress: Callable[[int, int], None] | None = None,
) -> TargetCompensation:
    """Compensated commands for the target poses of a pose file.

    Args:
        mech: the calibrated mechanism.
        origin: where it came from, in words (said in the text output).
        targets: the pose file (:func:`pincal.io.read_pose_file`; poses [m, rad]).
        components: the pose components to reach, comma-separated (None: the model's
            measured components).
        terms: the calibration's joint terms, included in the commands (None: none).
        terms_note: what they are, in words (see ``pincal.cli``'s ``calibration_terms``).
        allow_branch_change: keep commands on another branch than their start.
        skip_unreachable: leave unreachable targets out instead of failing.
        progress: called with (targets done, targets).

    Raises:
        ColumnError: the file lacks a component the compensation imposes.
        UnreachablePoseError: a target is unreachable and ``skip_unreachable`` is False.
    """
    comps = compensation_components(mech, components)
    pf = read_pose_file(targets)
    absent = [c for c in comps if c not in pf.components]
    if absent:
        raise ColumnError(
            f"{Path(targets).name} gives {' '.join(pf.components)} but the compensation "
            f"imposes {' '.join(comps)}: add columns {absent} or choose --components "
            f"{','.join(c for c in comps if c in pf.components) or 'x,y,z'}",
            missing=absent,
        )
    starts, start_note = nominal_starts(pf, mech)
    result = compensate(
        mech, pf.poses, progress=progress, components=comps,
        starts=starts, allow_branch_change=allow_branch_change, joint_terms=terms,
    )  # fmt: skip
    if result.unreachable and not skip_unreachable:
        first = result.unreachable[0]
        raise UnreachablePoseError(
            f"targets {list(result.unreachable)} are unreachable (target {first}: "
            f"{result.reasons[first]}); use --skip-unreachable to write the others"
        )
    joint_terms = _terms_summary(result, terms, terms_note)
    return TargetCompensation(mech, origin, result, start_note, allow_branch_change, joint_terms)

"""A model described as ``pincal info`` describes it: its structure and what it identifies.

:func:`structure_lines` lists the joints, closures (with their rank at home), actuated,
passive and idle joints, mobility and measured frame; :func:`describe_presets` runs the
identifiability analysis of each preset (with joint terms when asked) and finds the
identifiable base set, returning the JSON records and the text lines
(:class:`ModelDescription`). Nothing is printed.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from pincal.model import (
    Mechanism,
    degenerate_translations,
    describe_direction,
    direction_record,
    sample_actuators,
    with_joint_terms,
)
from pincal.sensitivity import BASE_POSES, Identifiability, base_set, identifiability, parameters

__all__ = [
    "ModelDescription",
    "base_line",
    "describe_presets",
    "reduction_line",
    "structure_lines",
]

def structure_lines(mech: Mechanism, frame_given: bool = False) -> list[str]:
    """The model's structure as text lines.

    Lists joints, closures (rank at home), actuated, passive and idle joints, mobility,
    measured frame (and the automatic candidates), and the notes about joint ranges
    and kinds. ``frame_given``: the measured frame was named on the command line.
    """
    m = mech.model
    lines = [
        f"model {mech.name}  ({mech.source})",
        f"  joints: {m.njoints - 1} (nq {m.nq}, nv {m.nv})",
    ]
    for j in range(1, m.njoints):
        lines.append(f"    {m.names[j]:24s} {m.joints[j].shortname()}")
    Jc = mech.closure_jacobian(mech.q_home)
    total = int(np.linalg.matrix_rank(Jc)) if Jc.size else 0
    lines.append(f"  closures: {len(mech.closures)} (rank {total} of {Jc.shape[0]} rows at home)")
    k0 = 0
    for c in mech.closures:
        rows = Jc[k0 : k0 + c.size]
        k0 += c.size
        rank = int(np.linalg.matrix_rank(rows)) if rows.size else 0
        lines.append(f"    {c.frame_a} ↔ {c.frame_b}  [{c.label}]  rank {rank}/{c.size}")
    actuated = set(mech.actuated)
    passive = [
        m.names[j] for j in range(1, m.njoints) if m.names[j] not in actuated and m.nvs[j] > 0
    ]
    lines.append(f"  actuated: {', '.join(mech.actuated)}")
    lines.append(f"  passive: {', '.join(passive) or '-'}")
    if mech.idle_joints:
        lines.append(
            f"  free passive (not held by the actuators, do not move the measured frame): "
            f"{', '.join(mech.idle_joints)}"
        )
    lines.append(f"  mobility: {mech.mobility} (= {mech.n_actuated} actuated joints)")
    lines.append(
        f"  measured frame: {mech.measured_frame} [{' '.join(mech.measured_components)}]"
        f"{'' if mech.sidecar.measured_frame or frame_given else ' (chosen automatically)'}"
    )
    others = [c for c in mech.measured_frame_candidates if c != mech.measured_frame][:5]
    if others:
        lines.append(f"    other candidates: {', '.join(others)}")
    for note in mech.notes:
        lines.append(f"  note: {note}")
    return lines


@dataclass(frozen=True)
class ModelDescription:
    """What each preset of a model identifies, as :func:`describe_presets` found it.

    Attributes:
        presets: one JSON record per preset (name, parameter count, identifiable rank,
            parameters breaking a loop closure; with one preset asked, its explanation
            and each parameter's direction).
        base: the ``base`` preset found (parameters, translations and weak directions
            left out), None when not looked for.
        lines: the text of ``pincal info`` for the presets and the base set.
    """

    presets: list[dict[str, Any]]
    base: dict[str, Any] | None
    lines: list[str]


def describe_presets(
    mech: Mechanism,
    preset: str | None,
    terms: Sequence[str],
    thermal_span: tuple[float, float],
    progress: Callable[[int, int], None] | None = None,
) -> ModelDescription:
    """The identifiability of ``preset`` (None: ``full`` and every preset, and ``base``).

    Args:
        mech: the mechanism (with its payload).
        preset: the one preset to explain parameter by parameter, or None.
        terms: the error model's joint-space terms (``compliance``, ``temperature``…)
            added beside each preset's parameters; with ``temperature`` the analysis runs
            on 60 random poses at temperatures drawn uniformly in ``thermal_span``.
        thermal_span: (low, high) temperatures [°C] of the thermal term's analysis.
        progress: ``progress(done, total)`` over the sets analysed (random-pose
            Jacobian SVDs).
    """
    step = progress or (lambda _done, _total: None)
    names = [preset] if preset else ["full", *mech.presets]
    with_base = preset is None and "base" not in mech.presets
    steps = len(names) + with_base
    sets = [with_joint_terms(mech, parameters(mech, name), terms) for name in names]
    idents: list[Identifiability] = []
    rows, cond = None, None
    if "temperature" in terms:  # random poses at temperatures spread over thermal_span
        rows = sample_actuators(mech, 60, np.random.default_rng(0))
        cond = {"temperature": np.random.default_rng(1).uniform(*thermal_span, len(rows))}
    for params in sets:
        idents.append(identifiability(mech, params, rows, rng=np.random.default_rng(0),
                                      conditions=cond))  # fmt: skip
        step(len(idents), steps)
    found = base_set(mech) if with_base else None  # = parameters(mech, "base")
    step(steps, steps)
    presets, lines = [], []
    for name, params, ident in zip(names, sets, idents, strict=True):
        n_breaking = int(ident.breaks_closure.size)
        presets.append(
            {
                "preset": name,
                "parameters": len(params),
                "identifiable": int(ident.rank),
                "breaks_closure": n_breaking,
                "explanation": list(ident.describe()) if preset else [],
                "directions": [direction_record(mech, p.name, p.joint, p.dof, p.twist)
                               for p in params.parameters] if preset else [],
            }
        )  # fmt: skip
        breaking = f", {n_breaking} break loop closure" if n_breaking else ""
        lines.append(
            f"  preset {name!r}: {len(params)} parameters, {ident.rank} identifiable{breaking}"
        )
        if preset:
            lines += [f"    {line}" for line in ident.describe()]
            lines.append("    what each parameter moves, in its parent link's frame (hold one "
                         "in a preset by {joints: J, along_parent: x|y|z|[a,b,c], hold: true}; "
                         "about_parent for rotations):")  # fmt: skip
            lines += [f"      {describe_direction(mech, p.name, p.joint, p.dof, p.twist)}"
                      for p in params.parameters]  # fmt: skip
    base = None
    if found is not None:  # the base preset, with what it leaves out
        n_base, n_degenerate = len(found.params), len(degenerate_translations(mech))
        base = {"parameters": n_base, "degenerate_translations_left_out": n_degenerate}
        base["weak_directions_left_out"] = found.weak
        lines.append(base_line(mech, n_base, n_degenerate, BASE_POSES))
        if found.note():
            lines.append(f"    {found.note()}")
    return ModelDescription(presets, base, lines)


def reduction_line(preset: str, rank: int, n: int) -> str:
    """The one line `pincal poses` and `pincal calibrate` print when reducing a preset.

    Printed when a rank-deficient preset (``rank`` of ``n`` parameters identifiable) is
    reduced to its identifiable base set.
    """
    return (
        f"pincal: preset {preset!r}: {rank} of {n} parameters identifiable; using its "
        f"identifiable base set (`pincal info MODEL` offers it as the 'base' preset)"
    )


def base_line(mech: Mechanism, n_base: int, n_degenerate: int, n_poses: int) -> str:
    """The line of `pincal info` that offers the identifiable base set as a preset."""
    left = (
        f"; {n_degenerate} translations between coincident passive axes left out"
        if n_degenerate
        else ""
    )
    return (
        f"  preset 'base': {n_base} parameters, all identifiable (the identifiable base set "
        f"of 'full' over {n_poses} random poses{left}); use it with --params base "
        f"(simulate, calibrate) or --preset base (poses, info)"
    )

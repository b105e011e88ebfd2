"""Parameter sets by name: ``full``, sidecar presets, computed presets, explicit entries.

:func:`parameters` turns a preset name (``PRESET+TERM…`` adds joint-space terms) or a
list of entries (``"<joint>.<dof>"``, joint patterns with dofs or parent-frame
directions, ``hold`` entries) into a :class:`pincal.model.ParameterSet` of
:mod:`pincal.model.params._parameters`.
"""

from __future__ import annotations

import fnmatch
from collections.abc import Callable, Mapping, Sequence

from pincal.errors import ParameterError, UnknownNameError
from pincal.model._mechanism import Mechanism
from pincal.model.params._directions import matching_dofs
from pincal.model.params._joint_term_set import with_joint_terms
from pincal.model.params._joint_terms import term_of_dof
from pincal.model.params._parameters import (
    DOFS,
    Parameter,
    ParameterSet,
    full_parameters,
    origin_dofs,
    origin_parameter,
)

__all__ = ["parameters"]

_COMPUTED_ELSEWHERE = {"base": "pincal.parameters (pincal.sensitivity.parameters)"}
"""Computed presets of later stages, named in the error when they are asked for here."""


def parameters(
    mech: Mechanism,
    preset: str | Sequence = "full",
    *,
    computed: Mapping[str, Callable[[Mechanism], ParameterSet]] | None = None,
) -> ParameterSet:
    """Build a parameter set from a preset name, or an explicit list of entries.

    Args:
        mech: the mechanism.
        preset: ``"full"``, a computed preset named in ``computed`` (a sidecar preset of
            the same name takes precedence), a preset name from the sidecar,
            ``PRESET+TERM[+TERM…]`` (the preset and joint-space terms on every actuated joint, e.g.
            ``base+compliance``; see :func:`pincal.model.with_joint_terms`), or a list
            whose entries are ``"<joint>.<dof>"`` strings or ``{"joints": pattern, "dofs":
            [...]}`` mappings (fnmatch patterns over URDF joint names). Instead of ``dofs``,
            an entry may name a direction in the parent link's frame
            (:mod:`pincal.model.params._directions`): ``along_parent: x|y|z|[a, b, c]`` (the
            joint's translation parallel to it) or ``about_parent`` (its rotation); an
            entry with ``hold: true`` removes what it names from the parameters listed
            before it.
        computed: presets computed by a later stage (name → ``builder(mech)``); the
            ``"base"`` preset is passed by :func:`pincal.sensitivity.parameters`.

    Raises:
        UnknownNameError: unknown preset, joint or dof (valid names listed).
    """
    computed = {} if computed is None else computed
    if not isinstance(preset, str | list | tuple):
        raise ParameterError(
            f"preset must be a name or a list of entries, got {type(preset).__name__}"
        )
    if isinstance(preset, str) and "+" in preset and preset not in mech.presets:
        # PRESET+TERM[+TERM…]: the preset and joint terms
        base, *kinds = preset.split("+")
        return with_joint_terms(mech, parameters(mech, base, computed=computed), kinds)
    if isinstance(preset, str):
        if preset == "full":
            return full_parameters(mech)
        if preset in computed and preset not in mech.presets:
            return computed[preset](mech)
        if preset not in mech.presets:
            where = _COMPUTED_ELSEWHERE.get(preset)
            hint = f" ('{preset}' is computed: use {where})" if where else ""
            raise UnknownNameError("preset", preset, ["full", *computed, *mech.presets], hint)
        label, entries = preset, mech.presets[preset]
        if not isinstance(entries, list):
            raise ParameterError(f"preset {preset!r} must be a list of entries")
    else:
        label, entries = "custom", preset
    joint_names = list(mech.tree.joints)
    params: list[Parameter] = []
    for entry in entries:
        held = isinstance(entry, dict) and entry.get("hold") is True
        chosen = [origin_parameter(mech, j, d) for j, d in _entry_pairs(mech, entry, joint_names)]
        if held:  # leave them out of the set built so far
            out = {p.name for p in chosen}
            if not out & {p.name for p in params}:
                raise ParameterError(
                    f"preset entry {entry!r} holds {sorted(out)}, none of which is listed "
                    "before it; list the parameters first, then the entries that hold some"
                )
            params = [p for p in params if p.name not in out]
        else:
            params += chosen
    return ParameterSet(params, label)


_DIRECTION_KEYS = ("along_parent", "about_parent")


def _entry_pairs(mech: Mechanism, entry: object, joint_names: list[str]) -> list[tuple[str, str]]:
    """(joint, dof) pairs of one preset entry (see :func:`parameters`)."""
    if isinstance(entry, str):
        joint, _, dof = entry.rpartition(".")
        pairs = [(joint, [dof])]
    elif isinstance(entry, dict) and "joints" in entry and (
        "dofs" in entry or any(k in entry for k in _DIRECTION_KEYS)
    ):
        keys = [k for k in ("dofs", *_DIRECTION_KEYS) if k in entry]
        if len(keys) != 1 or not isinstance(entry["joints"], str):
            raise ParameterError(
                f"preset entry {entry!r}: 'joints' must be a name pattern, with one of "
                f"'dofs' (a list of {', '.join(DOFS)}), 'along_parent' or 'about_parent'"
            )
        pattern = entry["joints"]
        matched = [j for j in joint_names if fnmatch.fnmatchcase(j, pattern)]
        if not matched:
            raise UnknownNameError("joint", pattern, joint_names)
        if keys[0] == "dofs":
            dofs_ = entry["dofs"]
            if not isinstance(dofs_, list | str):
                raise ParameterError(
                    f"preset entry {entry!r}: 'dofs' must be a list of {', '.join(DOFS)}"
                )
            pairs = [(j, [dofs_] if isinstance(dofs_, str) else list(dofs_)) for j in matched]
        else:
            key = keys[0]
            pairs = [
                (j, matching_dofs(mech, j, [(d, origin_parameter(mech, j, d).twist)
                                            for d in origin_dofs(mech, j)], key, entry[key]))
                for j in matched
            ]  # fmt: skip
    else:
        raise ParameterError(
            f"preset entry {entry!r} must be '<joint>.<dof>', {{joints: ..., dofs: [...]}} "
            "or {joints: ..., along_parent: x|y|z|[a, b, c]} (about_parent for rotations)"
        )
    out = []
    for joint, dofs in pairs:
        if joint not in mech.tree.joints:
            raise UnknownNameError("joint", joint, joint_names)
        for dof in dofs:
            if not isinstance(dof, str) or (dof not in DOFS and term_of_dof(dof) is None):
                raise UnknownNameError("dof", str(dof), DOFS)
            out.append((joint, dof))
    return out

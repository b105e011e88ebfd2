"""The ``base`` preset: the identifiable base set and why it leaves out what it does.

The analysis of :func:`pincal.sensitivity.analyse_jacobian` with the stricter threshold
:data:`~pincal.sensitivity.BASE_RTOL` = 100 × RANK_RTOL over :data:`BASE_POSES` seeded
workspace poses: directions between the two thresholds exist but are too weak to
identify in practice (and fall below the rank rule on other pose sets); the preset
leaves them out and :meth:`BaseSet.note` says so.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pincal.errors import UnidentifiableError
from pincal.model import (
    Mechanism,
    ParameterSet,
    degenerate_translations,
    full_parameters,
    sample_actuators,
)
from pincal.sensitivity._identifiability import BASE_RTOL, Identifiability, analyse_jacobian
from pincal.sensitivity._identification_jacobian import jacobian_and_closure_breaking
from pincal.sensitivity._rank import RANK_RTOL, numerical_rank

__all__ = ["BASE_POSES", "BaseSet", "base_parameters", "base_set"]

BASE_POSES = 60
"""Random workspace poses (seed 0) over which the ``base`` preset is computed."""


@dataclass(frozen=True)
class BaseSet:
    """The identifiable base set and why parameters were left out of it.

    Attributes:
        params: the base parameters (the ``base`` preset for the default candidates).
        analysis: identifiability of the candidates at :data:`BASE_RTOL`.
        weak: directions identifiable under the rank rule (σ > RANK_RTOL·σ1) but too weak
            for the base set (σ ≤ BASE_RTOL·σ1); one parameter fewer each.
        weakest: σ/σ1 of the weakest such direction (nan when ``weak`` is 0).
    """

    params: ParameterSet
    analysis: Identifiability
    weak: int
    weakest: float

    def note(self) -> str | None:
        """Why the weak directions were left out (None when there are none)."""
        if not self.weak:
            return None
        return (
            f"{self.weak} weakly identifiable direction(s) left out (singular value down to "
            f"{self.weakest:.2g} of the largest, below {BASE_RTOL:g}): the measurements "
            f"hardly change along them, so no instrument resolves them and even noise-free "
            f"double-precision data fixes them only to ~{1e-16 / self.weakest:.0e} relative"
        )


def base_set(mech: Mechanism, params: ParameterSet | None = None) -> BaseSet:
    """The identifiable base set with the reasons for what it leaves out.

    The candidates are ``params`` (default: the ``full`` preset) without their
    :func:`pincal.model.degenerate_translations` (never fitted); over :data:`BASE_POSES` random
    workspace poses drawn with seed 0 (deterministic), the base parameters of
    :func:`analyse_jacobian` with the threshold :data:`BASE_RTOL` are kept, in the
    candidates' order. Parameters that break loop closure, are absorbed by others, or
    only span directions weaker than :data:`BASE_RTOL` are left out.

    Args:
        mech: the mechanism.
        params: candidate parameters (default: ``full``); degenerate translations are
            left out of them.

    Returns:
        :class:`BaseSet` whose ``params`` is labelled ``"base"`` (default candidates) or
        ``"<label> base"``.

    Raises:
        UnidentifiableError: no candidate parameter changes the measured quantity.
    """
    # translations that split an emulated joint are never fitted (identify holds them):
    # left out of any candidates, so that every command reduces a preset to one set
    skip = set(degenerate_translations(mech))
    given = full_parameters(mech) if params is None else params
    candidates = given.subset([k for k, n in enumerate(given.names) if n not in skip])
    rows = sample_actuators(mech, BASE_POSES, np.random.default_rng(0))
    J, breaking = jacobian_and_closure_breaking(mech, candidates, rows)
    ident = analyse_jacobian(J, candidates.names, BASE_RTOL, breaks_closure=breaking)
    if numerical_rank(ident.singular_values, RANK_RTOL) == 0:
        raise UnidentifiableError(
            f"none of the {len(candidates)} parameters of {mech.name!r} changes the measured "
            f"components {list(mech.measured_components)}; measure more components",
            candidates.names,
        )
    sv = ident.singular_values
    weak = numerical_rank(sv, RANK_RTOL) - ident.rank
    weakest = float(sv[ident.rank + weak - 1] / sv[0]) if weak else float("nan")
    label = "base" if params is None else f"{params.label} base"
    return BaseSet(candidates.subset(ident.base, label), ident, weak, weakest)


def base_parameters(mech: Mechanism, params: ParameterSet | None = None) -> ParameterSet:
    """The identifiable base set: the ``base`` preset (``parameters(mech, "base")``).

    ``base_set(mech, params).params``: see :func:`base_set` (the candidates, the poses
    and the :data:`BASE_RTOL` threshold). Computed when asked (no cache).

    Args:
        mech: the mechanism.
        params: candidate parameters (default: ``full`` minus degenerate translations).

    Returns:
        ParameterSet labelled ``"base"`` (default candidates) or ``"<label> base"``.

    Raises:
        UnidentifiableError: no candidate parameter changes the measured quantity.
    """
    return base_set(mech, params).params

"""Parameter sets by preset name, the presets this stage computes (``"base"``) included.

The model stage resolves ``"full"``, the sidecar's presets and explicit entries, and
takes computed presets as an argument (it imports no later stage and keeps no
registry); this module passes it the ones computed here. Every stage after this one
resolves preset names through :func:`parameters` (exported as ``pincal.parameters``).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from types import MappingProxyType

from pincal.model import Mechanism, ParameterSet
from pincal.model import parameters as model_parameters
from pincal.sensitivity._base_set import base_parameters

__all__ = ["COMPUTED_PRESETS", "parameters"]

COMPUTED_PRESETS: Mapping[str, Callable[[Mechanism], ParameterSet]] = MappingProxyType(
    {"base": base_parameters}
)
"""The presets this stage computes: ``"base"``, the identifiable base set of ``full``
(:func:`~pincal.sensitivity.base_parameters`)."""


def parameters(mech: Mechanism, preset: str | Sequence = "full") -> ParameterSet:
    """A parameter set from a preset name or a list of entries, ``"base"`` included.

    :func:`pincal.model.parameters` with :data:`COMPUTED_PRESETS`: ``"base"`` is the
    identifiable base set of ``full`` over 60 seeded random workspace poses (a sidecar
    preset of the same name takes precedence).

    Args:
        mech: the mechanism.
        preset: ``"full"``, ``"base"``, a sidecar preset, ``PRESET+TERM[+TERM…]`` (e.g.
            ``base+compliance``) or a list of entries (see :func:`pincal.model.parameters`).

    Returns:
        The parameter set (SI: metres and radians per unit value).

    Raises:
        UnknownNameError: unknown preset, joint or dof (valid names listed).
    """
    return model_parameters(mech, preset, computed=COMPUTED_PRESETS)

"""Which pose components fix a machine's commands, from its actuator Jacobian.

Components x y z rx ry rz fix n actuators where their rows of the actuator Jacobian G
(:func:`pincal.model.actuator_jacobian`) have rank n: ``pincal poses`` switches its reach
screen off short of it, and inverse kinematics refuses components that are dependent
here and nearby, each naming components that would do.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from pincal.model.files import COMPONENTS

__all__ = ["fixing_components"]


def fixing_components(G: NDArray[np.float64], imposed: Sequence[str]) -> tuple[int, list[str]]:
    """The rank of the imposed components' map, and components that would fix the commands.

    Args:
        G: (6, n_act) actuator Jacobian of all six components x y z rx ry rz
            (:func:`actuator_jacobian` with ``components=COMPONENTS``) [m or rad per m
            or rad].
        imposed: the components imposed (names from x y z rx ry rz).

    Returns:
        ``(rank, suggestion)``: the rank of the imposed rows of G (tolerance 1e-9 of its
        largest entry), and components (x y z rx ry rz order) of rank ``n_act``: the
        imposed ones that add to the rank, then others of the imposed kind (positions or
        orientations) first; [] when no set of components reaches rank ``n_act``.
    """
    n = G.shape[1]
    tol = 1e-9 * max(float(np.abs(G).max(initial=0.0)), 1e-300)

    def rank(names: list[str]) -> int:
        return (
            int(np.linalg.matrix_rank(G[[COMPONENTS.index(c) for c in names]], tol)) if names else 0
        )

    kind = imposed[0].startswith("r") if imposed else False
    others = sorted(
        (c for c in COMPONENTS if c not in imposed), key=lambda c: c.startswith("r") != kind
    )
    keep: list[str] = []
    for c in [*imposed, *others]:
        if len(keep) < n and rank([*keep, c]) > len(keep):
            keep.append(c)
    return rank(list(imposed)), ([c for c in COMPONENTS if c in keep] if len(keep) == n else [])

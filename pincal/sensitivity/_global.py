"""Global sensitivity of geometric parameters over a workspace (seed 002).

The local sensitivity of parameter k at pose i is the norm of column k of the
identification Jacobian, taken separately over the position rows (x, y, z: [m per
unit of the parameter]) and over the orientation rows (rx, ry, rz: [rad per unit]).
The global sensitivity is its mean over the workspace samples, i.e. the usual index
``S(k) = ∫_W s_k dW / ∫_W dW`` estimated on a grid or uniform sample of W:

    S_pos(k) = mean_i ‖J_pos,i[:, k]‖,    S_ori(k) = mean_i ‖J_ori,i[:, k]‖.

``*_normalised`` divides each class by its largest entry (so the most sensitive
parameter of the class has 1). Parameters whose position AND orientation
sensitivities agree to a relative tolerance form a group (the patent's "equal global
sensitivity"); parameters with zero sensitivity in both classes are listed apart.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pincal.errors import ParameterError
from pincal.model import Mechanism, ParameterSet, sample_actuators
from pincal.sensitivity._identification_jacobian import identification_jacobian

__all__ = ["GlobalSensitivity", "global_sensitivity", "global_sensitivity_from_jacobians"]


@dataclass(frozen=True)
class GlobalSensitivity:
    """Workspace-averaged sensitivity of each parameter.

    Attributes:
        names: parameter (column) names, n of them.
        position: (n,) mean position-column norm [m per unit of the parameter]; zeros if
            no position component is measured.
        orientation: (n,) mean orientation-column norm [rad per unit]; zeros if none.
        position_normalised, orientation_normalised: (n,) divided by the class maximum.
        groups: groups (≥ 2 members, names in column order) of equal sensitivity in both
            classes, in order of decreasing position (then orientation) sensitivity.
        insensitive: names with zero sensitivity in both classes.
        n_samples: workspace samples averaged.
        rtol: relative tolerance of the equality test.
    """

    names: tuple[str, ...]
    position: np.ndarray
    orientation: np.ndarray
    position_normalised: np.ndarray
    orientation_normalised: np.ndarray
    groups: tuple[tuple[str, ...], ...]
    insensitive: tuple[str, ...]
    n_samples: int
    rtol: float

    def weights(self) -> np.ndarray:
        """(n,) combined normalised sensitivity, the larger of the two classes (0..1)."""
        return np.maximum(self.position_normalised, self.orientation_normalised)

    def group_of(self, name: str) -> tuple[str, ...]:
        """The group containing ``name`` (a 1-tuple if it is alone)."""
        for g in self.groups:
            if name in g:
                return g
        if name not in self.names:
            raise ParameterError(f"no parameter {name!r}; parameters are {list(self.names)}")
        return (name,)

    def describe(self) -> list[str]:
        """One line per parameter: name, S_pos, S_ori, normalised values."""
        lines = []
        for k, n in enumerate(self.names):
            lines.append(
                f"{n:24s} S_pos {self.position[k]:.6g}  S_ori {self.orientation[k]:.6g}  "
                f"(normalised {self.position_normalised[k]:.4f}, "
                f"{self.orientation_normalised[k]:.4f})"
            )
        return lines


def _normalise(s: np.ndarray) -> np.ndarray:
    top = float(np.max(s)) if s.size else 0.0
    return s / top if top > 0 else np.zeros_like(s)


def _equal(a: float, b: float, scale: float, rtol: float) -> bool:
    return abs(a - b) <= rtol * max(abs(a), abs(b)) + 1e-12 * scale


def global_sensitivity_from_jacobians(
    jacobians: np.ndarray,
    names: Sequence[str],
    position_rows: Sequence[int],
    orientation_rows: Sequence[int],
    rtol: float = 1e-6,
) -> GlobalSensitivity:
    """Global sensitivity from per-sample Jacobians.

    Args:
        jacobians: (m, k, n) identification Jacobians at m workspace samples.
        names: n column names.
        position_rows: indices into the k rows of the position components [m].
        orientation_rows: indices into the k rows of the orientation components [rad].
        rtol: relative tolerance for equal sensitivities (groups).
    """
    J = np.asarray(jacobians, dtype=float)
    if J.ndim != 3 or J.shape[2] != len(names):
        raise ParameterError(
            f"jacobians must have shape (m, k, {len(names)}) for {len(names)} names, got {J.shape}"
        )
    if not rtol > 0:
        raise ParameterError(f"rtol must be positive, got {rtol}")
    n = J.shape[2]
    pos_rows, ori_rows = list(position_rows), list(orientation_rows)
    pos = np.linalg.norm(J[:, pos_rows, :], axis=1).mean(axis=0) if pos_rows else np.zeros(n)
    ori = np.linalg.norm(J[:, ori_rows, :], axis=1).mean(axis=0) if ori_rows else np.zeros(n)
    scale_p, scale_o = float(np.max(pos, initial=0.0)), float(np.max(ori, initial=0.0))
    zero = [k for k in range(n) if pos[k] <= 1e-12 * scale_p and ori[k] <= 1e-12 * scale_o]
    order = sorted(set(range(n)) - set(zero), key=lambda k: (-pos[k], -ori[k], k))
    groups: list[list[int]] = []
    for k in order:
        for g in groups:
            j = g[0]
            if _equal(pos[k], pos[j], scale_p, rtol) and _equal(ori[k], ori[j], scale_o, rtol):
                g.append(k)
                break
        else:
            groups.append([k])
    return GlobalSensitivity(
        names=tuple(names),
        position=pos,
        orientation=ori,
        position_normalised=_normalise(pos),
        orientation_normalised=_normalise(ori),
        groups=tuple(tuple(names[k] for k in sorted(g)) for g in groups if len(g) > 1),
        insensitive=tuple(names[k] for k in zero),
        n_samples=J.shape[0],
        rtol=rtol,
    )


def global_sensitivity(
    mech: Mechanism,
    params: ParameterSet,
    workspace: np.ndarray | int = 200,
    *,
    rng: np.random.Generator | int | None = 0,
    values: np.ndarray | None = None,
    rtol: float = 1e-6,
) -> GlobalSensitivity:
    """Per-parameter sensitivity integrated over the workspace.

    Args:
        mech: nominal mechanism.
        params: the n parameters.
        workspace: actuator rows (m, n_act) of the workspace samples [m, rad] (e.g. a
            regular grid of poses through the inverse kinematics), or a number of random
            feasible samples drawn with :func:`pincal.sample_actuators`.
        rng: seed or generator for random samples.
        values: (n,) parameter values at which to linearise (default nominal).
        rtol: relative tolerance of the equal-sensitivity groups.

    Returns:
        GlobalSensitivity over the measured components of ``mech``.
    """
    if isinstance(workspace, int | np.integer):
        if workspace < 1:
            raise ParameterError(f"number of workspace samples must be ≥ 1, got {workspace}")
        rows = sample_actuators(mech, int(workspace), np.random.default_rng(rng))
    else:
        rows = np.atleast_2d(np.asarray(workspace, dtype=float))
        if rows.shape[1] != len(mech.actuated):
            raise ParameterError(
                f"workspace rows must have shape (m, {len(mech.actuated)}) for actuators "
                f"{list(mech.actuated)}, got {rows.shape}"
            )
    comps = tuple(mech.measured_components)
    J = identification_jacobian(mech, params, rows, values).reshape(
        rows.shape[0], len(comps), len(params)
    )
    pos_rows = [i for i, c in enumerate(comps) if c in ("x", "y", "z")]
    ori_rows = [i for i, c in enumerate(comps) if c.startswith("r")]
    return global_sensitivity_from_jacobians(J, params.names, pos_rows, ori_rows, rtol)

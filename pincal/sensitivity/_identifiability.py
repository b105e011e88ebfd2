"""Identifiability: rank, base parameters and the combinations the others fall into.

The numerical rank r of the column-scaled identification Jacobian over many poses
(from its singular values) is the number of identifiable parameters. The *base*
parameters are chosen greedily in the set's order (an orthogonalisation that keeps
a column when it is not in the span of the columns kept so far), so a preset's
physically meaningful parameters, listed first, are preferred. Every other
parameter's column is a combination of base columns, ``J_k = Σ_i β_ki J_i``: its
effect is absorbed into those base parameters and it cannot be identified.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pincal.model._mechanism import Mechanism
from pincal.model._parameters import ParameterSet

__all__ = ["Identifiability", "analyse_jacobian", "identifiability"]


@dataclass(frozen=True)
class Identifiability:
    """Result of an identifiability analysis.

    Attributes:
        names: all parameter names (n,).
        rank: numerical rank of the scaled Jacobian.
        base: indices of the identifiable base parameters (rank,), in name order.
        unidentifiable: indices of the parameters that are not identifiable.
        combinations: for each unidentifiable index k, ``{base index: β}`` such that the
            (scaled) column of k equals Σ β · base columns.
        singular_values: of the column-scaled Jacobian (descending).
        column_scale: norms used to scale each column (n,).
    """

    names: tuple[str, ...]
    rank: int
    base: np.ndarray
    unidentifiable: np.ndarray
    combinations: dict[int, dict[int, float]]
    singular_values: np.ndarray
    column_scale: np.ndarray

    @property
    def full_rank(self) -> bool:
        return self.rank == len(self.names)

    @property
    def base_names(self) -> tuple[str, ...]:
        return tuple(self.names[i] for i in self.base)

    @property
    def unidentifiable_names(self) -> tuple[str, ...]:
        return tuple(self.names[i] for i in self.unidentifiable)

    def describe(self, max_terms: int = 4) -> list[str]:
        """One sentence per unidentifiable parameter, e.g.
        ``"leg3_u1.rx is not identifiable (absorbed by +1.000·leg3_u2.rx)"``."""
        lines = []
        for k in self.unidentifiable:
            combo = self.combinations.get(int(k), {})
            terms = sorted(combo.items(), key=lambda kv: -abs(kv[1]))
            shown = [f"{b:+.3f}·{self.names[i]}" for i, b in terms[:max_terms]]
            if len(terms) > max_terms:
                shown.append(f"… ({len(terms) - max_terms} more)")
            absorbed = " ".join(shown) if shown else "no effect on the measurements"
            verb = "absorbed by" if shown else "it has"
            lines.append(f"{self.names[k]} is not identifiable ({verb} {absorbed})")
        return lines

    def summary(self) -> str:
        head = f"{self.rank} of {len(self.names)} parameters identifiable"
        return "\n".join([head, *self.describe()])


def analyse_jacobian(J: np.ndarray, names: tuple[str, ...], rtol: float = 1e-8) -> Identifiability:
    """Identifiability of the parameters whose identification Jacobian is ``J`` (N, n).

    Columns are scaled to unit norm first, so mixed units (m, rad) do not bias the
    rank; a column below 1e-12 of the largest column norm counts as zero (the
    parameter has no effect). ``rtol`` is the relative threshold
    on the pivoted R diagonal.
    """
    J = np.asarray(J, dtype=float)
    n = J.shape[1]
    scale = np.linalg.norm(J, axis=0)
    scale[scale <= 1e-12 * max(float(scale.max(initial=0.0)), 1e-300)] = 0.0  # no effect
    safe = np.where(scale > 0, scale, 1.0)
    Js = J / safe
    Js[:, scale == 0] = 0.0
    sv = np.linalg.svd(Js, compute_uv=False)
    rank = int(np.sum(sv > rtol * sv[0])) if sv.size and sv[0] > 0 else 0
    # Greedy selection in the given order: a column joins the base when it is not
    # (numerically) in the span of the earlier base columns. Presets list the physically
    # meaningful parameters first, so they are preferred as base parameters.
    basis = np.zeros((Js.shape[0], 0))
    chosen: list[int] = []
    for k in range(n):
        if len(chosen) == rank:
            break
        v = Js[:, k] - basis @ (basis.T @ Js[:, k])
        v -= basis @ (basis.T @ v)
        norm = np.linalg.norm(v)
        if norm > np.sqrt(rtol):
            basis = np.column_stack([basis, v / norm])
            chosen.append(k)
    base = np.array(chosen, dtype=int)
    others = np.array([k for k in range(n) if k not in set(chosen)], dtype=int)
    combos: dict[int, dict[int, float]] = {}
    if base.size and others.size:
        beta = np.linalg.lstsq(J[:, base], J[:, others], rcond=None)[0]  # parameter units
        bscale = safe[base][:, None] / safe[others][None, :]  # relative size in scaled terms
        for col, k in enumerate(others):
            combos[int(k)] = {
                int(base[i]): float(beta[i, col])
                for i in range(base.size)
                if abs(beta[i, col] * bscale[i, col]) > 1e-6
            }
    return Identifiability(tuple(names), rank, base, others, combos, sv, scale[:n])


def identifiability(
    mech: Mechanism,
    params: ParameterSet,
    q_act_rows: np.ndarray | None = None,
    n_poses: int = 60,
    rng: np.random.Generator | None = None,
    rtol: float = 1e-8,
) -> Identifiability:
    """Analyse which parameters the measured components can identify.

    Args:
        mech: nominal mechanism.
        params: parameter set to analyse.
        q_act_rows: (m, n_act) poses; by default ``n_poses`` random workspace poses.
        rng: random generator for the default poses.
        rtol: relative rank threshold.
    """
    from pincal.model._workspace import sample_actuators
    from pincal.sensitivity._jacobian import identification_jacobian

    if q_act_rows is None:
        q_act_rows = sample_actuators(mech, n_poses, rng or np.random.default_rng(0))
    J = identification_jacobian(mech, params, q_act_rows)
    return analyse_jacobian(J, params.names, rtol)

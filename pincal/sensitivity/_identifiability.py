"""Identifiability: rank, base parameters and the combinations the others fall into.

The numerical rank r of the column-scaled identification Jacobian over many poses is
the number of identifiable parameters; it follows the one rank rule of
:func:`pincal.sensitivity._rank.numerical_rank` (σi > rtol·σ1). The *base* parameters
are chosen greedily in the set's order (an orthogonalisation that keeps a column when
its part outside the span of the columns kept so far exceeds max(rtol, BASE_RTOL)·σ1
and 1 % of the weakest part of the best-conditioned choice,
:data:`~pincal.sensitivity._base_columns.ORDER_COST`), so a preset's physically
meaningful parameters, listed first, are preferred unless one is barely independent of
those before it (a base conditioned like that column).
The base always has exactly r members: the greedy pass stops at r, and if it found
fewer, the remaining members are the columns with the largest part outside the span
(column pivoting). Every other parameter's column is a combination of base columns,
``J_k = Σ_i β_ki J_i``: its effect is absorbed into those base parameters and it
cannot be identified.

Over-constrained loops (e.g. a ``6d`` closure of a planar loop) add a third class:
parameters whose change would open a loop that no passive-joint motion can close
(their closure-Jacobian column ∂c/∂p_k lies outside the range of ∂c/∂q_u at some
pose). They cannot change while the mechanism stays assembled, so they are reported
as *breaking loop closure* and are neither base nor absorbed parameters.

The ``base`` preset built on this analysis: :mod:`pincal.sensitivity._base_set`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from pincal.errors import PincalError
from pincal.model import (
    Mechanism,
    ParameterSet,
    active_limits,
    degenerate_translations,
    sample_actuators,
)
from pincal.sensitivity._base_columns import greedy_base
from pincal.sensitivity._closure_loops import ClosureLoop, closure_line, closure_loops
from pincal.sensitivity._identification_jacobian import jacobian_and_closure_breaking
from pincal.sensitivity._rank import RANK_RTOL, RangeSolver, numerical_rank, unit_columns

__all__ = [
    "BASE_RTOL",
    "Identifiability",
    "analyse_jacobian",
    "identifiability",
]

BASE_RTOL = 1e-6
"""Relative singular-value threshold of the ``base`` preset: 100 × the rank rule's
:data:`~pincal.sensitivity._rank.RANK_RTOL`. A direction between the two exists (the
rank rule counts it) but changes the measurements 1e6 times less than the strongest
one: a 1 µm instrument would fix it to ~1 m, exact double-precision data only to
~1e-10 of the parameter scale, and on fewer or other poses it may fall below the rank
rule. The base preset leaves such directions out, so its parameters stay identifiable
(to ≤ 1e-9 from noise-free data) on any reasonable pose set."""

_COMBINATION_CUTOFF = 1e-6
"""Coefficients (in column-scaled units) below this are left out of a combination."""


def _empty() -> np.ndarray:
    return np.zeros(0, dtype=int)


@dataclass(frozen=True)
class Identifiability:
    """Result of an identifiability analysis.

    Attributes:
        names: all parameter names (n,).
        rank: numerical rank of the scaled Jacobian of the closable parameters; always
            equal to ``len(base)``.
        base: indices of the identifiable base parameters (rank,), in name order.
        unidentifiable: indices of the closable parameters that are not identifiable.
        combinations: for each unidentifiable index k, ``{base index: β}`` such that the
            column of k equals Σ β · base columns (parameter units).
        singular_values: of the column-scaled Jacobian of the closable parameters
            (descending).
        column_scale: norms used to scale each column (n,).
        breaks_closure: indices of the parameters that cannot change without breaking a
            loop closure (over-constrained loops); not counted as identifiable.
        splits_joint: indices of the translations between coincident revolute axes
            (:func:`pincal.model.degenerate_translations`): changing one splits an
            emulated ball or universal joint, an error the physical joint cannot have
            (and the mechanism it gives may not be buildable); not counted as
            identifiable, never fitted.
        units: each parameter's SI unit (``m``, ``rad``, …), or () when not given: the
            sentences of :meth:`describe` then state amounts in mm and mrad.
        loops: each loop closure's label and the indices of the parameters on its loop
            (:func:`pincal.sensitivity.closure_loops`), or () when not known: the
            parameters that break closure are then said by joint only.
    """

    names: tuple[str, ...]
    rank: int
    base: np.ndarray
    unidentifiable: np.ndarray
    combinations: dict[int, dict[int, float]]
    singular_values: np.ndarray
    column_scale: np.ndarray
    breaks_closure: np.ndarray = field(default_factory=_empty)
    splits_joint: np.ndarray = field(default_factory=_empty)
    units: tuple[str, ...] = ()
    loops: tuple[ClosureLoop, ...] = ()

    @property
    def full_rank(self) -> bool:
        """True when every parameter is identifiable."""
        return self.rank == len(self.names)

    @property
    def base_names(self) -> tuple[str, ...]:
        """Names of the identifiable base set."""
        return tuple(self.names[i] for i in self.base)

    @property
    def unidentifiable_names(self) -> tuple[str, ...]:
        """Names of the parameters outside the base set."""
        return tuple(self.names[i] for i in self.unidentifiable)

    @property
    def breaks_closure_names(self) -> tuple[str, ...]:
        """Names of the parameters that would open a loop closure."""
        return tuple(self.names[i] for i in self.breaks_closure)

    @property
    def splits_joint_names(self) -> tuple[str, ...]:
        """Names of the translations inside an emulated ball or universal joint."""
        return tuple(self.names[i] for i in self.splits_joint)

    def describe(self, max_terms: int = 4) -> list[str]:
        """One sentence per parameter that is not identifiable.

        For example ``"leg3_u1.rx is not identifiable (absorbed by +1.000·leg3_u2.rx)"``;
        with :attr:`units`, in amounts a user can picture: ``"tool_frame.ty is not
        identifiable: 1 mm of it moves the measurements as +689 mrad of
        arm_7_joint.offset, +47.1 mm of tool_frame.tx do"``.
        """
        lines = []
        for k in self.unidentifiable:
            combo = self.combinations.get(int(k), {})
            terms = sorted(combo.items(), key=lambda kv: -abs(kv[1]))
            if self.units and terms:
                lines.append(self._in_units(int(k), terms, max_terms))
                continue
            shown = [f"{b:+.3f}·{self.names[i]}" for i, b in terms[:max_terms]]
            if len(terms) > max_terms:
                shown.append(f"… ({len(terms) - max_terms} more)")
            absorbed = " ".join(shown) if shown else "no effect on the measurements"
            verb = "absorbed by" if shown else "it has"
            lines.append(f"{self.names[k]} is not identifiable ({verb} {absorbed})")
        if self.breaks_closure.size:
            lines.append(self._closure_line(max_terms))
        for k in self.splits_joint:
            lines.append(
                f"{self.names[k]} would split an emulated ball or universal joint (a "
                "translation between revolute axes that meet at one point; not fitted)"
            )
        return lines

    def _closure_line(self, max_joints: int) -> str:
        """One line for every parameter that breaks loop closure, grouped by loop.

        :func:`~pincal.sensitivity.closure_line`; by joint when the loops are not known.
        """
        members = [self.names[k] for k in self.breaks_closure]
        loops = tuple((label, tuple(self.names[k] for k in on)) for label, on in self.loops)
        return closure_line(members, loops, max_joints)

    def _in_units(self, k: int, terms: list[tuple[int, float]], max_terms: int) -> str:
        """The sentence of parameter k, its combination in mm / mrad (else SI) amounts."""

        def shown(i: int) -> tuple[float, str]:
            unit = self.units[i]
            return (1e-3, {"m": "mm", "rad": "mrad"}[unit]) if unit in ("m", "rad") else (1.0, unit)

        step, unit = shown(k)
        parts = []
        for i, b in terms[:max_terms]:
            scale, u = shown(i)
            parts.append(f"{b * step / scale:+.3g} {u} of {self.names[i]}")
        if len(terms) > max_terms:
            parts.append(f"… ({len(terms) - max_terms} more)")
        verb = "does" if len(parts) == 1 else "do"
        return (f"{self.names[k]} is not identifiable: 1 {unit} of it moves the measurements "
                f"as {', '.join(parts)} {verb}")  # fmt: skip

    def summary(self) -> str:
        """A headline (rank and counts) and one line per unidentifiable parameter."""
        head = f"{self.rank} of {len(self.names)} parameters identifiable"
        if self.breaks_closure.size:
            head += f"; {self.breaks_closure.size} break loop closure"
        if self.splits_joint.size:
            head += f"; {self.splits_joint.size} would split an emulated joint"
        return "\n".join([head, *self.describe()])


def analyse_jacobian(
    J: np.ndarray,
    names: tuple[str, ...],
    rtol: float = RANK_RTOL,
    breaks_closure: np.ndarray | None = None,
    splits_joint: np.ndarray | None = None,
    units: tuple[str, ...] = (),
    loops: tuple[ClosureLoop, ...] = (),
) -> Identifiability:
    """Identifiability of the parameters whose identification Jacobian is ``J`` (N, n).

    Columns are scaled to unit norm first, so mixed units (m, rad) do not bias the
    rank; a column below 1e-12 of the largest column norm counts as zero (the
    parameter has no effect). The rank is the count of singular values above
    ``rtol``·σ1 and the base has exactly that many parameters.

    Args:
        J: identification Jacobian (N, n).
        names: the n parameter names.
        rtol: relative rank threshold (default :data:`pincal.sensitivity._rank.RANK_RTOL`).
        breaks_closure: indices (or an (n,) boolean mask) of parameters that break loop
            closure; they are reported apart and left out of the rank.
        splits_joint: indices (or an (n,) boolean mask) of translations inside emulated
            ball or universal joints; reported apart and left out of the rank likewise.
        units: the n parameters' SI units, for :meth:`Identifiability.describe` (or ()).
        loops: the loop closures and the parameters on each (:func:`closure_loops`),
            for :meth:`Identifiability.describe` (or ()).

    Raises:
        PincalError: J is not 2-D with one column per name, or contains NaN/inf.
    """
    J = np.asarray(J, dtype=float)
    if J.ndim != 2 or J.shape[1] != len(names):
        raise PincalError(
            f"J must have shape (rows, {len(names)}) for {len(names)} parameter names; "
            f"got {J.shape}"
        )
    if not np.all(np.isfinite(J)):
        raise PincalError("J contains NaN or infinite entries; check the poses and parameters")
    n = J.shape[1]
    breaking, splitting = (
        _mask(breaks_closure, n),
        _mask(splits_joint, n) & ~_mask(breaks_closure, n),
    )
    Js, scale = unit_columns(J)  # the one scaling of jacobian_rank
    safe = np.where(scale > 0, scale, 1.0)
    closable = np.flatnonzero(~breaking & ~splitting)
    Jc = Js[:, closable]
    sv = np.linalg.svd(Jc, compute_uv=False) if Jc.size else np.zeros(0)
    rank = numerical_rank(sv, rtol)
    # in set order only columns independent at BASE_RTOL (a column barely outside the
    # span of those before it makes a base conditioned like its part: the 2-RSU ankle's
    # full set took a rod-end offset at 1e-6 of σ1, whose Gauss–Newton steps went 48 mm
    # off); the rank's other members are pivoted in
    threshold = max(rtol, BASE_RTOL) * float(sv[0]) if sv.size else 0.0
    base = closable[greedy_base(Jc, rank, threshold)] if rank else _empty()
    others = np.array([k for k in closable if k not in set(base.tolist())], dtype=int)
    combos: dict[int, dict[int, float]] = {}
    if base.size and others.size:
        beta_s = RangeSolver.factor(Js[:, base], rtol=0.0).solve(Js[:, others])  # scaled
        for col, k in enumerate(others):
            combos[int(k)] = {
                int(base[i]): float(beta_s[i, col] * safe[k] / safe[base[i]])  # parameter units
                for i in range(base.size)
                if abs(beta_s[i, col]) > _COMBINATION_CUTOFF
            }
    return Identifiability(
        tuple(names),
        rank,
        base,
        others,
        combos,
        sv,
        scale[:n],
        np.flatnonzero(breaking),
        np.flatnonzero(splitting),
        tuple(units) if len(units) == n else (),
        tuple(loops) if breaking.any() else (),
    )


def _mask(indices: np.ndarray | None, n: int) -> np.ndarray:
    """(n,) boolean mask from indices or a mask (None: all False)."""
    out = np.zeros(n, dtype=bool)
    if indices is not None:
        b = np.asarray(indices)
        if b.dtype == bool and b.shape == (n,):
            out = b.copy()
        else:
            out[b.astype(int).reshape(-1)] = True
    return out


def identifiability(
    mech: Mechanism,
    params: ParameterSet,
    q_act_rows: np.ndarray | None = None,
    n_poses: int = 60,
    rng: np.random.Generator | None = None,
    rtol: float = RANK_RTOL,
    conditions: Mapping[str, np.ndarray | None] | None = None,
) -> Identifiability:
    """Analyse which parameters the measured components can identify.

    Parameters that break loop closure (over-constrained loops, see
    :func:`pincal.sensitivity.closure_breaking`) at any of the poses are reported in
    ``breaks_closure``, translations inside emulated ball or universal joints
    (:func:`pincal.model.degenerate_translations`) in ``splits_joint``; neither is
    counted as identifiable.

    Args:
        mech: nominal mechanism.
        params: parameter set to analyse.
        q_act_rows: (m, n_act) poses [m, rad]; by default ``n_poses`` random workspace poses.
        n_poses: number of random workspace poses sampled when ``q_act_rows`` is None.
        rng: random generator for the default poses.
        rtol: relative rank threshold.
        conditions: per-pose conditions of ``q_act_rows`` that joint terms need (e.g.
            ``{"temperature": (m,) °C}`` for a thermal term; ``Measurements.conditions``).

    Raises:
        InputLimitError: more parameters than ``Limits.parameters`` of the limits in force
            (:func:`pincal.model.active_limits`; ``PINCAL_MAX_PARAMETERS`` on the command line).
    """
    limits = active_limits()
    limits.check(
        f"parameters in set {params.label!r} to analyse",
        len(params),
        limits.parameters,
        "PINCAL_MAX_PARAMETERS",
        f"model {mech.name!r}",
    )
    if q_act_rows is None:
        q_act_rows = sample_actuators(mech, n_poses, rng or np.random.default_rng(0))
    J, breaking = jacobian_and_closure_breaking(mech, params, q_act_rows, conditions=conditions)
    splitting = np.isin(params.names, degenerate_translations(mech))
    loops = closure_loops(mech, params) if np.any(breaking) else ()
    return analyse_jacobian(J, params.names, rtol, breaks_closure=breaking,
                            splits_joint=splitting, units=params.units, loops=loops)  # fmt: skip

"""Screens that keep only candidate poses a real machine can go to.

Applied to a :class:`~pincal.design._candidates.CandidateSet` before selection, in this
order, each counting what it removes from what the previous ones kept:

1. **joint-limit margin** — every actuator with finite limits keeps ``joint_margin`` of
   its range free at both ends (0.05: 5 % of the range);
2. **singularity margin** — σ_min of the dimensionless actuator → pose Jacobian
   G = ∂(measured components)/∂q_act (:func:`actuator_jacobians`, through the loop
   closure for a parallel machine) at least ``singular_margin`` times
   its median over the candidates (the workspace's typical value). Rows: position
   components divided by L, rotation components as they are; columns: revolute
   actuators as they are, prismatic ones times L; L [m] balances the two row blocks
   (RMS of the position rows / RMS of the rotation rows of G over the candidates, as
   :func:`~pincal.design._scaling.characteristic_length`). With position components
   only, or a measured point the actuators do not move, L = 1 m (σ_min is then relative anyway);
3. **self-collision** and 4. **obstacle collision** — the URDF collision geometry
   (:class:`~pincal.design._collisions.CollisionChecker`) at each pose's closed
   configuration; skipped, with a note, when the model has none;
5. **compensation** — a test given by the caller, run on the survivors only (the CLI
   compensates each target on a perturbed model: stage 6, which this stage may not import).

:func:`screen_candidates` returns the kept candidates with the counts added to their
``rejected`` reasons, so ``CandidateSet.summary()`` states them.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from pincal.design._candidates import CandidateSet
from pincal.design._collisions import Box, CollisionChecker
from pincal.errors import ConvergenceError, OptionValueError
from pincal.model import Mechanism, actuator_jacobians

__all__ = [
    "SCREENS",
    "ScreenReport",
    "ScreenSettings",
    "actuator_sigma_min",
    "scaled_actuator_jacobians",
    "screen_candidates",
]

_log = logging.getLogger(__name__)

#: screen names, in the order they are applied (the keys of ScreenReport.removed)
SCREENS = (
    "joint-limit margin",
    "singularity margin",
    "self-collision",
    "obstacle collision",
    "compensation",
)


@dataclass(frozen=True)
class ScreenSettings:
    """What the screens require of a candidate.

    Attributes:
        joint_margin: share of each finite actuator range kept free at both ends, [0, 0.5).
        singular_margin: least σ_min(G) relative to its median over the candidates
            (0: no singularity screen).
        collisions: screen self-collisions (and obstacles) with the collision geometry.
        obstacles: boxes of the surroundings (world frame).
    """

    joint_margin: float = 0.05
    singular_margin: float = 0.1
    collisions: bool = True
    obstacles: tuple[Box, ...] = ()

    def __post_init__(self) -> None:
        if not 0.0 <= self.joint_margin < 0.5:
            raise OptionValueError(
                f"joint margin {self.joint_margin:g} must be in [0, 0.5) (a share of each "
                "actuator range kept free at both ends, e.g. 0.05)"
            )
        if not 0.0 <= self.singular_margin < 1.0:
            raise OptionValueError(
                f"singularity margin {self.singular_margin:g} must be in [0, 1) (σ_min "
                "relative to its median over the candidates, e.g. 0.1)"
            )


@dataclass(frozen=True)
class ScreenReport:
    """What the screens did.

    Attributes:
        removed: candidates removed per screen (``SCREENS`` order; absent: not run).
        notes: screens skipped and why, pairs ignored, the σ_min reference.
        kept: (N,) bool over the screened candidate set.
    """

    removed: dict[str, int]
    notes: tuple[str, ...]
    kept: NDArray[np.bool_]

    def summary(self) -> str:
        """One line, e.g. ``"screens removed: 3 joint-limit margin, 0 singularity ..."``."""
        return "screens removed: " + ", ".join(f"{n} {k}" for k, n in self.removed.items())


def scaled_actuator_jacobians(
    mech: Mechanism, q_act: NDArray[np.float64], length: float | None = None
) -> tuple[NDArray[np.float64], NDArray[np.float64], float]:
    """The dimensionless actuator → measured-components Jacobians of the rows.

    Args:
        mech: the mechanism (its measured components are the rows of G).
        q_act: (N, n_act) actuator rows [m, rad].
        length: L [m] (None: balanced over these rows, see the module docstring).

    Returns:
        (G (N, k, n_act) scaled — NaN where the forward kinematics failed —, the row
        scale (k,): 1/L [1/m] on position rows and 1 on rotation rows, L [m]).
    """
    rows = np.atleast_2d(np.asarray(q_act, dtype=float))
    G = actuator_jacobians(mech, rows)
    is_pos = np.array([c in "xyz" for c in mech.measured_components])
    if length is None:
        ok = np.all(np.isfinite(G), axis=(1, 2))
        if is_pos.all() or not is_pos.any() or not ok.any():
            length = 1.0
        else:
            rms_r = float(np.sqrt(np.mean(G[ok][:, ~is_pos] ** 2)))
            rms_p = float(np.sqrt(np.mean(G[ok][:, is_pos] ** 2)))
            # a measured point the actuators do not move (rms_p = 0) has no length scale
            length = rms_p / rms_r if rms_r > 0 and rms_p > 0 else 1.0
    prismatic = np.array([mech.tree.joints[j].type == "prismatic" for j in mech.actuated])
    scale = np.where(is_pos, 1.0 / length, 1.0)
    G *= scale[None, :, None]
    G[:, :, prismatic] *= length
    return G, scale, float(length)


def actuator_sigma_min(
    mech: Mechanism, q_act: NDArray[np.float64], length: float | None = None
) -> tuple[NDArray[np.float64], float]:
    """σ_min of the dimensionless actuator → measured-components Jacobian per row.

    Args:
        mech: the mechanism (its measured components are the rows of G).
        q_act: (N, n_act) actuator rows [m, rad].
        length: L [m] (None: balanced over these rows, see the module docstring).

    Returns:
        (σ_min per row (N,) — NaN where the forward kinematics failed —, L [m]).
    """
    G, _, length = scaled_actuator_jacobians(mech, q_act, length)
    sigma = np.full(len(G), np.nan)
    for i, Gi in enumerate(G):
        if np.all(np.isfinite(Gi)):
            sigma[i] = np.linalg.svd(Gi, compute_uv=False)[-1]
    return sigma, length


def screen_candidates(
    mech: Mechanism,
    candidates: CandidateSet,
    settings: ScreenSettings | None = None,
    *,
    compensable: Callable[[CandidateSet], NDArray[np.bool_]] | None = None,
) -> tuple[CandidateSet, ScreenReport]:
    """The candidates that pass every screen, and what each screen removed.

    Args:
        mech: the nominal mechanism the candidates were made with.
        candidates: feasible candidates (N).
        settings: the margins (default :class:`ScreenSettings`).
        compensable: called with the candidates the other screens kept (M), returns
            (M,) whether each survives compensation (None: not screened).

    Returns:
        (kept candidates — ``rejected`` extended by the screens' counts —, report).
    """
    settings = settings or ScreenSettings()
    n = len(candidates)
    keep = np.ones(n, dtype=bool)
    removed: dict[str, int] = {}
    notes: list[str] = []

    def apply(name: str, ok: NDArray[np.bool_]) -> None:
        removed[name] = int(np.sum(keep & ~ok))
        keep[:] &= ok

    lo, hi = np.asarray(mech.actuator_limits, dtype=float).T
    finite = np.isfinite(lo) & np.isfinite(hi)
    pad = np.where(finite, settings.joint_margin * (hi - lo), 0.0)
    q_act = candidates.q_act
    inside = (q_act >= np.where(finite, lo + pad, -np.inf)) & (
        q_act <= np.where(finite, hi - pad, np.inf)
    )
    apply(SCREENS[0], np.all(inside, axis=1))
    if settings.singular_margin > 0 and n:
        sigma, length = actuator_sigma_min(mech, q_act)
        ref = float(np.nanmedian(sigma)) if np.isfinite(sigma).any() else 0.0
        bound = settings.singular_margin * ref
        apply(SCREENS[1], np.isfinite(sigma) & (sigma >= bound))
        notes.append(
            f"singularity margin: σ_min ≥ {settings.singular_margin:g} × median "
            f"{ref:.4g} (L = {length * 1e3:.4g} mm)"
        )
    if settings.collisions:
        checker = CollisionChecker(mech, settings.obstacles)
        if not checker.available:
            notes.append(f"collisions not screened: {checker.note}")
        else:
            self_hit = np.zeros(n, dtype=bool)
            obstacle_hit = np.zeros(n, dtype=bool)
            q = mech.q_home
            for i in np.flatnonzero(keep):
                try:
                    q = mech.configuration(q_act[i], q)
                except ConvergenceError:
                    q = mech.q_home
                    self_hit[i] = True  # cannot be checked: not kept
                    continue
                self_hit[i], obstacle_hit[i] = checker.collisions(q)
            apply(SCREENS[2], ~self_hit)
            if settings.obstacles:
                apply(SCREENS[3], ~obstacle_hit)
            own, outer = checker.ignored_at_home
            notes.append(
                f"collisions: {checker.n_pairs} geometry pairs checked"
                + (f"; {own} self pairs in contact at home ignored" if own else "")
                + (f"; {outer} obstacle pairs in contact at home ignored" if outer else "")
            )
    if compensable is not None:
        survivors = np.flatnonzero(keep)
        got = np.asarray(compensable(candidates.subset(survivors)), dtype=bool)
        if got.shape != survivors.shape:
            raise OptionValueError(
                f"compensable returned shape {got.shape}; expected {survivors.shape}"
            )
        ok = np.ones(n, dtype=bool)
        ok[survivors] = got
        apply(SCREENS[4], ok)
    idx = np.flatnonzero(keep)
    kept = candidates.subset(idx)
    kept.rejected.update({k: v for k, v in removed.items()})
    report = ScreenReport(removed, tuple(notes), keep.copy())
    _log.info("%s", report.summary())
    return kept, report

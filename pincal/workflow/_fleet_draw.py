"""A simulated production fleet: line offset, unit-to-unit spread, planted faulty units.

Every unit of a line shares the line's systematic offset of the nominal geometry and
differs from it by an independent Gaussian production spread per parameter (1σ
``spread_mm`` for lengths, ``spread_mrad`` for angles). A planted out-of-family unit
carries a faulty part besides: every parameter of one joint placement (one name
prefix, e.g. ``leg3_u1.*``) moved by ±``shift`` of its production σ — what a
mis-machined or mis-assembled part does. Draws come from ``SeedSequence(seed)``: child
0 for the fleet (offset, spread, planted units), child ``i + 1`` for unit ``i``'s poses
and noise, so a unit's data do not depend on the fleet's size or order of work.

Recalibrated units are measured in a second session (new poses and noise); a drifted
one has, in that session, one joint placement's parameters moved as a faulty part's
are (a part that wore, slipped or was replaced). Their draws come from
``SeedSequence([seed, 2])`` (child 0: which units, which part; child ``i + 1``: unit
``i``'s second session), so a fleet without recalibrations is drawn as before.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pincal.errors import ParameterError
from pincal.measure import Measurements, NoiseModel, simulate_measurements
from pincal.model import Mechanism, ParameterSet, sample_actuators

__all__ = ["FleetDraw", "draw_fleet", "simulate_unit"]


@dataclass(frozen=True)
class FleetDraw:
    """The true geometry of a simulated fleet.

    Attributes:
        names: the n parameter names; units: their units (``"m"``/``"rad"``).
        offset: (n,) the line's systematic offset shared by every unit [m, rad].
        spread: (n,) 1σ production spread per parameter [m, rad].
        values: (N, n) every unit's true parameter errors [m, rad].
        planted: unit index → {parameter name: its faulty-part shift [m, rad]}.
        seeds: (N,) each unit's ``SeedSequence`` child (its poses and noise).
        second: unit index → its true parameter errors in the second session [m, rad].
        drifts: unit index → {parameter name: its drift between the sessions [m, rad]}.
        second_seeds: (N,) each unit's second-session ``SeedSequence`` child.
    """

    names: tuple[str, ...]
    units: tuple[str, ...]
    offset: np.ndarray
    spread: np.ndarray
    values: np.ndarray
    planted: dict[int, dict[str, float]]
    seeds: tuple[np.random.SeedSequence, ...]
    second: dict[int, np.ndarray]
    drifts: dict[int, dict[str, float]]
    second_seeds: tuple[np.random.SeedSequence, ...]


def draw_fleet(
    params: ParameterSet,
    n_units: int,
    seed: int = 0,
    *,
    spread_mm: float = 0.1,
    spread_mrad: float = 0.5,
    offset_mm: float = 0.5,
    offset_mrad: float = 2.0,
    planted: int | None = None,
    shift: float = 8.0,
    free: np.ndarray | None = None,
    recalibrated: int = 0,
    drifted: int = 0,
) -> FleetDraw:
    """Draw a fleet's true parameter errors (see the module doc).

    Args:
        params: the parameter set (names, units ``"m"``/``"rad"``).
        n_units: N ≥ 2 units.
        seed: the fleet's seed.
        spread_mm: 1σ production spread of lengths [mm].
        spread_mrad: 1σ production spread of angles [mrad].
        offset_mm: bound of the uniform line offset of lengths [mm].
        offset_mrad: bound of the uniform line offset of angles [mrad].
        planted: out-of-family units (default max(1, round(0.03 N))), < N / 2.
        shift: a faulty part's shift in production σ (±, random sign per parameter).
        free: (n,) 1 where a built machine can have an error, 0 where not (a
            translation inside an emulated joint, a loop-breaking offset:
            :func:`pincal.workflow.buildable_mask`); None: every parameter.
        recalibrated: units measured in a second session (0 ≤ R ≤ N).
        drifted: of those, units whose second session has a part moved by ``shift``
            (0 ≤ D ≤ R).

    Returns:
        The :class:`FleetDraw`.

    Raises:
        ParameterError: N < 2, planted units not below half the fleet, a negative size,
            more recalibrated units than units or drifted than recalibrated.
    """
    n_units = int(n_units)
    if n_units < 2:
        raise ParameterError(f"a fleet needs at least 2 units, got {n_units}")
    k = max(1, round(0.03 * n_units)) if planted is None else int(planted)
    if not 0 <= k < n_units / 2:
        raise ParameterError(
            f"planted out-of-family units must be 0 ≤ K < N/2 (the family is the majority), "
            f"got {k} of {n_units}"
        )
    if min(spread_mm, spread_mrad, offset_mm, offset_mrad, shift) < 0:
        raise ParameterError("spread, offset and shift are sizes ≥ 0")
    if not 0 <= drifted <= recalibrated <= n_units:
        raise ParameterError(
            f"drifted ≤ recalibrated ≤ units, each ≥ 0: got {drifted} drifted of {recalibrated} "
            f"recalibrated of {n_units} units"
        )
    children = np.random.SeedSequence(seed).spawn(n_units + 1)
    rng = np.random.default_rng(children[0])
    metric = np.array([u == "m" for u in params.units])
    free = np.ones(len(params)) if free is None else np.asarray(free, dtype=float)
    spread = np.where(metric, spread_mm, spread_mrad) * 1e-3 * free
    bound = np.where(metric, offset_mm, offset_mrad) * 1e-3 * free
    offset = rng.uniform(-bound, bound)
    values = offset + spread * rng.standard_normal((n_units, len(params)))
    groups: dict[str, list[int]] = {}
    for j, name in enumerate(params.names):
        if free[j]:
            groups.setdefault(name.rsplit(".", 1)[0], []).append(j)
    prefixes = sorted(groups)

    def part(rng: np.random.Generator) -> tuple[list[int], np.ndarray]:
        """One joint placement's columns and their ±shift production σ."""
        cols = groups[prefixes[int(rng.integers(len(prefixes)))]]
        return cols, rng.choice([-1.0, 1.0], size=len(cols)) * shift * spread[cols]

    faulty: dict[int, dict[str, float]] = {}
    for unit in sorted(int(u) for u in rng.choice(n_units, size=k, replace=False)):
        cols, moved = part(rng)
        values[unit, cols] += moved
        faulty[unit] = {params.names[j]: float(m) for j, m in zip(cols, moved, strict=True)}
    later = np.random.SeedSequence([seed, 2]).spawn(n_units + 1)
    rng2 = np.random.default_rng(later[0])
    chosen = [int(u) for u in rng2.choice(n_units, size=recalibrated, replace=False)]
    second = {u: values[u].copy() for u in chosen}
    drifts: dict[int, dict[str, float]] = {}
    for unit in sorted(chosen[:drifted]):
        cols, moved = part(rng2)
        second[unit][cols] += moved
        drifts[unit] = {params.names[j]: float(m) for j, m in zip(cols, moved, strict=True)}
    return FleetDraw(
        tuple(params.names),
        tuple(params.units),
        offset,
        spread,
        values,
        faulty,
        tuple(children[1:]),
        dict(sorted(second.items())),
        drifts,
        tuple(later[1:]),
    )


def simulate_unit(
    nominal: Mechanism,
    params: ParameterSet,
    values: np.ndarray,
    n_poses: int,
    noise: NoiseModel,
    seed: np.random.SeedSequence,
) -> Measurements:
    """Measure one unit at random poses of its workspace.

    Args:
        nominal: the nominal mechanism.
        params: the parameter set ``values`` belong to.
        values: (n,) the unit's true parameter errors [m, rad].
        n_poses: poses drawn (those the unit cannot close are left out).
        noise: the instrument's noise.
        seed: the unit's ``SeedSequence`` child (poses, then noise).

    Returns:
        The unit's measurements (≤ n_poses poses) [SI].
    """
    rng = np.random.default_rng(seed)
    actual = params.apply(nominal, np.asarray(values, dtype=float))
    q_act = sample_actuators(nominal, int(n_poses), rng)
    q_act = q_act[actual.closable_batch(q_act)]
    return simulate_measurements(actual, q_act, noise, rng)

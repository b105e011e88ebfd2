"""Candidate specs: ``auto``, ``grid:LEVELS``, ``random:COUNT``, ``oa:LEVELS``.

The default spec, ``auto``, is the joint grid of 4 levels (3 where 4 would pass
:data:`AUTO_ROWS` rows: seven actuators), topped up with ``random:500`` poses drawn in
the workspace when the grid leaves fewer than :data:`AUTO_LEAST` usable poses, or poses
that identify fewer parameters than the whole grid (a pose workspace thin in the
actuators' space: the wedge mechanism's grid keeps 4 of 64; the caller's screens
removing most of an arm's grid: a Panda whose collision capsules touch at most folded
poses kept 81 of 2 187, a Baxter arm beside its body 147 of rank 30 < 34), and replaced
by them when even 3 levels pass :data:`AUTO_ROWS` or the grid costs more rows than
allowed (many actuators).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

import numpy as np

from pincal.design._candidate_sources import (
    grid_candidates,
    orthogonal_candidates,
    random_candidates,
)
from pincal.design._candidates import (
    MAX_CANDIDATE_BYTES,
    MAX_CANDIDATES,
    CandidateSet,
    Progress,
)
from pincal.errors import InputLimitError, OptionValueError, PincalError, clip
from pincal.model import Mechanism, ParameterSet
from pincal.sensitivity import jacobian_rank

__all__ = ["AUTO_LEAST", "AUTO_ROWS", "candidate_set", "parse_candidate_spec"]

#: ``auto``: the grid's levels, the feasible candidates below which random poses are
#: added, and how many
AUTO_GRID, AUTO_LEAST, AUTO_RANDOM = 4, 100, 500
#: ``auto``: most grid rows (a 7-joint arm's 4⁷ rows: 52 s CPU for a Panda design; 3⁷:
#: 6.8 s, O1 within 4 %)
AUTO_ROWS = 4096


def parse_candidate_spec(spec: str) -> tuple[str, int]:
    """``"grid:4"`` → ("grid", 4); kinds: grid (levels), random (count), oa (levels), auto."""
    if spec == "auto":
        return "auto", AUTO_GRID
    kind, _, arg = spec.partition(":")
    defaults = {"grid": 4, "random": 500, "oa": 5}
    if kind not in defaults:
        raise OptionValueError(
            f"{clip(spec)} is not a candidate spec; use auto, grid:LEVELS, random:COUNT or "
            "oa:LEVELS"
        )
    least = {"grid": 2, "random": 1, "oa": 2}[kind]
    try:
        number = float(arg) if arg else defaults[kind]  # "1e4" is an integer too
    except ValueError:
        number = math.nan
    if not (math.isfinite(number) and number == int(number) and number >= least):
        raise OptionValueError(
            f"{clip(spec)}: {clip(arg)} is not an integer >= {least}; candidate specs are "
            f"grid:LEVELS (>= 2), random:COUNT (>= 1) or oa:LEVELS (>= 2)"
        )
    return kind, int(number)


def candidate_set(
    mech: Mechanism,
    params: ParameterSet,
    spec: str = "grid:4",
    rng: np.random.Generator | int | None = None,
    *,
    progress: Progress | None = None,
    max_candidates: int | None = MAX_CANDIDATES,
    max_bytes: int | None = MAX_CANDIDATE_BYTES,
    n_jobs: int = 1,
    scheduler: str | None = None,
    joint_margin: float = 0.0,
    usable: Callable[[CandidateSet], CandidateSet] | None = None,
) -> CandidateSet:
    """Candidates from a spec string: ``auto``, ``grid:LEVELS``, ``random:COUNT`` or ``oa:LEVELS``.

    The cost (rows, memory) is estimated before any work and refused past
    ``max_candidates`` rows or ``max_bytes`` (None: no bound). ``n_jobs``, ``scheduler``:
    local processes or a Dask scheduler evaluating the rows (see
    :func:`evaluate_candidates`); the candidates do not depend on them. ``joint_margin``:
    the joint-limit screen's margin, which a grid's default ranges leave out.
    ``usable``: the candidates the caller's screens keep of some (``auto`` tops its grid
    up when they keep fewer than :data:`AUTO_LEAST`, or poses of lower rank than the
    whole grid's; None: every feasible one).

    Raises:
        OptionValueError: the spec is malformed (kind, or a number that is not an integer
            of the kind's minimum).
        InputLimitError: the estimate passes a bound, naming the estimate and the bound.
    """
    kind, value = parse_candidate_spec(spec)
    lim, mem = max_candidates, max_bytes
    if kind == "auto":
        result = _auto_candidates(mech, params, rng, progress, lim, mem, n_jobs, scheduler,
                                  joint_margin, usable or (lambda c: c))  # fmt: skip
    elif kind == "grid":
        result = grid_candidates(
            mech, params, value, progress=progress, max_candidates=lim, max_bytes=mem,
            n_jobs=n_jobs, scheduler=scheduler, joint_margin=joint_margin,
        )  # fmt: skip
    elif kind == "random":
        result = random_candidates(
            mech, params, value, rng, progress=progress, max_candidates=lim, max_bytes=mem,
            n_jobs=n_jobs, scheduler=scheduler,
        )  # fmt: skip
    else:
        result = orthogonal_candidates(
            mech, params, value, progress=progress, max_candidates=lim, max_bytes=mem,
            n_jobs=n_jobs, scheduler=scheduler,
        )  # fmt: skip
    if len(result) == 0:
        raise PincalError(f"no feasible candidate poses from {spec!r}: {result.summary()}")
    return result


def _auto_candidates(
    mech: Mechanism,
    params: ParameterSet,
    rng: np.random.Generator | int | None,
    progress: Progress | None,
    max_candidates: int | None,
    max_bytes: int | None,
    n_jobs: int,
    scheduler: str | None,
    joint_margin: float,
    usable: Callable[[CandidateSet], CandidateSet],
) -> CandidateSet:
    """``auto`` (module doc): the grid, with random workspace poses when it keeps few."""
    grid, n_act = None, len(mech.actuated)
    levels = AUTO_GRID if AUTO_GRID**n_act <= AUTO_ROWS else AUTO_GRID - 1
    why = f"grid:{levels} would be {levels**n_act} rows"
    try:
        if levels**n_act <= AUTO_ROWS:
            grid = grid_candidates(mech, params, levels, progress=progress,
                                   max_candidates=max_candidates, max_bytes=max_bytes,
                                   n_jobs=n_jobs, scheduler=scheduler,
                                   joint_margin=joint_margin)  # fmt: skip
    except InputLimitError:  # the grid's own bounds refuse it
        pass
    if grid is not None:
        kept = usable(grid)
        n = len(params)
        rank = jacobian_rank(kept.jacobians.reshape(-1, n)) if len(kept) else 0
        whole = rank if len(kept) == len(grid) else jacobian_rank(grid.jacobians.reshape(-1, n))
        if len(kept) >= AUTO_LEAST and rank == whole:
            return grid
        why = f"grid:{levels} kept {len(kept)} of {grid.tried}"
        why += " after the screens" if len(kept) < len(grid) else ""
        why += f", of rank {rank} < {whole}" if rank < whole else ""
    extra = random_candidates(mech, params, AUTO_RANDOM, rng, progress=progress,
                              max_candidates=max_candidates, max_bytes=max_bytes,
                              n_jobs=n_jobs, scheduler=scheduler)  # fmt: skip
    source = f"auto: {why}, random:{AUTO_RANDOM} added"
    if grid is None:
        return dataclasses.replace(extra, source=source)
    return grid.joined(extra, source)

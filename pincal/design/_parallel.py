"""Candidate evaluation in parallel processes (joblib).

Pinocchio models (and so mechanisms) do not pickle: a worker receives the mechanism's
recipe — its URDF text, typed sidecar, name, source path, measured frame, solver
options and assembled home configuration — and rebuilds the mechanism once per
process (cached by the recipe's digest). The batched forward kinematics and the
batched Jacobian blocks are computed row by row independently, so splitting the rows
into chunks gives the same numbers as one call. Workers use one BLAS thread.

Chunks are mapped through :class:`pincal.executor.Executor`: local processes (joblib's
loky) by default, a Dask cluster when a scheduler is given (``local:N`` or
``tcp://host:port``).
"""

from __future__ import annotations

import hashlib
import itertools
import pickle
from typing import Any

import numpy as np

from pincal.errors import PincalError
from pincal.executor import Executor
from pincal.model import Mechanism, ParameterSet, active_limits
from pincal.sensitivity import sensitivities_batch

__all__ = ["check_n_jobs", "parallel_rows"]

#: rebuilt mechanisms of this process, by recipe digest (a worker keeps one or two)
_REBUILT: dict[str, Mechanism] = {}


def check_n_jobs(n_jobs: int) -> int:
    """``n_jobs`` as given when it is a positive integer or -1 (every CPU).

    Raises:
        PincalError: anything else.
    """
    if isinstance(n_jobs, bool) or not isinstance(n_jobs, int) or (n_jobs < 1 and n_jobs != -1):
        raise PincalError(f"n_jobs must be a positive integer or -1 (every CPU), got {n_jobs!r}")
    return n_jobs


def _recipe(mech: Mechanism) -> tuple[str, bytes]:
    """(digest, pickled limits in force and constructor arguments): ``mech`` elsewhere."""
    args = (
        active_limits(),
        mech.urdf_xml,
        mech.sidecar,
        mech.name,
        mech.source,
        mech.measured_frame,
        mech.options,
        np.asarray(mech.q_home, dtype=float),
    )
    blob = pickle.dumps(args, protocol=pickle.HIGHEST_PROTOCOL)
    return hashlib.sha256(blob).hexdigest(), blob


def _rebuild(recipe: tuple[str, bytes]) -> Mechanism:
    digest, blob = recipe
    if digest not in _REBUILT:
        limits, urdf, sidecar, name, source, frame, options, q_home = pickle.loads(blob)
        if len(_REBUILT) > 2:
            _REBUILT.clear()
        with limits.applied():  # the parent's limits, not the worker's defaults
            _REBUILT[digest] = Mechanism(
                urdf,
                sidecar,
                name=name,
                source=source,
                measured_frame=frame,
                q_guess=q_home,
                options=options,
            )
    return _REBUILT[digest]


def _fk_chunk(item: tuple[tuple[str, bytes], np.ndarray]) -> tuple[Any, ...]:
    """Batched forward kinematics of a chunk ``(recipe, rows)``.

    Returns (Q, solved, R, p), or (Q, solved, None, None) when the batched solve does
    not apply. Executor items run on one BLAS thread.
    """
    recipe, rows = item
    mech = _rebuild(recipe)
    Q, solved, bk = mech.try_configurations_batch(rows)
    if bk is None:
        return Q, solved, None, None
    R, p = mech.batch_model.frame_placement(bk, mech.frame_id(mech.measured_frame))
    return Q, solved, R, p


def _sensitivity_chunk(
    item: tuple[tuple[str, bytes], ParameterSet, np.ndarray],
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Positions, rotations and Jacobian blocks of a chunk ``(recipe, params, Q)``."""
    recipe, params, Q = item
    sens = sensitivities_batch(_rebuild(recipe), params, Q)
    return sens.positions, sens.rotations, sens.jacobian


def _chunks(n: int, parts: int) -> list[slice]:
    bounds = np.linspace(0, n, parts + 1).round().astype(int)
    return [slice(int(a), int(b)) for a, b in itertools.pairwise(bounds) if b > a]


def parallel_rows(
    kind: str,
    mech: Mechanism,
    rows: np.ndarray,
    n_jobs: int,
    params: ParameterSet | None = None,
    scheduler: str | None = None,
) -> tuple[Any, ...]:
    """Batched FK (``kind="fk"``) or sensitivities (``"sensitivity"``) of rows, in chunks.

    Args:
        kind: ``"fk"``: rows are actuator rows (N, n_act), returns ``(Q, solved, R, p)``
            like :meth:`Mechanism.try_configurations_batch` followed by the measured
            frame's placements (R, p None when the batched solve does not apply);
            ``"sensitivity"``: rows are configurations (N, nq), returns ``(positions,
            rotations, jacobian)`` like :func:`sensitivities_batch`.
        mech: the mechanism (rebuilt in each worker).
        rows: (N, ·) rows, split into one contiguous chunk per worker.
        n_jobs: local worker processes without a scheduler (-1 = every CPU).
        params: parameter set (``"sensitivity"`` only).
        scheduler: a Dask scheduler (``local:N``, ``tcp://host:port``) or None.

    Returns:
        The chunks' results concatenated in row order.

    Raises:
        The first failing chunk's error.
    """
    recipe = _recipe(mech)
    with Executor(scheduler, n_jobs) as ex:
        parts = _chunks(rows.shape[0], max(1, min(ex.workers, rows.shape[0])))
        if kind == "fk":
            out = ex.map(_fk_chunk, [(recipe, rows[s]) for s in parts]).values()
        else:
            items = [(recipe, params, rows[s]) for s in parts]
            out = ex.map(_sensitivity_chunk, items).values()
    if kind == "fk" and any(o[2] is None for o in out):
        return np.concatenate([o[0] for o in out]), np.concatenate([o[1] for o in out]), None, None
    return tuple(np.concatenate([o[k] for o in out]) for k in range(len(out[0])))

"""Candidate evaluation in parallel processes (joblib).

Pinocchio models (and so mechanisms) do not pickle: a worker receives the mechanism's
recipe — its URDF text, typed sidecar, name, source path, measured frame, solver
options and assembled home configuration — and rebuilds the mechanism once per
process (cached by the recipe's digest). The batched forward kinematics and the
batched Jacobian blocks are computed row by row independently, so splitting the rows
into chunks gives the same numbers as one call. Workers use one BLAS thread.

Parallel runs use joblib's default process backend (loky); to run on a Dask cluster,
select joblib's Dask backend around the call (``joblib.parallel_config(backend="dask")``).
"""

from __future__ import annotations

import hashlib
import itertools
import pickle
from typing import Any

import numpy as np

from pincal.errors import PincalError
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


def _fk_chunk(recipe: tuple[str, bytes], rows: np.ndarray) -> tuple[Any, ...]:
    """Batched forward kinematics of a chunk: (Q, solved, R, p) or (Q, solved, None, None)."""
    from threadpoolctl import threadpool_limits

    with threadpool_limits(1):
        mech = _rebuild(recipe)
        Q, solved, bk = mech.try_configurations_batch(rows)
        if bk is None:
            return Q, solved, None, None
        R, p = mech.batch_model.frame_placement(bk, mech.frame_id(mech.measured_frame))
        return Q, solved, R, p


def _sensitivity_chunk(
    recipe: tuple[str, bytes], params: ParameterSet, Q: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Measured-frame positions, rotations and Jacobian blocks of a chunk of configurations."""
    from threadpoolctl import threadpool_limits


    with threadpool_limits(1):
        sens = sensitivities_batch(_rebuild(recipe), params, Q)
        return sens.positions, sens.rotations, sens.jacobian


def _chunks(n: int, parts: int) -> list[slice]:
    bounds = np.linspace(0, n, parts + 1).round().astype(int)
    return [slice(int(a), int(b)) for a, b in itertools.pairwise(bounds) if b > a]


def parallel_rows(
    kind: str, mech: Mechanism, rows: np.ndarray, n_jobs: int, params: ParameterSet | None = None
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
        n_jobs: worker processes (joblib; -1 = every CPU).
        params: parameter set (``"sensitivity"`` only).

    Returns:
        The chunks' results concatenated in row order.
    """
    from joblib import Parallel, cpu_count, delayed

    workers = cpu_count() if n_jobs == -1 else n_jobs
    parts = _chunks(rows.shape[0], max(1, min(workers, rows.shape[0])))
    recipe = _recipe(mech)
    if kind == "fk":
        out = Parallel(n_jobs=n_jobs)(delayed(_fk_chunk)(recipe, rows[s]) for s in parts)
    else:
        out = Parallel(n_jobs=n_jobs)(
            delayed(_sensitivity_chunk)(recipe, params, rows[s]) for s in parts
        )
    if kind == "fk" and any(o[2] is None for o in out):
        return np.concatenate([o[0] for o in out]), np.concatenate([o[1] for o in out]), None, None
    return tuple(np.concatenate([o[k] for o in out]) for k in range(len(out[0])))

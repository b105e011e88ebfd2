"""Monte-Carlo identification studies, optionally in parallel processes (joblib).

Each run simulates measurements of the mechanism with known parameter errors and
noise, then identifies the parameters. Runs are independent: run k draws its noise
from child k of ``np.random.SeedSequence(seed)``, so the numbers do not depend on
``n_jobs`` or on the order in which workers finish.

Pinocchio models (and so mechanisms) do not pickle: workers receive the model's name
or file path and rebuild the mechanism once per process. Every run uses one BLAS
thread (``threadpool_limits(1)``): the dense solves are small, and threaded BLAS on
a busy machine is slower.

Runs go through :class:`pincal.executor.Executor`: local processes by default (joblib's
loky backend), a Dask cluster with ``scheduler="local:N"`` or ``"tcp://host:8786"``
(the optional ``pincal[dask]`` extra); the numbers are the same on every backend::

    study = monte_carlo("stewart_6ups", "stewart42", rows, errors, noise, runs=200,
                        scheduler="tcp://scheduler:8786")
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from pincal.errors import ParameterError, ShapeError
from pincal.executor import Executor
from pincal.identification import identify
from pincal.measure import NoiseModel, simulate_measurements
from pincal.model import Mechanism, ParameterSet, load_mechanism
from pincal.sensitivity import parameters

__all__ = ["MonteCarloStudy", "monte_carlo"]


@dataclass(frozen=True)
class MonteCarloStudy:
    """Identified values of repeated simulated calibrations.

    Attributes:
        names: the n parameter names.
        true_values: (n,) the simulated parameter errors [m, rad].
        values: (runs, n) identified values [m, rad].
        success: (runs,) whether each identification converged.
        seed: the study seed (run k uses child k of ``SeedSequence(seed)``).
    """

    names: tuple[str, ...]
    true_values: np.ndarray
    values: np.ndarray
    success: np.ndarray
    seed: int

    @property
    def errors(self) -> np.ndarray:
        """(runs, n) identified minus true values [m, rad]."""
        return self.values - self.true_values


@lru_cache(maxsize=4)
def _setup(model: str, preset: str) -> tuple[Mechanism, ParameterSet]:
    """The mechanism and parameter set, built once per process."""
    mech = load_mechanism(model)
    return mech, parameters(mech, preset)


def one_run(args: tuple, seed: np.random.SeedSequence) -> tuple[np.ndarray, bool]:
    """One simulate-and-identify run (an executor item; workers import it).

    Args:
        args: ``(model, preset, rows, true_values, noise, method)`` as for
            :func:`monte_carlo` (rows (m, n_act), true_values (n,) [m, rad]).
        seed: the run's ``SeedSequence`` child (its measurement noise).

    Returns:
        ((n,) identified values [m, rad], converged).
    """
    model, preset, rows, true_values, noise, method = args
    with threadpool_limits(1):
        mech, params = _setup(model, preset)
        actual = _actual(mech, params, true_values.tobytes())
        meas = simulate_measurements(actual, rows, noise, np.random.default_rng(seed))
        result = identify(mech, params, meas, method)
    return np.asarray(result.full_values, dtype=float), bool(result.success)


_ACTUAL: dict[tuple[int, bytes], Mechanism] = {}


def _actual(mech: Mechanism, params: ParameterSet, key: bytes) -> Mechanism:
    """The mechanism with the true errors applied (cached per process)."""
    k = (id(mech), key)
    if k not in _ACTUAL:
        _ACTUAL.clear()
        _ACTUAL[k] = params.apply(mech, np.frombuffer(key, dtype=float))
    return _ACTUAL[k]


def monte_carlo(
    model: str | Path,
    preset: str,
    q_act_rows: np.ndarray,
    true_values: np.ndarray,
    noise: NoiseModel | Mapping[str, float] | None,
    runs: int,
    *,
    seed: int = 0,
    method: str = "gauss-newton",
    n_jobs: int = 1,
    scheduler: str | None = None,
) -> MonteCarloStudy:
    """Repeat simulate-and-identify ``runs`` times with independent noise.

    Args:
        model: bundled model name or model file path (workers rebuild the mechanism).
        preset: parameter preset name (e.g. ``"full"``, ``"stewart42"``).
        q_act_rows: (m, n_act) actuator values of the measured poses [m, rad].
        true_values: (n,) parameter errors of the simulated machine [m, rad].
        noise: measurement noise (NoiseModel or mapping as for simulate_measurements).
        runs: number of repetitions (≥ 1).
        seed: study seed; run k uses child k of ``np.random.SeedSequence(seed)``.
        method: identification solver name.
        n_jobs: parallel processes (joblib; 1 = in this process, -1 = all cores).
        scheduler: a Dask scheduler (``local:N`` or ``tcp://host:8786``) instead of
            local processes (needs ``pincal[dask]``).

    Returns:
        The :class:`MonteCarloStudy` (identical numbers for any ``n_jobs``/scheduler).

    Raises:
        ParameterError: ``runs`` < 1 or ``true_values`` of the wrong length.
        ShapeError: ``q_act_rows`` not (m, n_act).
    """
    model = str(model)
    mech, params = _setup(model, preset)
    if int(runs) < 1:
        raise ParameterError(f"runs must be at least 1, got {runs}")
    truth = params.check_values(true_values).copy()
    rows = np.atleast_2d(np.asarray(q_act_rows, dtype=float))
    if rows.ndim != 2 or rows.shape[1] != mech.n_actuated:
        raise ShapeError(
            f"q_act_rows must have shape (m, {mech.n_actuated}) for actuated joints "
            f"{list(mech.actuated)}, got {np.shape(q_act_rows)}"
        )
    args = (model, preset, rows, truth, noise, method)
    with Executor(scheduler, n_jobs) as ex:
        out = ex.map(one_run, [args] * int(runs), seed=seed).values()
    values = np.array([v for v, _ in out]).reshape(int(runs), len(params))
    success = np.array([s for _, s in out], dtype=bool)
    return MonteCarloStudy(tuple(params.names), truth, values, success, int(seed))

"""Stage 0 — one executor for independent work: local processes or a Dask cluster.

Units of a fleet, Monte-Carlo draws, bootstrap refits and candidate evaluations are
independent items mapped through :class:`Executor`: local processes by default
(joblib/loky, as before), ``dask.distributed`` when a scheduler is given
(``tcp://host:8786``, or ``local:N`` for a ``LocalCluster`` of N worker processes).

- seeded items get child ``i`` of ``numpy.random.SeedSequence(seed)`` — the numbers do
  not depend on the backend, the worker count or the completion order;
- a failing item is reported in its own :class:`ItemResult`, not fatal to the others;
- with a :class:`Store` (``pincal.io.ResultStore``: a directory) each result is written
  atomically as it arrives, and a rerun loads what is written instead of computing it
  again (resume);
- a progress bar (tqdm) on the client.

Dask is an optional extra (``pip install "pincal[dask]"``); without it, asking for a
scheduler raises :class:`~pincal.errors.MissingExtraError`. This stage imports no other.
"""

from __future__ import annotations

from pincal.executor._map import Executor, ItemResult, MapResult, Store
from pincal.executor._scheduler import SchedulerSpec, parse_scheduler

__all__ = [
    "Executor",
    "ItemResult",
    "MapResult",
    "SchedulerSpec",
    "Store",
    "parse_scheduler",
]

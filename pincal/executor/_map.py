"""Map a function over independent items: local processes (joblib) or dask.distributed."""

from __future__ import annotations

import functools
import os
import pickle
import uuid
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
from threadpoolctl import threadpool_limits
from tqdm import tqdm

from pincal.errors import ItemFailedError, OptionValueError, WorkerSetupError
from pincal.executor._scheduler import SchedulerSpec, parse_scheduler

__all__ = ["Executor", "ItemResult", "MapResult", "Store", "run_item"]


class Store(Protocol):
    """Where a map keeps each item's result for a resumed run.

    :class:`pincal.io.ResultStore` is one: a directory, each result written atomically.
    """

    def has(self, key: str) -> bool:
        """Whether a result of ``key`` is written."""
        ...

    def load(self, key: str) -> Any:
        """The stored result of ``key``."""
        ...

    def save(self, key: str, value: Any) -> None:
        """Write ``value`` as the result of ``key``, whole or not at all."""
        ...


#: one item's run in a worker: (index, item, seed child) → ``run_item``'s tuple
ItemCall = Callable[
    [int, Any, "np.random.SeedSequence | None"],
    tuple[int, bool, Any, str | None, BaseException | None],
]
#: the client's callback on one arrived item: ``run_item``'s tuple unpacked
Arrived = Callable[[int, bool, Any, str | None, Any], None]


@dataclass(frozen=True)
class ItemResult:
    """The outcome of one item.

    Attributes:
        index: the item's position in the mapped sequence.
        key: its key (the store's file name; default ``str(index)``).
        ok: whether the function returned.
        value: what it returned (None when it failed).
        error: ``"ErrorType: message"`` when it failed, else None.
        exception: the worker's exception when it could be carried back, else None.
        cached: read from the store (not computed in this run).
    """

    index: int
    key: str
    ok: bool
    value: Any = None
    error: str | None = None
    exception: BaseException | None = None
    cached: bool = False


@dataclass(frozen=True)
class MapResult:
    """Every item's :class:`ItemResult`, in item order.

    Attributes:
        items: (n,) the results, ``items[i].index == i``.
    """

    items: tuple[ItemResult, ...]

    def __iter__(self) -> Iterator[ItemResult]:
        return iter(self.items)

    def __len__(self) -> int:
        return len(self.items)

    def __getitem__(self, i: int) -> ItemResult:
        return self.items[i]

    @property
    def failed(self) -> list[ItemResult]:
        """The items that failed."""
        return [r for r in self.items if not r.ok]

    @property
    def cached(self) -> int:
        """How many results were read from the store instead of computed."""
        return sum(r.cached for r in self.items)

    def values(self) -> list[Any]:
        """(n,) every value in item order, or the first failure raised.

        Raises:
            Exception: the first failed item's own exception when it was carried back,
                else :class:`~pincal.errors.ItemFailedError` naming the item.
        """
        for r in self.items:
            if not r.ok:
                if r.exception is not None:
                    raise r.exception
                raise ItemFailedError(f"item {r.key} failed: {r.error}", r.key, "")
        return [r.value for r in self.items]


def run_item(
    fn: Callable[..., Any], index: int, item: Any, child: np.random.SeedSequence | None
) -> tuple[int, bool, Any, str | None, BaseException | None]:
    """Run ``fn`` on one item in a worker, one BLAS thread, catching its error.

    Args:
        fn: the mapped function, ``fn(item)`` or ``fn(item, seed)`` with a seed child.
        index: the item's position.
        item: the item.
        child: its ``SeedSequence`` child, or None for unseeded work.

    Returns:
        ``(index, ok, value, error text, exception)``; the exception only when it
        survives pickling (it travels back to the client).
    """
    try:
        with threadpool_limits(1):
            value = fn(item) if child is None else fn(item, child)
        return index, True, value, None, None
    except Exception as exc:
        text = f"{type(exc).__name__}: {' '.join(str(exc).split())}"
        try:
            portable: BaseException | None = pickle.loads(pickle.dumps(exc))
        except Exception:
            portable = None
        return index, False, None, text, portable


class Executor:
    """Maps functions over items on local processes or a Dask cluster.

    Args:
        scheduler: None (local processes), ``local:N`` (a Dask ``LocalCluster`` of N
            workers, started on first use and stopped by :meth:`close`), a scheduler
            address (``tcp://host:8786``) or a parsed :class:`SchedulerSpec`.
        n_jobs: local processes without a scheduler (1 = in this process, -1 = every CPU).
        retries: times an item whose worker died is tried again before it is reported.

    Use it as a context manager (``with Executor("local:2") as ex: ex.map(...)``) so a
    local cluster is stopped.
    """

    def __init__(
        self, scheduler: str | SchedulerSpec | None = None, n_jobs: int = 1, *, retries: int = 2
    ):
        if isinstance(scheduler, SchedulerSpec):
            self.spec = scheduler
        else:
            self.spec = parse_scheduler(scheduler, n_jobs)
        if int(retries) < 0:
            raise OptionValueError(f"retries must be ≥ 0, got {retries}")
        self.retries = int(retries)
        self._client: Any = None
        self._cluster: Any = None

    def __enter__(self) -> Executor:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Close the Dask client and stop a local cluster this executor started."""
        if self._client is not None:
            self._client.close()
            self._client = None
        if self._cluster is not None:
            self._cluster.close()
            self._cluster = None

    @property
    def workers(self) -> int:
        """Worker processes (a remote scheduler's current count; 1 in this process)."""
        if self.spec.kind == "dask":
            return len(self.client().scheduler_info().get("workers", {}))
        return self.spec.workers if self.spec.workers != -1 else (os.cpu_count() or 1)

    def client(self) -> Any:
        """The ``distributed.Client`` (connected, or its local cluster started, once)."""
        if not self.spec.uses_dask:
            raise OptionValueError("this executor runs local processes: it has no Dask client")
        if self._client is None:
            import logging

            from distributed import Client, LocalCluster

            if self.spec.kind == "local-dask":
                self._cluster = LocalCluster(
                    n_workers=self.spec.workers,
                    threads_per_worker=1,
                    processes=True,
                    dashboard_address=":0",  # any free port: never clashes with a running one
                    silence_logs=logging.ERROR,
                )
                self._client = Client(self._cluster)
            else:
                self._client = Client(self.spec.address)
        return self._client

    def map(
        self,
        fn: Callable[..., Any],
        items: Sequence[Any],
        *,
        seed: int | None = None,
        keys: Sequence[str] | None = None,
        store: Store | None = None,
        progress: str | None = None,
    ) -> MapResult:
        """``fn`` on every item, each result in its own :class:`ItemResult`.

        Args:
            fn: a module-level function (workers import it): ``fn(item)``, or
                ``fn(item, seed)`` when ``seed`` is given, with ``seed`` child ``i`` of
                ``numpy.random.SeedSequence(seed)`` for item ``i`` — so seeded results are
                the same for any backend, worker count and completion order.
            items: (n,) the items (picklable).
            seed: the study seed, or None for unseeded work.
            keys: (n,) distinct item keys (default ``str(i)``); the store's file names.
            store: a :class:`Store` (:class:`pincal.io.ResultStore`, a directory):
                results already written there are loaded, not computed (resume); each
                new success is written as it arrives on the client.
            progress: a label for a progress bar on stderr (shown on a terminal), or None.

        Returns:
            The :class:`MapResult` in item order: a failed item carries its error; the
            others are unaffected.
        """
        n = len(items)
        keys = [str(i) for i in range(n)] if keys is None else [str(k) for k in keys]
        if len(keys) != n or len(set(keys)) != n:
            raise OptionValueError(f"keys must be {n} distinct texts, one per item")
        children = np.random.SeedSequence(seed).spawn(n) if seed is not None else [None] * n
        out: dict[int, ItemResult] = {}
        if store is not None:
            for i, key in enumerate(keys):
                if store.has(key):
                    out[i] = ItemResult(i, key, True, store.load(key), cached=True)
        pending = [i for i in range(n) if i not in out]
        bar = tqdm(total=n, initial=n - len(pending), desc=progress, disable=progress is None
                   or None, leave=False)  # fmt: skip

        def arrived(index: int, ok: bool, value: Any, error: str | None, exc: Any) -> None:
            if ok and store is not None:
                store.save(keys[index], value)
            out[index] = ItemResult(index, keys[index], ok, value, error, exc)
            bar.update(1)

        call = functools.partial(run_item, fn)
        try:
            if self.spec.uses_dask:
                self._map_dask(call, items, children, pending, arrived)
            else:
                self._map_local(call, items, children, pending, arrived, out.__contains__)
        finally:
            bar.close()
        return MapResult(tuple(out[i] for i in range(n)))

    def _map_local(
        self,
        call: ItemCall,
        items: Sequence[Any],
        children: Sequence[np.random.SeedSequence | None],
        pending: list[int],
        arrived: Arrived,
        done: Callable[[int], bool],
    ) -> None:
        if self.spec.workers == 1:
            for i in pending:
                arrived(*call(i, items[i], children[i]))
            return
        from joblib import Parallel, delayed
        from joblib.externals.loky.process_executor import TerminatedWorkerError

        for attempt in range(self.retries + 1):
            left = [i for i in pending if not done(i)]
            if not left:
                return
            try:
                run = Parallel(n_jobs=self.spec.workers, return_as="generator_unordered")
                for res in run(delayed(call)(i, items[i], children[i]) for i in left):
                    arrived(*res)
            except TerminatedWorkerError as exc:  # a worker died: the rest is tried again
                if attempt == self.retries:
                    for i in pending:
                        if not done(i):
                            arrived(i, False, None, f"worker lost: {exc}", None)

    def _map_dask(
        self,
        call: ItemCall,
        items: Sequence[Any],
        children: Sequence[np.random.SeedSequence | None],
        pending: list[int],
        arrived: Arrived,
    ) -> None:
        from distributed import as_completed

        client = self.client()
        if pending:
            _check_workers(client, call, items[pending[0]], children[pending[0]])
        token = uuid.uuid4().hex[:8]
        futures = {
            client.submit(
                call,
                i,
                items[i],
                children[i],
                key=f"pincal-{token}-{i}",
                pure=False,
                retries=self.retries,
            ): i
            for i in pending
        }
        for fut in as_completed(list(futures)):
            i = futures[fut]
            try:
                res = fut.result()
            except Exception as exc:  # the worker died every time (KilledWorker) or similar
                arrived(i, False, None, f"{type(exc).__name__}: {exc}", None)
            else:
                arrived(*res)
            fut.release()


def _check_workers(client: Any, call: ItemCall, item: Any, child: Any) -> None:
    """Raise WorkerSetupError when a worker cannot load the call with its first item.

    A task whose function a worker cannot unpickle (its module missing there) breaks
    that worker's connection and is never answered: the map would wait for ever. Sent
    as the arguments of a builtin (``len``), the same pickles fail at once, on the
    client, and leave the workers usable.
    """
    try:
        client.run(len, (call, item, child))
    except Exception as exc:  # the worker's unpickling error, carried back as text
        raise WorkerSetupError(
            f"the Dask workers cannot load the work sent to them ({exc}): every worker "
            "needs pincal and the module that defines the mapped function, installed in "
            "the same versions as here; a script's own functions can be sent with "
            "Executor.client().upload_file(PATH)"
        ) from exc

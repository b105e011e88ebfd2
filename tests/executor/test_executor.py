"""The executor: same seeded numbers on every backend, per-item failures, resume."""

from __future__ import annotations

import importlib
import importlib.util
import os
import sys
from pathlib import Path

import numpy as np
import pytest

from pincal.errors import ItemFailedError, MissingExtraError, OptionValueError, WorkerSetupError
from pincal.executor import Executor, parse_scheduler
from pincal.io import ResultStore

HAS_DASK = importlib.util.find_spec("distributed") is not None
needs_dask = pytest.mark.skipif(not HAS_DASK, reason="dask.distributed not installed")


def draw(item, seed):
    """A seeded item: its draws depend on its seed child only."""
    rng = np.random.default_rng(seed)
    return item * 10 + rng.normal(size=3)


def counted(item):
    """Leaves one file per call in item[0] (calls are counted across processes)."""
    folder, value = item
    Path(folder, f"{value}.{os.getpid()}.{np.random.default_rng().integers(1 << 60)}").touch()
    if value == 3:
        raise ValueError("item 3 is bad")
    return value * value


def dies_once(item):
    """Kills its worker process the first time (a marker file says it happened)."""
    folder, value = item
    marker = Path(folder, f"died-{value}")
    if value == 1 and not marker.exists():
        marker.touch()
        os._exit(3)
    return value + 100


@pytest.fixture(scope="module")
def dask2():
    if not HAS_DASK:
        pytest.skip("dask.distributed not installed")
    with Executor("local:2") as ex:
        yield ex


def _calls(folder: Path) -> int:
    return len(list(folder.glob("*.*.*")))


def test_seeded_items_are_identical_on_every_backend(dask2):
    items = list(range(7))
    serial = Executor().map(draw, items, seed=11).values()
    local2 = Executor(n_jobs=2).map(draw, items, seed=11).values()
    dasked = dask2.map(draw, items, seed=11).values()
    for a, b, c in zip(serial, local2, dasked, strict=True):
        assert np.array_equal(a, b) and np.array_equal(a, c)
    other = Executor().map(draw, items, seed=12).values()
    assert not np.array_equal(serial[0], other[0])
    # item i's numbers are child i of SeedSequence(seed), whatever else is mapped
    alone = draw(4, np.random.SeedSequence(11).spawn(5)[4])
    assert np.array_equal(alone, serial[4])


@pytest.mark.parametrize("backend", ["serial", "joblib2", "dask2"])
def test_a_failing_item_is_reported_and_the_rest_resume(tmp_path, backend, request):
    ex = (
        request.getfixturevalue("dask2")
        if backend == "dask2"
        else Executor(n_jobs=2 if backend == "joblib2" else 1)
    )
    calls = tmp_path / "calls"
    calls.mkdir()
    items = [(str(calls), v) for v in range(6)]
    keys = [f"unit-{v}" for v in range(6)]
    first = ex.map(counted, items, keys=keys, store=ResultStore(tmp_path / "store"))
    assert [r.ok for r in first] == [True, True, True, False, True, True]
    assert first[3].error == "ValueError: item 3 is bad"
    assert isinstance(first[3].exception, ValueError)
    assert [r.value for r in first if r.ok] == [0, 1, 4, 16, 25]
    assert _calls(calls) == 6
    with pytest.raises(ValueError, match="item 3 is bad"):
        first.values()
    # a rerun computes only the failed item again; the others are read back
    again = ex.map(counted, items, keys=keys, store=ResultStore(tmp_path / "store"))
    assert _calls(calls) == 7
    assert again.cached == 5 and [r.cached for r in again] == [True] * 3 + [False] + [True] * 2
    assert [r.value for r in again] == [r.value for r in first]


def test_the_store_writes_whole_files(tmp_path):
    store = ResultStore(tmp_path / "s")
    store.save("a/b c", {"x": 1})
    assert store.has("a/b c") and not store.has("a_b c")
    assert store.load("a/b c") == {"x": 1}
    assert not list((tmp_path / "s").glob("*.tmp"))
    with pytest.raises(KeyError):
        store.load("missing")


def test_a_worker_that_dies_is_replaced_and_its_item_retried(tmp_path):
    items = [(str(tmp_path), v) for v in range(4)]
    out = Executor(n_jobs=2).map(dies_once, items)
    assert [r.value for r in out] == [100, 101, 102, 103]
    assert (tmp_path / "died-1").exists()


@needs_dask
def test_a_dask_worker_that_dies_loses_no_item(tmp_path, dask2):
    items = [(str(tmp_path), v) for v in range(4)]
    out = dask2.map(dies_once, items)
    assert [r.value for r in out] == [100, 101, 102, 103]
    assert (tmp_path / "died-1").exists()


def test_scheduler_texts():
    assert parse_scheduler(None).kind == "joblib"
    assert parse_scheduler("", 3).workers == 3
    for bad in ["local:0", "local:x", "host:8786", "dask"]:
        with pytest.raises(OptionValueError, match="local:N"):
            parse_scheduler(bad)
    with pytest.raises(OptionValueError, match="positive integer"):
        parse_scheduler(None, 0)


def test_without_dask_a_scheduler_names_the_extra(monkeypatch):
    real = importlib.util.find_spec

    def find_spec(name, *args):
        return None if name == "distributed" else real(name, *args)

    monkeypatch.setattr(importlib.util, "find_spec", find_spec)
    for text in ["local:2", "tcp://10.0.0.1:8786"]:
        with pytest.raises(MissingExtraError, match=r'pip install "pincal\[dask\]"'):
            Executor(text)
    assert Executor(None, 2).spec.workers == 2  # the default needs no extra


def test_an_unpicklable_error_still_travels_as_text():
    out = Executor().map(_raise_local, [1])
    assert not out[0].ok and out[0].error.startswith("_Unpicklable")
    with pytest.raises(ItemFailedError, match="item 0 failed"):
        out.values()


class _Unpicklable(Exception):
    def __reduce__(self):
        raise TypeError("this error does not pickle")


def _raise_local(item):
    raise _Unpicklable(f"bad item {item}")


@needs_dask
def test_work_the_workers_cannot_load_is_refused_at_once(tmp_path, monkeypatch, dask2):
    """A function whose module only this process has: refused, the workers still usable."""
    (tmp_path / "only_here.py").write_text("def square(x):\n    return x * x\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    only_here = importlib.import_module("only_here")
    (tmp_path / "only_here.py").unlink()  # the workers (started elsewhere) cannot import it
    try:
        with pytest.raises(WorkerSetupError, match="only_here"):
            dask2.map(only_here.square, [1, 2, 3])
    finally:
        del sys.modules["only_here"]
    assert dask2.map(draw, [1, 2], seed=0).values()[1].shape == (3,)

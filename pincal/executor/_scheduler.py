"""The ``--scheduler`` text: none (local processes), ``local:N`` or a Dask address."""

from __future__ import annotations

import importlib.util
import re
from dataclasses import dataclass

from pincal.errors import MissingExtraError, OptionValueError, clip

__all__ = ["SchedulerSpec", "parse_scheduler", "require_dask"]

_ADDRESS = re.compile(r"^(tcp|tls|inproc|ws|wss|ucx)://\S+$")


@dataclass(frozen=True)
class SchedulerSpec:
    """Where items run.

    Attributes:
        kind: ``"joblib"`` (local processes), ``"local-dask"`` (a ``LocalCluster`` this
            process starts and stops) or ``"dask"`` (an existing scheduler).
        workers: processes of a local backend (≥ 1; -1 = every CPU for joblib).
        address: the scheduler's address (``"dask"`` only), e.g. ``tcp://host:8786``.
    """

    kind: str
    workers: int = 1
    address: str | None = None

    @property
    def uses_dask(self) -> bool:
        """Whether the items run on dask.distributed."""
        return self.kind != "joblib"


def require_dask() -> None:
    """Raise MissingExtraError unless ``dask.distributed`` can be imported.

    Raises:
        MissingExtraError: dask or distributed is not installed.
    """
    if importlib.util.find_spec("dask") is None or importlib.util.find_spec("distributed") is None:
        raise MissingExtraError(
            "a --scheduler runs the work on dask.distributed, which is not installed: "
            'install the optional extra with `pip install "pincal[dask]"` (or '
            '`pip install "dask[distributed]"`), or drop --scheduler to use local processes'
        )


def parse_scheduler(text: str | None, n_jobs: int = 1) -> SchedulerSpec:
    """The executor a ``--scheduler`` value (and ``--jobs``) selects.

    Args:
        text: None or ``""`` (local processes, ``n_jobs`` of them), ``local:N`` (a Dask
            ``LocalCluster`` of N single-threaded worker processes) or a scheduler
            address ``tcp://host:8786``.
        n_jobs: local processes without a scheduler (≥ 1, or -1 = every CPU).

    Returns:
        The :class:`SchedulerSpec`.

    Raises:
        OptionValueError: a value of none of these forms, or N < 1.
        MissingExtraError: a scheduler is asked for and dask is not installed.
    """
    if isinstance(n_jobs, bool) or not isinstance(n_jobs, int) or (n_jobs < 1 and n_jobs != -1):
        raise OptionValueError(f"jobs must be a positive integer or -1 (every CPU), got {n_jobs!r}")
    if text is None or not str(text).strip():
        return SchedulerSpec("joblib", n_jobs)
    text = str(text).strip()
    if text.startswith("local:"):
        count = text[len("local:") :]
        if not count.isdigit() or int(count) < 1:
            raise OptionValueError(
                f"scheduler {clip(text, quote=True)}: local:N needs a worker count N ≥ 1, "
                "e.g. local:2"
            )
        require_dask()
        return SchedulerSpec("local-dask", int(count))
    if _ADDRESS.match(text):
        require_dask()
        return SchedulerSpec("dask", 0, text)
    raise OptionValueError(
        f"scheduler {clip(text, quote=True)} is not understood: give local:N (a local Dask "
        "cluster of N workers) or a scheduler address such as tcp://host:8786"
    )

"""Size limits on untrusted inputs, in force for a block of code.

The library never reads the environment: its limits are :class:`Limits` (defaults
below), passed explicitly where a function takes them (``UrdfTree(xml, limits)``,
``read_text(path, limit=…)``) and otherwise the ones in force, :func:`active_limits`,
set for a block with ``with Limits(dof=400).applied(): …``. The command line reads the
``PINCAL_MAX_*`` environment variables once per command (:mod:`pincal.cli._environment`)
and runs the command under them.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass

from pincal.errors import InputLimitError

__all__ = ["DEFAULT_MAX_BYTES", "ENVIRONMENT", "Limits", "active_limits"]

#: Default cap on one input file: 200 MB (a 100 000-pose CSV is ~30 MB).
DEFAULT_MAX_BYTES = 200 * 1024 * 1024

#: the environment variable the command line reads for each limit (file size in MB)
ENVIRONMENT = {
    "file_bytes": "PINCAL_MAX_FILE_MB",
    "links": "PINCAL_MAX_LINKS",
    "dof": "PINCAL_MAX_DOF",
    "depth": "PINCAL_MAX_TREE_DEPTH",
    "parameters": "PINCAL_MAX_PARAMETERS",
}

#: what each limit protects, for the messages
_WHY = {
    "dof": " (Pinocchio's data grows as dof³: 0.6 GB at 200, 6.9 GB at 600)",
    "depth": " (Pinocchio's URDF parser crashes beyond ~3000 levels)",
    "parameters": " (the analysis time grows with the square of the count)",
}


@dataclass(frozen=True)
class Limits:
    """Size limits checked on inputs before they are parsed or analysed.

    Defaults leave a margin over real machines (the largest example-robot-data robot,
    TIAGo dual, has 101 degrees of freedom, 130 links and a depth of 21) while keeping
    Pinocchio's data (which grows as nv³: 0.6 GB and 1 s at nv = 200, 6.9 GB at 600)
    and its recursive URDF parser (it overflows the stack beyond ~3 000 levels) safe.

    Attributes:
        file_bytes: largest input file [bytes] (``PINCAL_MAX_FILE_MB`` on the command
            line, in MB; default 200 MB).
        links: most ``<link>`` elements (``PINCAL_MAX_LINKS``, default 1000).
        dof: most degrees of freedom nv (``PINCAL_MAX_DOF``, default 200).
        depth: most joints from the root link to any link (``PINCAL_MAX_TREE_DEPTH``,
            default 256).
        parameters: most parameters an identifiability analysis takes
            (``PINCAL_MAX_PARAMETERS``, default 3000: ~4 s; the cost grows with the
            square of the count).
    """

    file_bytes: int = DEFAULT_MAX_BYTES
    links: int = 1000
    dof: int = 200
    depth: int = 256
    parameters: int = 3000

    def check(self, what: str, value: int, limit: int, env: str, where: str) -> None:
        """Raise InputLimitError when ``value > limit`` (the message says how to raise it).

        Args:
            what: what was counted ("links", "degrees of freedom", …).
            value: the count.
            limit: its bound (one of this object's fields).
            env: the environment variable of that bound (:data:`ENVIRONMENT`).
            where: the input, for the message.
        """
        if value > limit:
            field = next(k for k, v in ENVIRONMENT.items() if v == env)
            raise InputLimitError(
                f"{where} has {value} {what}, over the limit of {limit}{_WHY.get(field, '')}; "
                f"if the model is right, raise the limit with the environment variable "
                f"{env}={value} (in Python: `with Limits({field}={value}).applied():`)"
            )

    @contextmanager
    def applied(self) -> Iterator[Limits]:
        """Make these the limits in force inside the ``with`` block (this thread/task)."""
        token = _ACTIVE.set(self)
        try:
            yield self
        finally:
            _ACTIVE.reset(token)


_ACTIVE: ContextVar[Limits | None] = ContextVar("pincal_limits", default=None)
_DEFAULT = Limits()


def active_limits() -> Limits:
    """The limits in force: the innermost :meth:`Limits.applied`, else the defaults."""
    return _ACTIVE.get() or _DEFAULT

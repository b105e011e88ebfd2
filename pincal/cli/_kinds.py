"""The ``--instrument`` choice of ``pincal simulate``, read live from the kind registry.

Its choices are the registered scalar instrument kinds
(:func:`pincal.measure.instrument_kinds`) and ``socket`` (a ball seated in the sockets
of a plate), read when the option is parsed, so a kind registered after the CLI was
imported is offered too.
"""

from __future__ import annotations

from collections.abc import Sequence

import click

__all__ = ["SOCKET", "InstrumentChoice"]

#: the socket-plate artefact, simulated by :func:`pincal.workflow.simulate_campaign`
SOCKET = "socket"


class InstrumentChoice(click.Choice):
    """``click.Choice`` over the registered instrument kinds (and ``socket``).

    Args:
        socket: offer ``socket`` too.
    """

    name = "instrument"

    def __init__(self, socket: bool = True) -> None:
        self._socket = socket
        super().__init__([SOCKET])

    @property  # type: ignore[override]
    def choices(self) -> Sequence[str]:
        """The registered instrument kinds (and ``socket`` where sockets are accepted)."""
        from pincal.measure import instrument_kinds

        return (*instrument_kinds(), *([SOCKET] if self._socket else []))

    @choices.setter
    def choices(self, value: Sequence[str]) -> None:
        """Set by ``click.Choice.__init__``; the registry is the source."""

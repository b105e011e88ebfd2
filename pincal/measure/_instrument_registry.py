"""The registry of instrument kinds: name → :class:`Instrument` or :class:`Artefact` class.

A new kind is one class plus one call ``add_instrument_kind(MyKind)``:

* a scalar kind (one reading per pose) is a :class:`pincal.measure.Instrument`
  subclass: files (``# kind: …``), ``pincal simulate --instrument``, the joint
  identification and the instrument analysis find it here;
* an artefact kind (k residuals per pose, unknowns shared by its datasets, e.g. the
  ``socket`` plates, the ``flush`` contacts) is a :class:`pincal.measure.Artefact`
  subclass (its dataset class): the joint identification finds its residuals and shared terms here.
"""

from __future__ import annotations

from typing import TypeVar

from pincal.errors import MeasurementError
from pincal.measure._artefact_kind import Artefact
from pincal.measure._flush_contact import FlushContact
from pincal.measure._instrument_kind import Instrument
from pincal.measure._instrument_kinds import Distance, Plane, Point, Sphere
from pincal.measure._sockets import SocketData

__all__ = [
    "INSTRUMENT_KINDS",
    "add_instrument_kind",
    "artefact_class",
    "artefact_kinds",
    "instrument_class",
    "instrument_kinds",
]

_KINDS: dict[str, type[Instrument] | type[Artefact]] = {}

K = TypeVar("K", type[Instrument], type[Artefact])


def add_instrument_kind(cls: K) -> K:
    """Register an instrument kind under ``cls.kind`` (usable as a class decorator).

    Args:
        cls: an :class:`Instrument` subclass (scalar kind) or an :class:`Artefact`
            subclass (artefact kind); one name space for both.

    Raises:
        MeasurementError: neither, or the name is taken by another class.
    """
    if not (isinstance(cls, type) and issubclass(cls, (Instrument, Artefact))):
        raise MeasurementError(
            f"an instrument kind is an Instrument or Artefact subclass, got {cls!r}"
        )
    name = getattr(cls, "kind", "")
    if not isinstance(name, str) or not name.isidentifier():
        raise MeasurementError(f"instrument kind name must be an identifier, got {name!r}")
    if _KINDS.get(name, cls) is not cls:
        raise MeasurementError(f"instrument kind {name!r} is already {_KINDS[name].__name__}")
    _KINDS[name] = cls
    return cls


def instrument_kinds() -> tuple[str, ...]:
    """The registered scalar kind names, in registration order."""
    return tuple(k for k, c in _KINDS.items() if issubclass(c, Instrument))


def artefact_kinds() -> tuple[str, ...]:
    """The registered artefact kind names, in registration order."""
    return tuple(k for k, c in _KINDS.items() if issubclass(c, Artefact))


def instrument_class(kind: str) -> type[Instrument]:
    """The class of a registered scalar kind.

    Raises:
        MeasurementError: an unknown kind (the registered ones are named).
    """
    cls = _KINDS.get(kind) if isinstance(kind, str) else None
    if cls is None or not issubclass(cls, Instrument):
        raise MeasurementError(
            f"unknown instrument kind {kind!r}; choose from {instrument_kinds()} "
            "(or use a pose/position measurement file)"
        )
    return cls


def artefact_class(kind: str) -> type[Artefact]:
    """The dataset class of a registered artefact kind.

    Raises:
        MeasurementError: an unknown artefact kind (the registered ones are named).
    """
    cls = _KINDS.get(kind) if isinstance(kind, str) else None
    if cls is None or not issubclass(cls, Artefact):
        raise MeasurementError(
            f"unknown artefact kind {kind!r}; choose from {artefact_kinds()} "
            "(register its Artefact class with add_instrument_kind)"
        )
    return cls


for _cls in (Distance, Sphere, Plane, Point):
    add_instrument_kind(_cls)
add_instrument_kind(SocketData)
add_instrument_kind(FlushContact)

#: the built-in scalar instrument kinds (:func:`instrument_kinds` lists registered ones)
INSTRUMENT_KINDS = instrument_kinds()

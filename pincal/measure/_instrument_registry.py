"""The registry of scalar instrument kinds: name → :class:`Instrument` subclass.

A new kind is one :class:`pincal.measure.Instrument` subclass plus one call
``add_instrument_kind(MyKind)``: files (``# kind: …``), ``pincal simulate
--instrument``, the joint identification and the instrument analysis find it here.
"""

from __future__ import annotations

from pincal.errors import MeasurementError
from pincal.measure._instrument_kind import Instrument
from pincal.measure._instrument_kinds import Distance, Plane, Point, Sphere

__all__ = ["INSTRUMENT_KINDS", "add_instrument_kind", "instrument_class", "instrument_kinds"]

_KINDS: dict[str, type[Instrument]] = {}


def add_instrument_kind(cls: type[Instrument]) -> type[Instrument]:
    """Register an instrument kind under ``cls.kind`` (usable as a class decorator).

    Raises:
        MeasurementError: not an Instrument subclass, or the name is taken by another class.
    """
    if not (isinstance(cls, type) and issubclass(cls, Instrument)):
        raise MeasurementError(f"an instrument kind is an Instrument subclass, got {cls!r}")
    name = getattr(cls, "kind", "")
    if not isinstance(name, str) or not name.isidentifier():
        raise MeasurementError(f"instrument kind name must be an identifier, got {name!r}")
    if _KINDS.get(name, cls) is not cls:
        raise MeasurementError(f"instrument kind {name!r} is already {_KINDS[name].__name__}")
    _KINDS[name] = cls
    return cls


def instrument_kinds() -> tuple[str, ...]:
    """The registered kind names, in registration order."""
    return tuple(_KINDS)


def instrument_class(kind: str) -> type[Instrument]:
    """The class of a registered kind.

    Raises:
        MeasurementError: an unknown kind (the registered ones are named).
    """
    try:
        return _KINDS[kind]
    except (KeyError, TypeError):
        raise MeasurementError(
            f"unknown instrument kind {kind!r}; choose from {instrument_kinds()} "
            "(or use a pose/position measurement file)"
        ) from None


for _cls in (Distance, Sphere, Plane, Point):
    add_instrument_kind(_cls)

#: the built-in scalar instrument kinds (:func:`instrument_kinds` lists registered ones)
INSTRUMENT_KINDS = instrument_kinds()

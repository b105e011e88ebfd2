"""What only a joint fit of several data sets records with its result, typed.

A fit of instrument, socket and pose files together (:func:`pincal.identification.
identify_instruments`) knows more than the machine's parameters: the instruments'
identified values, the data sets' labels, the redundancy its χ² counts, what it did
not calibrate (the gauge), what no measurement fixes and the identified socket centres.
:class:`JointDetails` holds them on :attr:`IdentificationRecord.joint`;
``identification.json`` keeps them as top-level entries (:meth:`JointDetails.to_dict`,
read back by :meth:`JointDetails.from_dict`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

__all__ = ["JOINT_KEYS", "JointDetails"]

#: the top-level entries of ``identification.json`` a joint fit writes
JOINT_KEYS = ("instruments", "datasets", "redundancy", "gauge", "warnings", "socket_centres_mm")


@dataclass(frozen=True)
class JointDetails:
    """The joint fit's own outcome.

    Attributes:
        instruments: instrument / artefact unknown name → value at the solution [SI].
        datasets: the data sets' labels, in fit order.
        redundancy: ν = N − f, the equations the fit did not use up.
        gauge: what the data do not observe (held at nominal), in words.
        warnings: what no measurement fixes, in words (e.g. the length scale).
        socket_centres_mm: ``"plate.socket"`` → identified centre (x, y, z) [mm].
    """

    instruments: dict[str, float] = field(default_factory=dict)
    datasets: tuple[str, ...] = ()
    redundancy: int = 0
    gauge: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()
    socket_centres_mm: dict[str, tuple[float, ...]] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """The JSON entries (``warnings`` and ``socket_centres_mm`` only when present)."""
        out: dict[str, Any] = {
            "instruments": dict(self.instruments),
            "datasets": list(self.datasets),
            "redundancy": self.redundancy,
            "gauge": list(self.gauge),
        }
        if self.warnings:
            out["warnings"] = list(self.warnings)
        if self.socket_centres_mm:
            out["socket_centres_mm"] = {k: list(c) for k, c in self.socket_centres_mm.items()}
        return out

    @classmethod
    def from_dict(cls, notes: Mapping[str, Any]) -> JointDetails | None:
        """The details among a record's top-level entries (None: not a joint fit's).

        Raises:
            TypeError, ValueError: an entry of the wrong shape.
        """
        if "instruments" not in notes or "gauge" not in notes:
            return None
        return cls(
            {str(k): float(v) for k, v in dict(notes["instruments"]).items()},
            tuple(str(s) for s in notes.get("datasets") or ()),
            int(notes.get("redundancy", 0)),
            tuple(str(g) for g in notes["gauge"]),
            tuple(str(w) for w in notes.get("warnings") or ()),
            {str(k): tuple(float(v) for v in c)
             for k, c in dict(notes.get("socket_centres_mm") or {}).items()},
        )  # fmt: skip

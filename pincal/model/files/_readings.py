"""How measurement files name and scale joint readings (sidecar keys, file header).

Real controllers log joints under their own names, in their own units, sometimes as
offsets from a reference pose. Declared once, in the sidecar (or a measurement file's
header, which wins key by key)::

    columns: {torso1: torso_lift_joint, armL1: arm_1_joint}   # file column → URDF joint
    joint_units: {angle: deg, length: mm}      # by joint kind, {arm_1_joint: deg}, or deg
    joint_reference: home                      # readings are offsets from home, or
                                               # {arm_1_joint: 0.5} [rad or m, SI]

A joint's value is ``reference + reading / factor`` with ``factor`` the unit's units
per SI unit (deg: 180/π, mm: 1000). A bracketed unit in a column title (``armL1 [deg]``)
wins over ``joint_units``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from pincal._yaml import shown
from pincal.errors import ModelFileError

__all__ = ["KINDS", "JointReadings"]

#: keys of ``joint_units`` that name a joint kind rather than a joint
KINDS = ("angle", "length")
_ANGLES = ("rad", "mrad", "urad", "deg")
#: length units (those of :data:`pincal.io._units.LENGTH_UNITS`)
_LENGTHS = ("m", "mm", "um")


@dataclass(frozen=True)
class JointReadings:
    """The joint-reading declarations (all optional).

    Attributes:
        columns: ``{file column: URDF joint}``.
        units: ``{joint or kind (angle, length): unit}`` (units checked by the reader).
        reference: ``"home"``, or ``{joint: value}`` [rad or m]; {} for absolute readings.
    """

    columns: dict[str, str] = field(default_factory=dict)
    units: dict[str, str] = field(default_factory=dict)
    reference: str | dict[str, float] = field(default_factory=dict)

    @classmethod
    def from_values(cls, columns: Any, units: Any, reference: Any, where: str) -> JointReadings:
        """Check the three declarations (``where`` names their origin in messages).

        Raises:
            ModelFileError: a value of the wrong type, a joint mapped from two columns, a
                single unit that is neither an angle nor a length unit.
        """
        cols = _str_map(columns, f"{where} 'columns'", "file column names to joint names")
        joints = list(cols.values())
        twice = sorted({j for j in joints if joints.count(j) > 1})
        if twice:
            raise ModelFileError(f"{where} 'columns' maps several columns to {shown(twice)}")
        if isinstance(units, str):  # one unit: for the joints of its kind
            if units not in _ANGLES + _LENGTHS:
                raise ModelFileError(
                    f"{where} 'joint_units' {shown(units)} is neither an angle unit "
                    f"({', '.join(_ANGLES)}) nor a length unit ({', '.join(_LENGTHS)}); give "
                    "one of them, or 'angle=deg length=mm' / 'JOINT=UNIT' entries"
                )
            units = {"angle" if units in _ANGLES else "length": units}
        unit_map = _str_map(units, f"{where} 'joint_units'", "angle/length or joints to units")
        for kind, known in (("angle", _ANGLES), ("length", _LENGTHS)):
            if kind in unit_map and unit_map[kind] not in known:
                raise ModelFileError(
                    f"{where} 'joint_units' {kind}={shown(unit_map[kind])}: not a {kind} "
                    f"unit; use one of {', '.join(known)}"
                )
        ref: str | dict[str, float]
        if reference is None or reference == {}:
            ref = {}
        elif reference == "home":
            ref = "home"
        elif isinstance(reference, Mapping):
            ref = {}
            for k, v in reference.items():
                if isinstance(v, bool) or not isinstance(v, int | float) or v != v:
                    raise ModelFileError(
                        f"{where} joint_reference[{shown(k)}] must be a number [rad or m], "
                        f"got {shown(v)}"
                    )
                ref[str(k)] = float(v)
        else:
            raise ModelFileError(
                f"{where} 'joint_reference' must be 'home' or map joints to values [rad or m], "
                f"got {shown(reference)}"
            )
        return cls(cols, unit_map, ref)

    def updated(self, other: JointReadings) -> JointReadings:
        """These declarations with ``other``'s given ones winning (a file header's)."""
        return JointReadings(
            {**self.columns, **other.columns},
            {**self.units, **other.units},
            other.reference if other.reference else self.reference,
        )

    def to_dict(self) -> dict[str, Any]:
        """The sidecar keys (only those given)."""
        out: dict[str, Any] = {}
        if self.columns:
            out["columns"] = dict(self.columns)
        if self.units:
            out["joint_units"] = dict(self.units)
        if self.reference:
            ref = self.reference
            out["joint_reference"] = ref if isinstance(ref, str) else dict(ref)
        return out


def _str_map(v: Any, what: str, meaning: str) -> dict[str, str]:
    if v is None:
        return {}
    if not isinstance(v, Mapping) or not all(
        isinstance(k, str) and isinstance(x, str) for k, x in v.items()
    ):
        raise ModelFileError(f"{what} must map {meaning}, got {shown(v)}")
    return {str(k): str(x) for k, x in v.items()}

"""What an export reads of a calibration: both mechanisms, the values, the joint terms.

The calibrated geometry is the calibrated mechanism (joint origins at full precision,
zero offsets folded into them as the twist along each joint's axis). Joint terms are
not geometry: a ``<joint>.gain`` parameter ``g`` makes the joint take
``q_actual = (1 + g) · q`` for a reading ``q`` [rad or m]; the other kinds (harmonics,
compliance, temperature, strut compliance) need data a controller table does not hold
(payload, temperature, the joint angle's harmonics) and are named by the formats as
what they cannot express. The reference every format is compared with is the
calibrated geometry at ``q_actual`` (gains applied, other terms left out, said so).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from pincal.io import CalibrationDirectory
from pincal.model import DOFS, Mechanism

__all__ = ["CalibratedMachine"]


@dataclass(frozen=True, eq=False)
class CalibratedMachine:
    """A calibration as the exports read it.

    Attributes:
        calibrated, nominal: the two mechanisms (same tree, same joint names).
        values: parameter name → identified (or start) value [SI].
        model: model name; preset: the calibration's parameter preset; source: where
            it was read (for the header).
    """

    calibrated: Mechanism
    nominal: Mechanism
    values: Mapping[str, float]
    model: str
    preset: str
    source: str

    @classmethod
    def from_directory(cls, cal: CalibrationDirectory) -> CalibratedMachine:
        """From a calibration directory (:func:`pincal.io.read_calibration`)."""
        result = cal.result
        values = {n: float(v) for n, v in zip(result.names, result.full_values, strict=True)}
        return cls(cal.calibrated(), cal.nominal(), values, cal.model, cal.preset, str(cal.path))

    @classmethod
    def from_mechanisms(
        cls, calibrated: Mechanism, nominal: Mechanism, values: Mapping[str, float] | None = None
    ) -> CalibratedMachine:
        """From two mechanisms (``values``: the joint terms and offsets, if any)."""
        return cls(calibrated, nominal, dict(values or {}), calibrated.name, "", calibrated.name)

    def offset(self, joint: str) -> float:
        """The calibrated zero offset of ``joint`` [rad or m] (0 when not a parameter)."""
        return self.values.get(f"{joint}.offset", 0.0)

    def gains(self) -> dict[str, float]:
        """Actuated joint → gain ``g`` (``q_actual = (1 + g) q``), for those that have one."""
        return {
            j: self.values[f"{j}.gain"]
            for j in self.calibrated.actuated
            if f"{j}.gain" in self.values
        }

    def joint_terms(self) -> list[str]:
        """Names of the calibration's joint-term parameters (dof not a placement dof)."""
        return [n for n in self.values if n.rpartition(".")[2] not in DOFS]

    def terms_not_held(self, held: tuple[str, ...] = ()) -> list[str]:
        """Joint-term parameters whose dof is not in ``held`` (e.g. ``("gain",)``)."""
        return [n for n in self.joint_terms() if n.rpartition(".")[2] not in held]

    def actual(self, q_act: np.ndarray) -> np.ndarray:
        """(m, n_act) joint values the machine takes for readings ``q_act`` (gains applied)."""
        q = np.array(q_act, dtype=float, ndmin=2)
        for k, joint in enumerate(self.calibrated.actuated):
            q[:, k] *= 1.0 + self.gains().get(joint, 0.0)
        return q

    def reference(self, q_act: np.ndarray) -> np.ndarray:
        """(m, 4, 4) world placements of the measured frame by the calibrated model."""
        mech = self.calibrated
        out = np.empty((len(q_act), 4, 4))
        for i, q in enumerate(self.actual(q_act)):
            out[i] = mech.frame_placement(mech.configuration(q)).homogeneous
        return out

    def configuration(self, q_act: np.ndarray) -> np.ndarray:
        """(nq,) configuration of the calibrated model at readings ``q_act`` (n_act,)."""
        return self.calibrated.configuration(self.actual(q_act)[0])

"""Several markers on one link, fitted together: one problem over their stacked rows.

Marker k is a point of the measured link at its own unknown offset (the ``tool_frame``
joint for the first, ``marker<k>_frame`` for the others; see
:func:`pincal.measure.marker_mechanism`), seen in one instrument frame. Each marker's
rows are an ordinary :class:`CalibrationProblem` of the mechanism measuring that
marker's frame; all share one parameter set (so one instrument frame, one robot), and
a marker's offset has a zero Jacobian in the other markers' rows. :class:`StackedProblem`
stacks their residuals and Jacobians; :class:`MarkerSetProblem` is the
:class:`IdentificationProblem` whose residual model it is, so every solver of
:func:`identify` and its identifiable-set reduction, noise estimation and covariance
apply unchanged. Raw residuals are (Σ m_k, 3): the markers' rows one after the other.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from pincal.errors import MeasurementError
from pincal.identification.problem._identification_problem import IdentificationProblem
from pincal.identification.problem._instrument_problem import Dataset as Dataset  # the inherited
from pincal.identification.problem._problem import CalibrationProblem
from pincal.measure import Measurements
from pincal.measure import NoiseModel as NoiseModel  # __init__'s annotations resolve here
from pincal.model import Mechanism, ParameterSet

__all__ = ["MarkerSetProblem", "StackedProblem", "stacked_measurements"]


def stacked_measurements(parts: Sequence[Measurements]) -> Measurements:
    """The markers' rows one after the other, as measurements of the first marker's frame."""
    first = parts[0]
    return Measurements(
        np.vstack([p.q_act for p in parts]),
        np.vstack([p.positions for p in parts]),
        None,
        first.components,
        first.frame,
        first.actuated,
    )


class StackedProblem(CalibrationProblem):
    """The residual model of several markers: per-marker problems, one parameter vector.

    Args:
        parts: one :class:`CalibrationProblem` per marker, all of the same parameter
            set and components (the first one's mechanism is the calibrated model).
    """

    def __init__(self, parts: Sequence[CalibrationProblem]):
        self.parts = tuple(parts)
        first = self.parts[0]
        self.mech, self.params, self.meas = first.mech, first.params, first.meas
        self.rows, self.blocks = first.rows, first.blocks
        self.noise_source = first.noise_source

    @property
    def sigma(self) -> np.ndarray:  # type: ignore[override]
        """(Σ m_k, k) σ of every marker's rows, stacked (read-only: see ``with_block_std``)."""
        return np.vstack([p.sigma for p in self.parts])

    @sigma.setter
    def sigma(self, value: np.ndarray) -> None:
        raise AttributeError("set the σ of a stacked problem with with_block_std")

    @property
    def predict_starts(self) -> bool:
        """Whether the parts start each pose's loop solve from a first-order prediction."""
        return self.parts[0].predict_starts

    @predict_starts.setter
    def predict_starts(self, value: bool) -> None:
        for p in self.parts:
            p.predict_starts = value

    def with_block_std(self, std: Mapping[str, float]) -> StackedProblem:
        new = StackedProblem([p.with_block_std(std) for p in self.parts])
        new.noise_source = "estimated"
        return new

    @property
    def solver_floor_cost(self) -> float:
        return float(sum(p.solver_floor_cost for p in self.parts))

    @property
    def n_equations(self) -> int:
        return int(sum(p.n_equations for p in self.parts))

    def mechanism(self, values: np.ndarray) -> Mechanism:
        return self.parts[0].mechanism(values)

    def residuals(
        self, values: np.ndarray, jacobian: bool
    ) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
        """Stacked whitened residual, its Jacobian (or None) and raw residuals (Σm_k, 3)."""
        outs = [p.evaluate(values, jacobian) for p in self.parts]
        r = np.concatenate([o[0] for o in outs])
        J = np.vstack([o[1] for o in outs if o[1] is not None]) if jacobian else None
        raw = np.vstack([o[2] for o in outs])
        return r, J, raw

    def structural_jacobian(self, values: np.ndarray) -> np.ndarray:
        return np.vstack([p.structural_jacobian(values) for p in self.parts])


@dataclass(frozen=True, eq=False)
class MarkerSetProblem(IdentificationProblem):
    """An :class:`IdentificationProblem` of several markers (``measurements`` stacked).

    Attributes:
        mechs: one mechanism per marker, measuring its frame (same URDF and parameters).
        parts: one measurement set per marker (same rows).
    """

    mechs: tuple[Mechanism, ...] = ()
    parts: tuple[Measurements, ...] = ()

    @classmethod
    def build(
        cls,
        mechs: Sequence[Mechanism],
        params: ParameterSet,
        parts: Sequence[Measurements],
        initial: np.ndarray | None = None,
        fit: Sequence[str] | None = None,
    ) -> MarkerSetProblem:
        """Raises MeasurementError: not one measurement set per mechanism."""
        if len(mechs) != len(parts) or not parts:
            raise MeasurementError(
                f"give one measurement set per marker: {len(mechs)} markers, {len(parts)} sets"
            )
        return cls(
            mechs[0], params, stacked_measurements(parts), initial, fit,
            mechs=tuple(mechs), parts=tuple(parts),
        )  # fmt: skip

    @cached_property
    def model(self) -> CalibrationProblem:
        """The stacked residual model (one :class:`CalibrationProblem` per marker)."""
        return StackedProblem(
            [
                CalibrationProblem(m, self.params, p)
                for m, p in zip(self.mechs, self.parts, strict=True)
            ]
        )

"""Problems rebuilt in worker processes (a bootstrap's refits in parallel).

Pinocchio models, and so mechanisms and the problems holding them, do not pickle. A
recipe carries what rebuilds them — the mechanism's constructor arguments (URDF text,
typed sidecar, name, source, measured frame, solver options, assembled home) and the
limits in force, the parameter set, the data and the weights — and rebuilds the
problem when called in the worker. The worker checks that its problem gives the
caller's residual at the solution (see :func:`pincal.identification.uncertainty._bootstrap`);
a mechanism a recipe cannot reproduce (a payload, a model edited in place) is refitted
in the caller instead.
"""

from __future__ import annotations

import pickle
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from pincal.measure import Measurements, NoiseModel
from pincal.model import Mechanism, ParameterSet, active_limits

if TYPE_CHECKING:  # imported in the call: the problems import this module's users
    from pincal.identification.problem._instrument_problem import Dataset, InstrumentProblem
    from pincal.identification.problem._problem import CalibrationProblem

__all__ = ["InstrumentRecipe", "PoseRecipe", "mechanism_blob"]


def mechanism_blob(mech: Mechanism) -> bytes:
    """The pickled limits in force and constructor arguments of ``mech``."""
    args = (active_limits(), mech.urdf_xml, mech.sidecar, mech.name, mech.source,
            mech.measured_frame, mech.options, np.asarray(mech.q_home, dtype=float))  # fmt: skip
    return pickle.dumps(args, protocol=pickle.HIGHEST_PROTOCOL)


def _rebuild(blob: bytes) -> Mechanism:
    limits, urdf, sidecar, name, source, frame, options, q_home = pickle.loads(blob)
    with limits.applied():  # the caller's limits, not the worker's defaults
        return Mechanism(urdf, sidecar, name=name, source=source, measured_frame=frame,
                         q_guess=q_home, options=options)  # fmt: skip


@dataclass(frozen=True)
class PoseRecipe:
    """Rebuilds a pose problem (:class:`CalibrationProblem`) in a worker.

    Attributes:
        blob: :func:`mechanism_blob` of the nominal mechanism.
        params: the parameter set; meas: the measurements.
        noise: the declared noise given to the fit (None: the file's or estimated).
        block_std: {block: σ [m or rad]} of an estimated-noise fit (None: declared).
    """

    blob: bytes
    params: ParameterSet
    meas: Measurements
    noise: NoiseModel | Mapping[str, float] | None = None
    block_std: Mapping[str, float] | None = None

    def __call__(self) -> CalibrationProblem:
        from pincal.identification.problem._problem import CalibrationProblem

        model = CalibrationProblem(_rebuild(self.blob), self.params, self.meas, self.noise)
        return model if self.block_std is None else model.with_block_std(dict(self.block_std))


@dataclass(frozen=True)
class InstrumentRecipe:
    """Rebuilds an instrument problem (:class:`InstrumentProblem`) in a worker."""

    blob: bytes
    params: ParameterSet
    datasets: Sequence[Dataset]
    labels: Sequence[str] | None = None

    def __call__(self) -> InstrumentProblem:
        from pincal.identification.problem._instrument_problem import InstrumentProblem

        return InstrumentProblem(_rebuild(self.blob), self.params, self.datasets, self.labels)

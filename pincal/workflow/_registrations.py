"""The closed-form registrations of one marker calibration, each computed once.

Cross-validating a marker calibration fits the same training poses many times: each
candidate prior on the same folds, the registration-only baseline on the outer folds.
The registration (:func:`pincal.measure.register_markers`: instrument frame and
marker(s) in closed form) depends on the poses only, not on the prior or the preset,
so :class:`Registrations` computes it once per set of poses (keyed by their content)
and hands it to :func:`pincal.identification.fit_markers`. A fold's registration is
that of its own training poses: sharing never lets a held-out pose in.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable

from pincal.measure import MarkerRegistration, MarkerSetup, Measurements, register_markers
from pincal.model import Mechanism

__all__ = ["MarkerData", "MarkerProcedure", "Registrations"]

#: the poses of a marker fit: one measurement set, or one per marker (same rows)
MarkerData = Measurements | tuple[Measurements, ...]
#: a fitting procedure: marker data → calibrated mechanism
MarkerProcedure = Callable[[MarkerData], Mechanism]


class Registrations:
    """Registrations of measurement sets of one mechanism and set-up, by content."""

    def __init__(self, mech: Mechanism, setup: MarkerSetup) -> None:
        self._mech, self._setup = mech, setup
        self._done: dict[bytes, MarkerRegistration] = {}

    def __call__(self, meas: MarkerData) -> MarkerRegistration:
        """The registration of ``meas`` (one set, or one per marker), as fit_markers runs it."""
        parts = (meas,) if isinstance(meas, Measurements) else tuple(meas)
        h = hashlib.sha256()
        for p in parts:
            h.update(p.q_act.tobytes())
            h.update(p.positions.tobytes())
            if p.rotations is not None:
                h.update(p.rotations.tobytes())
        key = h.digest()
        if key not in self._done:
            self._done[key] = register_markers(
                self._mech,
                parts[0],
                marker_known=self._setup.marker is not None,
                frame_known=self._setup.instrument_frame == "known",
                more=parts[1:],
            )
        return self._done[key]

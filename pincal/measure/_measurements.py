"""Measurements of the measured frame, noise models and simulation.

A :class:`Measurements` holds, per pose, the commanded actuator values and the
measured position (and orientation, when the instrument gives it) of the measured
frame in the world frame. Internally SI (m, rad); noise models are stated in the
units an instrument data sheet uses (mm, mrad).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pincal.errors import MeasurementError
from pincal.model import COMPONENTS, Mechanism

__all__ = ["DEFAULT_NOISE", "Measurements", "NoiseModel", "simulate_measurements"]


@dataclass(frozen=True)
class NoiseModel:
    """Independent Gaussian measurement noise.

    Attributes:
        position: standard deviation per position coordinate [mm].
        orientation: standard deviation per rotation component [mrad].
    """

    position: float = 0.0
    orientation: float = 0.0

    def __post_init__(self) -> None:
        for name in ("position", "orientation"):
            v = getattr(self, name)
            try:
                ok = bool(np.isfinite(v) and v >= 0)
            except TypeError:
                ok = False
            if not ok:
                raise MeasurementError(f"noise {name} must be a finite std ≥ 0, got {v!r}")

    @classmethod
    def from_spec(cls, spec: NoiseModel | Mapping[str, float] | None) -> NoiseModel | None:
        """Accept None, a NoiseModel, or ``{"position": mm, "orientation": mrad}``.

        Raises:
            MeasurementError: unknown keys, non-numeric or negative values, other types.
        """
        if spec is None or isinstance(spec, NoiseModel):
            return spec
        if isinstance(spec, Mapping):
            unknown = set(spec) - {"position", "orientation"}
            if unknown:
                raise MeasurementError(
                    f"noise keys {sorted(unknown)} not understood; use 'position' [mm] and "
                    "'orientation' [mrad]"
                )
            try:
                position = float(spec.get("position", 0.0))
                orientation = float(spec.get("orientation", 0.0))
            except (TypeError, ValueError):
                raise MeasurementError(
                    f"noise values must be numbers (position [mm], orientation [mrad]), got "
                    f"{dict(spec)!r}"
                ) from None
            return cls(position, orientation)
        raise MeasurementError(f"noise must be None, a NoiseModel or a mapping, got {spec!r}")

    def std(self, components: tuple[str, ...]) -> np.ndarray:
        """Per-component standard deviations (k,) in SI [m, rad].

        Args:
            components: component names (k,) from ``x y z rx ry rz``; ``x y z`` take
                the position std, the others the orientation std.
        """
        return np.array(
            [self.position * 1e-3 if c in "xyz" else self.orientation * 1e-3 for c in components]
        )


#: the default instrument noise (1σ) of every command that simulates or designs a
#: campaign (`poses`, `simulate`, `demo`, `run`): a laser tracker measuring the full pose,
#: 0.01 mm per position coordinate and 0.02 mrad per rotation component. Defined here once.
DEFAULT_NOISE = NoiseModel(0.01, 0.02)


@dataclass(frozen=True)
class Measurements:
    """Measured poses of the measured frame.

    Attributes:
        q_act: (m, n_act) commanded actuator values [m, rad].
        positions: (m, 3) measured world positions [m].
        rotations: (m, 3, 3) measured orientations, or None (position-only instrument).
        components: measured components used for identification (from x y z rx ry rz).
        frame: name of the measured frame.
        actuated: actuated joint names (columns of ``q_act``).
        noise: the instrument noise model, or None if unknown.
        std: optional (m, k) per-pose standard deviations of the measured components
            [m, rad] (e.g. from a laser tracker's per-pose fit covariance); overrides
            ``noise`` for weighting.
        temperature: optional (m,) temperature of the machine at each pose [°C] (for
            the thermal-expansion term, ``--model geometric+temperature``).
    """

    q_act: np.ndarray
    positions: np.ndarray
    rotations: np.ndarray | None
    components: tuple[str, ...]
    frame: str
    actuated: tuple[str, ...]
    noise: NoiseModel | None = None
    std: np.ndarray | None = None
    temperature: np.ndarray | None = None

    def __post_init__(self) -> None:
        for name in ("q_act", "positions", "rotations", "std", "temperature"):
            value = getattr(self, name)
            if value is None or isinstance(value, np.ndarray):
                continue
            try:  # sequences are accepted and stored as float arrays
                object.__setattr__(self, name, np.asarray(value, dtype=float))
            except (TypeError, ValueError):
                raise MeasurementError(f"{name} must be an array of numbers") from None
        bad_comps = [c for c in self.components if c not in COMPONENTS]
        if bad_comps or not self.components or len(set(self.components)) != len(self.components):
            raise MeasurementError(
                f"components {tuple(self.components)} invalid; choose distinct names from "
                f"{COMPONENTS}"
            )
        m = self.q_act.shape[0] if self.q_act.ndim else 0
        if self.q_act.ndim != 2 or self.q_act.shape[1] != len(self.actuated):
            raise MeasurementError(
                f"q_act must be (m, {len(self.actuated)}), got {self.q_act.shape}"
            )
        if self.positions.shape != (m, 3):
            raise MeasurementError(f"positions must be ({m}, 3), got {self.positions.shape}")
        if self.rotations is not None and self.rotations.shape != (m, 3, 3):
            raise MeasurementError(f"rotations must be ({m}, 3, 3), got {self.rotations.shape}")
        if self.rotations is None and any(c.startswith("r") for c in self.components):
            raise MeasurementError(
                f"components {self.components} include rotations but no orientation was measured"
            )
        if self.std is not None:
            if self.std.shape != (m, len(self.components)):
                raise MeasurementError(
                    f"std must be ({m}, {len(self.components)}), got {self.std.shape}"
                )
            if not np.all(np.isfinite(self.std) & (self.std > 0)):
                raise MeasurementError("std must be finite and > 0")
        if self.temperature is not None:
            if self.temperature.shape != (m,):
                raise MeasurementError(
                    f"temperature must be ({m},) [°C], got {self.temperature.shape}"
                )
            if not np.all(np.isfinite(self.temperature)):
                raise MeasurementError("temperature must be finite [°C]")
        for name, arr in (("q_act", self.q_act), ("positions", self.positions)):
            bad = np.nonzero(~np.all(np.isfinite(arr.reshape(m, -1)), axis=1))[0]
            if bad.size:
                raise MeasurementError(f"{name} has NaN or inf in pose {int(bad[0])}")

    def __len__(self) -> int:
        """Number of poses m."""
        return self.q_act.shape[0]

    @property
    def component_indices(self) -> np.ndarray:
        """Indices (k,) of ``components`` in ``x y z rx ry rz``."""
        return np.array([COMPONENTS.index(c) for c in self.components])

    @property
    def conditions(self) -> dict[str, np.ndarray | None]:
        """Per-pose conditions for the error-model terms: ``{"temperature": (m,) °C or None}``."""
        return {"temperature": self.temperature}

    def subset(self, indices: np.ndarray | list[int] | slice) -> Measurements:
        """Measurements of the poses at ``indices``.

        Args:
            indices: pose indices (integers in [-m, m)), a boolean mask (m,) or a slice.

        Raises:
            MeasurementError: an index out of range or not an integer / boolean.
        """
        m = len(self)
        idx = indices if isinstance(indices, slice) else np.asarray(indices)
        if not isinstance(idx, slice):
            if idx.dtype == bool:
                if idx.shape != (m,):
                    raise MeasurementError(
                        f"a boolean mask must have shape ({m},), got {idx.shape}"
                    )
            elif idx.size and not np.issubdtype(idx.dtype, np.integer):
                raise MeasurementError(f"pose indices must be integers, got {idx.dtype}")
            elif idx.size and (idx.min() < -m or idx.max() >= m):
                raise MeasurementError(f"pose indices must lie in [0, {m}), got {idx.tolist()}")
        return Measurements(
            self.q_act[idx],
            self.positions[idx],
            None if self.rotations is None else self.rotations[idx],
            self.components,
            self.frame,
            self.actuated,
            self.noise,
            None if self.std is None else self.std[idx],
            None if self.temperature is None else self.temperature[idx],
        )


def simulate_measurements(
    actual: Mechanism,
    q_act_rows: np.ndarray,
    noise: NoiseModel | Mapping[str, float] | None = None,
    rng: np.random.Generator | None = None,
    components: tuple[str, ...] | None = None,
) -> Measurements:
    """Measure the ``actual`` mechanism at actuator rows (m, n_act), with optional noise.

    Position noise is added in the world frame, orientation noise as a rotation
    ``R · exp3(n)`` in the measured frame. Orientation is recorded only when a rotation
    component is measured.

    Args:
        actual: the machine measured (simulation truth).
        q_act_rows: actuator values (m, n_act) [m, rad]; a single row (n_act,) is accepted.
        noise: a :class:`NoiseModel`, ``{"position": mm, "orientation": mrad}`` or None.
        rng: random generator for the noise (default: a fresh one).
        components: measured components (default ``actual.measured_components``).

    Returns:
        The measurements (m poses) [SI].

    Raises:
        MeasurementError: bad noise specification or components.
        ConvergenceError: the closure cannot be solved for a row (from ``actual``).
    """
    noise = NoiseModel.from_spec(noise)
    comps = tuple(components or actual.measured_components)
    rng = rng if rng is not None else np.random.default_rng()
    rows = np.atleast_2d(np.asarray(q_act_rows, dtype=float))
    qs = actual.configurations(rows)
    with_rot = any(c.startswith("r") for c in comps)
    m = rows.shape[0]
    positions = np.empty((m, 3))
    rotations = np.empty((m, 3, 3)) if with_rot else None
    for i, q in enumerate(qs):
        oMf = actual.frame_placement(q)
        positions[i] = oMf.translation
        if rotations is not None:
            rotations[i] = oMf.rotation
    if noise is not None:
        positions = positions + rng.normal(0.0, noise.position * 1e-3, positions.shape)
        if rotations is not None:
            for i in range(m):
                rotations[i] = rotations[i] @ pin.exp3(rng.normal(0.0, noise.orientation * 1e-3, 3))
    return Measurements(
        rows.copy(), positions, rotations, comps, actual.measured_frame, actual.actuated, noise
    )

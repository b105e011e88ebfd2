"""The interface of a scalar instrument: one reading per pose of the tool point.

An instrument kind is one subclass of :class:`Instrument` (a frozen dataclass with at
least the field ``std``) registered by name (:func:`pincal.measure.add_instrument_kind`).
Everything that handles instruments — the file reader and writer, ``pincal simulate``,
the joint identification, candidate poses, ``pincal info`` — asks the class, never the
kind's name. A kind declares:

* ``kind`` (its name in files and on the command line), ``description`` (words);
* its own unknowns θ: :attr:`Instrument.parameter_names` / ``parameter_units`` and
  :meth:`Instrument.start` (start values from the readings at nominal tool points);
* :meth:`Instrument.predict`: the readings with their exact derivatives with respect to
  the tool point p (world frame [m]) and θ;
* its file header keys (:meth:`Instrument.from_header` / :meth:`Instrument.header`) and
  an optional integer column of ids (``id_column``, e.g. the plane of each contact);
* :meth:`Instrument.typical` (a typical set-up beside a workspace, for simulation and
  analysis), ``default_std`` [m], and :meth:`Instrument.candidate_sphere` (the sphere on
  which its candidate poses lie, if it has one);
* :meth:`Instrument.declared_constants`: the constants its file declares and the fit
  trusts (a sphere's radius, a bar's length scale) with the readings' derivatives, so
  the fit's gauge can say which of them the data cannot check (default: none).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass
from typing import ClassVar, Protocol

import numpy as np

from pincal.errors import MeasurementError

__all__ = ["DeclaredConstant", "HeaderValues", "Instrument", "unit_vector"]


class HeaderValues(Protocol):
    """The header of an instrument file, as the file reader offers it to a kind.

    Lengths come back in metres (the file's ``length_unit`` applied); a missing key
    without a default raises the reader's format error naming the file and the key.
    """

    def has(self, key: str) -> bool:
        """Whether the header gives ``key``."""
        ...

    def length(self, key: str, default: float | None = None) -> float:
        """A length > 0 [m]."""
        ...

    def vector(self, key: str, n: int, default: str | None = None) -> np.ndarray:
        """``n`` finite numbers (unitless)."""
        ...

    def vectors(self, key: str, n: int) -> list[np.ndarray]:
        """Every line of a repeatable key, ``n`` finite numbers each."""
        ...


def unit_vector(v: object, what: str) -> tuple[float, float, float]:
    """``v`` normalised to a unit 3-vector.

    Raises:
        MeasurementError: not a finite, non-zero 3-vector.
    """
    arr = np.asarray(v, dtype=float).reshape(-1)
    norm = float(np.linalg.norm(arr)) if arr.size == 3 else 0.0
    if arr.size != 3 or not np.all(np.isfinite(arr)) or norm < 1e-12:
        raise MeasurementError(f"{what} must be a non-zero 3-vector, got {v!r}")
    return tuple(float(x) for x in arr / norm)  # type: ignore[return-value]


@dataclass(frozen=True)
class DeclaredConstant:
    """A constant an instrument file declares and the joint fit trusts (does not fit).

    An error δ of it changes the readings by ``derivative · δ``; what the fitted
    machine cannot absorb of that is the data's information on it, and the gauge names
    it when its 1σ exceeds a share of ``value``
    (:data:`pincal.identification.SCALE_STD_LIMIT`).

    Attributes:
        name: what it is, in words, as the gauge line starts (``"the sphere radius"``).
        value: its declared value [unit], ≠ 0 (1 for a relative scale).
        unit: ``"m"`` or ``"1"`` (a relative scale of the readings: a 1σ in %).
        derivative: (m,) ∂v/∂constant per reading [m / unit].
        error: what an error of it is, in words (``"a radius error"``).
        rests_on: what the calibrated machine then rests on, in words.
    """

    name: str
    value: float
    unit: str
    derivative: np.ndarray
    error: str
    rests_on: str

    def __post_init__(self) -> None:
        if self.unit not in ("m", "1") or not (np.isfinite(self.value) and self.value != 0):
            raise MeasurementError(
                f"declared constant {self.name!r}: unit must be 'm' or '1' (a relative "
                f"scale) and its value finite and ≠ 0, got {self.value!r} {self.unit!r}"
            )


class Instrument(ABC):
    """A scalar instrument: one reading ``v(p, θ)`` [m] per pose of the tool point p.

    Subclasses are frozen dataclasses whose first field is ``std`` (1σ of one reading
    [m], > 0; checked by :meth:`_check_std` in their ``__post_init__``).
    """

    #: the kind's name in files (``# kind: …``) and on the command line
    kind: ClassVar[str]
    #: one line of words: what it measures
    description: ClassVar[str] = ""
    #: 1σ of one reading a typical instrument of this kind has [m]
    default_std: ClassVar[float] = 1e-6
    #: name of an integer column of ids the kind reads per row (e.g. ``"plane"``), or None
    id_column: ClassVar[str | None] = None
    #: its readings change at most as fast as the tool point moves (``|∂v/∂p| ≤ 1``):
    #: the gate's unit check bounds their spread by the tool points'
    unit_gradient: ClassVar[bool] = True

    std: float

    def _check_std(self) -> None:
        if not (np.isfinite(self.std) and self.std > 0):
            raise MeasurementError(f"instrument std must be finite and > 0 [m], got {self.std}")

    # -- own unknowns ---------------------------------------------------------------
    @property
    @abstractmethod
    def parameter_names(self) -> tuple[str, ...]:
        """Names of θ, in order."""

    @property
    def parameter_units(self) -> tuple[str, ...]:
        """``"m"`` / ``"rad"`` per θ entry (default: all lengths)."""
        return ("m",) * len(self.parameter_names)

    @abstractmethod
    def start(
        self, P: np.ndarray, v: np.ndarray, ids: np.ndarray | None
    ) -> tuple[Instrument, np.ndarray]:
        """Start values θ0 from readings ``v`` (m,) at nominal tool points P (m, 3) [m].

        Returns:
            (the instrument with any reference geometry filled in, θ0 (k,)).
        """

    # -- the model -------------------------------------------------------------------
    @abstractmethod
    def _predict(
        self, P: np.ndarray, theta: np.ndarray, ids: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`predict` on checked arguments."""

    def predict(
        self, P: np.ndarray, theta: np.ndarray, ids: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Readings at tool positions and their exact derivatives.

        Args:
            P: (m, 3) tool positions [m] (world frame).
            theta: (k,) instrument parameters (see :attr:`parameter_names`).
            ids: (m,) integer ids of the kind's :attr:`id_column` (None: all 0).

        Returns:
            v (m,) readings [m], dv/dp (m, 3), dv/dθ (m, k).

        Raises:
            MeasurementError: wrong shapes, ids out of range.
        """
        P = np.atleast_2d(np.asarray(P, dtype=float))
        theta = np.asarray(theta, dtype=float).reshape(-1)
        if P.ndim != 2 or P.shape[1] != 3:
            raise MeasurementError(f"tool positions must be (m, 3), got {P.shape}")
        if theta.size != len(self.parameter_names):
            raise MeasurementError(
                f"{self.kind} instrument has {len(self.parameter_names)} parameters "
                f"{self.parameter_names}, got {theta.size} values"
            )
        return self._predict(P, theta, self.check_ids(ids, len(P)))

    @property
    def n_ids(self) -> int:
        """How many ids of the :attr:`id_column` its parameters describe (1 without one)."""
        return 1

    def check_ids(self, ids: object, m: int) -> np.ndarray | None:
        """(m,) integer ids ≥ 0 of the :attr:`id_column` (None for a kind without one).

        Raises:
            MeasurementError: ids given to a kind without an id column, or not one
                integer ≥ 0 per row.
        """
        if self.id_column is None:
            if ids is not None:
                raise MeasurementError(f"the {self.kind} kind reads no ids per row")
            return None
        a = np.zeros(m, dtype=int) if ids is None else np.asarray(ids)
        if a.shape != (m,) or not np.all(a == np.round(a)) or (a.size and a.min() < 0):
            raise MeasurementError(f"{self.id_column} ids must be one integer ≥ 0 per reading")
        return a.astype(int)

    # -- files ----------------------------------------------------------------------
    @classmethod
    def from_header(cls, std: float, header: HeaderValues) -> Instrument:
        """The instrument from its file header (``std`` [m] already read)."""
        return cls(std)  # type: ignore[call-arg]

    def header(self, length: Callable[[float], str], number: Callable[[float], str]) -> list[str]:
        """The kind's own header lines (``"key: value"``).

        ``length`` formats a length [m] in the file's unit, ``number`` a unitless number.
        """
        return []

    # -- set-ups ----------------------------------------------------------------------
    @classmethod
    @abstractmethod
    def typical(
        cls, P: np.ndarray, std: float | None = None
    ) -> tuple[Instrument, np.ndarray, np.ndarray | None]:
        """A typical set-up beside tool positions P (m, 3) [m].

        Returns:
            (instrument, true θ (k,), ids (m,) or None).
        """

    def declared_constants(
        self, P: np.ndarray, theta: np.ndarray, ids: np.ndarray | None = None
    ) -> tuple[DeclaredConstant, ...]:
        """The constants its file declares and the fit trusts, at tool positions P.

        Args:
            P: (m, 3) tool positions [m].
            theta: (k,) its parameters.
            ids: (m,) ids of its :attr:`id_column`, as :meth:`predict`.

        Returns:
            One :class:`DeclaredConstant` per constant (default: none), each with the
            (m,) derivative of the readings.
        """
        return ()

    def candidate_sphere(
        self, theta: np.ndarray, home: np.ndarray
    ) -> tuple[np.ndarray, float] | None:
        """(centre (3,) [m], radius [m]) of the sphere its candidate poses lie on, or None.

        None: its candidates are random workspace poses. ``home``: the home tool point [m].
        """
        return None

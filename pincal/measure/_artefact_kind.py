"""The interface of an artefact instrument: k residuals per pose of the measured frame.

An artefact kind (a ball seated in the sockets of a plate, a ball in a fixed nest, …)
is one subclass of :class:`Artefact` — the dataset class of the kind, a frozen
dataclass — registered by name with :func:`pincal.measure.add_instrument_kind`, the
same registry as the scalar kinds. The joint identification
(:class:`pincal.identification.InstrumentProblem`) asks the class, never the kind's
name. A kind declares:

* ``kind`` (its name), ``description`` (words), ``dim`` (residuals per pose, k);
* the poses: ``q_act``, ``actuated``, ``frame`` (as every dataset) and :attr:`sigma`;
* its own unknowns (one dataset's): :attr:`Artefact.parameter_names` /
  ``parameter_units`` and their start values (:meth:`Artefact.start`);
* unknowns shared with the other datasets of the kind: :attr:`Artefact.shared_names`
  (equal names are one unknown, e.g. the socket centres of one plate), and the terms
  of the group (:meth:`Artefact.shared_terms`: the shared unknowns' order and start
  values, residuals that tie them alone, e.g. a plate's known distances, and what no
  measurement fixes);
* :meth:`Artefact.residuals`: ``reference − model`` with exact derivatives with
  respect to the measured frame's position p (world [m]), its local rotation ω [rad],
  the own and the shared unknowns.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Sequence
from typing import ClassVar

import numpy as np

from pincal.errors import MeasurementError

__all__ = ["Artefact", "SharedTerms"]


class Artefact(ABC):
    """A dataset of an artefact instrument: ``dim`` residuals per pose (m poses).

    Subclasses are frozen dataclasses with (at least) the attributes ``q_act`` (m, n_act)
    actuator values [m, rad], ``actuated`` (joint names) and ``frame`` (the measured
    frame).
    """

    #: the kind's name (registry, command line, default labels)
    kind: ClassVar[str]
    #: one line of words: what it measures
    description: ClassVar[str] = ""
    #: residuals per pose
    dim: ClassVar[int] = 3

    q_act: np.ndarray
    actuated: tuple[str, ...]
    frame: str

    @abstractmethod
    def __len__(self) -> int:
        """The number of poses m."""

    # -- noise and unknowns ---------------------------------------------------------
    @property
    @abstractmethod
    def sigma(self) -> np.ndarray:
        """(m, dim) 1σ of the residuals [m, rad]."""

    @property
    def parameter_names(self) -> tuple[str, ...]:
        """Names of this dataset's own unknowns θ, in order (default: none)."""
        return ()

    @property
    def parameter_units(self) -> tuple[str, ...]:
        """``"m"`` / ``"rad"`` per θ entry (default: all lengths)."""
        return ("m",) * len(self.parameter_names)

    @property
    def shared_names(self) -> tuple[str, ...]:
        """Names of the shared unknowns φ this dataset reads, in its own order.

        Equal names in several datasets of the kind are one unknown (default: none).
        """
        return ()

    def start(self, P: np.ndarray, Rs: np.ndarray) -> np.ndarray:
        """Start values θ0 (k,) from the nominal poses: P (m, 3) [m], Rs (m, 3, 3)."""
        return np.zeros(len(self.parameter_names))

    # -- the model -------------------------------------------------------------------
    @abstractmethod
    def residuals(
        self, P: np.ndarray, Rs: np.ndarray, theta: np.ndarray, phi: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Residuals ``reference − model`` and their exact derivatives.

        Args:
            P: (m, 3) positions of the measured frame [m] (world).
            Rs: (m, 3, 3) its orientations.
            theta: (k,) own unknowns (:attr:`parameter_names`).
            phi: (s,) shared unknowns in the order of :attr:`shared_names`.

        Returns:
            r (m, dim); ∂r/∂p (m, dim, 3); ∂r/∂ω (m, dim, 3), ω a rotation of the frame
            in its own axes (``R → R·exp(ω)``); ∂r/∂θ (m, dim, k); ∂r/∂φ (m, dim, s).
        """

    # -- the group of datasets of one kind -------------------------------------------
    @classmethod
    def shared_terms(cls, datasets: Sequence[Artefact]) -> SharedTerms:
        """The shared unknowns of the kind's datasets of one problem, and their terms.

        Default :class:`SharedTerms`: the shared names in order of first appearance,
        started at 0, no residuals of their own.
        """
        return SharedTerms(datasets)


class SharedTerms:
    """The unknowns shared by the datasets of one artefact kind in one problem.

    Args:
        datasets: the datasets of the kind (in the problem's order).

    Attributes:
        names: the shared unknowns, in column order; units: ``"m"`` / ``"rad"`` each.
        sigma: (d, 1) 1σ of the group's own residuals (:meth:`residuals`), or None.
    """

    def __init__(self, datasets: Sequence[Artefact]) -> None:
        self.datasets = list(datasets)
        self.names: tuple[str, ...] = tuple(
            dict.fromkeys(n for d in self.datasets for n in d.shared_names)
        )
        self.units: tuple[str, ...] = ("m",) * len(self.names)
        self.sigma: np.ndarray | None = None

    def index(self, d: Artefact) -> np.ndarray:
        """(s,) positions in :attr:`names` of the shared names of dataset ``d``.

        Raises:
            MeasurementError: ``d`` reads a shared name the terms do not have.
        """
        where = {n: i for i, n in enumerate(self.names)}
        missing = [n for n in d.shared_names if n not in where]
        if missing:
            raise MeasurementError(
                f"artefact kind {d.kind!r}: shared unknowns {missing} of a dataset are not "
                f"among the terms' names {list(self.names)}"
            )
        return np.array([where[n] for n in d.shared_names], dtype=int)

    def start(
        self, poses: Sequence[tuple[np.ndarray, np.ndarray]], thetas: Sequence[np.ndarray]
    ) -> np.ndarray:
        """Start values of the shared unknowns (len(names),).

        Args:
            poses: per dataset its nominal (P (m, 3) [m], Rs (m, 3, 3)).
            thetas: per dataset the start values of its own unknowns.
        """
        return np.zeros(len(self.names))

    def residuals(self, phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The group's own residuals (d,) [m] and their derivatives (d, len(names)).

        Only called when :attr:`sigma` is not None.
        """
        return np.zeros(0), np.zeros((0, len(self.names)))

    def warnings(self, alone: bool) -> tuple[str, ...]:
        """What no measurement fixes, in words.

        Args:
            alone: every dataset of the problem is of this kind.
        """
        return ()

    def points(self, phi: np.ndarray) -> dict[str, np.ndarray]:
        """Named 3-D points [m] the shared unknowns describe (reported; default none)."""
        return {}

"""The residual model every fit runs on, declared as a protocol.

A residual model maps the vector x of its unknowns to whitened residuals and their
analytic Jacobian. Its first :attr:`ResidualModel.n_machine` unknowns are the machine's
parameters, shared by every data set; the others are the data sets' own unknowns
(an instrument's pivot, a socket centre). Three classes satisfy it: the batched
:class:`pincal.identification.CalibrationProblem` of one pose file (no own unknowns),
its stacked form for several markers, and the joint
:class:`pincal.identification.InstrumentProblem` of several data sets. The solvers, the
driver (:mod:`pincal.identification.solvers._driver`) and the finishing step
(:mod:`pincal.identification.solvers._finish`) use only what is declared here.

The typing of ``evaluate`` (the Jacobian is an array when asked for, None when not) is
declared once, in :class:`Evaluates`: the three classes subclass it, implement
:meth:`Evaluates.residuals` and inherit ``evaluate``.
"""

from __future__ import annotations

from typing import Literal, Protocol, TypeVar, overload

import numpy as np

from pincal.model import Mechanism

__all__ = ["Evaluates", "RawResiduals", "ResidualModel"]

#: raw (unwhitened) residuals ``measured − model`` [m, rad]: (m, k) for one data set, or
#: one (m_i, k_i) array per data set of a joint fit
RawResiduals = np.ndarray | list[np.ndarray]

#: the raw residuals of one kind of residual model
RawT_co = TypeVar("RawT_co", bound=RawResiduals, covariant=True)


class Evaluates(Protocol[RawT_co]):
    """Whitened residuals and their Jacobian at a vector of unknowns, typed once.

    A residual model subclasses ``Evaluates[its raw residuals' type]``, implements
    :meth:`residuals` and inherits :meth:`evaluate`, whose overloads tell the type
    checker that the Jacobian is an array when asked for and None when not.
    """

    def residuals(
        self, values: np.ndarray, jacobian: bool
    ) -> tuple[np.ndarray, np.ndarray | None, RawT_co]:
        """(N,) whitened residuals, (N, n_x) their Jacobian (None if not asked), raw residuals.

        Args:
            values: (n_x,) the unknowns [SI: m, rad, or a term's own unit].
            jacobian: whether to compute the Jacobian.
        """
        ...

    @overload
    def evaluate(
        self, values: np.ndarray, jacobian: Literal[True] = True
    ) -> tuple[np.ndarray, np.ndarray, RawT_co]: ...

    @overload
    def evaluate(
        self, values: np.ndarray, jacobian: Literal[False]
    ) -> tuple[np.ndarray, None, RawT_co]: ...

    @overload
    def evaluate(
        self, values: np.ndarray, jacobian: bool
    ) -> tuple[np.ndarray, np.ndarray | None, RawT_co]: ...

    def evaluate(
        self, values: np.ndarray, jacobian: bool = True
    ) -> tuple[np.ndarray, np.ndarray | None, RawT_co]:
        """(N,) whitened residuals, (N, n_x) their Jacobian (None if not asked), raw residuals.

        The raw residuals are ``measured − model`` [m, rad] (:data:`RawResiduals`); see
        :meth:`residuals`, which this calls.
        """
        return self.residuals(values, jacobian)


class ResidualModel(Evaluates[RawResiduals], Protocol):
    """Whitened residuals of measurements in a vector of unknowns.

    Attributes:
        mech: the nominal mechanism the unknowns displace.
        names: the unknowns' names, machine parameters first.
        units: per unknown ``"m"`` or ``"rad"``.
        n_machine: the number of machine parameters (the shared unknowns, first in x).
        n_equations: N, the number of whitened residuals.
        known_noise: True when the whitening is the declared (or settled) noise, so the
            covariance is not scaled by χ²/ν.
        solver_floor_cost: cost ½‖r‖² of residuals at the kinematic solver's precision
            (below it, the data are fitted exactly).
        sigma: the σ whitening the residuals [m, rad] (an array, or one per data set).
    """

    mech: Mechanism

    @property
    def names(self) -> tuple[str, ...]:
        """The unknowns' names (n_x,): machine parameters first, then own unknowns."""
        ...

    @property
    def units(self) -> tuple[str, ...]:
        """The unknowns' units (n_x,): 'm', 'rad' or the term's own unit."""
        ...

    @property
    def n_machine(self) -> int:
        """How many of the unknowns are machine parameters (the leading ones)."""
        ...

    @property
    def n_equations(self) -> int:
        """Scalar measurement equations N (the residual vector's length)."""
        ...

    @property
    def known_noise(self) -> bool:
        """Whether ``sigma`` holds the noise (declared or per-pose), not an estimate."""
        ...

    @property
    def solver_floor_cost(self) -> float:
        """Cost of residuals at the kinematic solver's floor: below it, data fit exactly."""
        ...

    @property
    def sigma(self) -> np.ndarray | list[np.ndarray]:
        """The residuals' standard deviations [m, rad]: (m, k), or one (m_i, k_i) per data set."""
        ...

    def cost(self, values: np.ndarray) -> float:
        """½‖r‖² at ``values``."""
        ...

    def mechanism(self, values: np.ndarray) -> Mechanism:
        """The mechanism with the machine part of ``values`` applied."""
        ...

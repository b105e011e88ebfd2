"""The residual model every fit runs on, declared as a protocol.

A residual model maps the vector x of its unknowns to whitened residuals and their
analytic Jacobian. Its first :attr:`ResidualModel.n_machine` unknowns are the machine's
parameters, shared by every data set; the others are the data sets' own unknowns
(an instrument's pivot, a socket centre). Three classes satisfy it: the batched
:class:`pincal.identification.CalibrationProblem` of one pose file (no own unknowns),
its stacked form for several markers, and the joint
:class:`pincal.identification.InstrumentProblem` of several data sets. The solvers, the
driver (:mod:`pincal.identification._driver`) and the finishing step
(:mod:`pincal.identification._finish`) use only what is declared here.
"""

from __future__ import annotations

from typing import Literal, Protocol, overload

import numpy as np

from pincal.model import Mechanism

__all__ = ["RawResiduals", "ResidualModel"]

#: raw (unwhitened) residuals ``measured − model`` [m, rad]: (m, k) for one data set, or
#: one (m_i, k_i) array per data set of a joint fit
RawResiduals = np.ndarray | list[np.ndarray]


class ResidualModel(Protocol):
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

    @overload
    def evaluate(
        self, values: np.ndarray, jacobian: Literal[True] = True
    ) -> tuple[np.ndarray, np.ndarray, RawResiduals]: ...

    @overload
    def evaluate(
        self, values: np.ndarray, jacobian: Literal[False]
    ) -> tuple[np.ndarray, None, RawResiduals]: ...

    @overload
    def evaluate(
        self, values: np.ndarray, jacobian: bool
    ) -> tuple[np.ndarray, np.ndarray | None, RawResiduals]: ...

    def evaluate(
        self, values: np.ndarray, jacobian: bool = True
    ) -> tuple[np.ndarray, np.ndarray | None, RawResiduals]:
        """(N,) whitened residuals, (N, n_x) their Jacobian (None if not asked), raw residuals."""
        ...

    def cost(self, values: np.ndarray) -> float:
        """½‖r‖² at ``values``."""
        ...

    def mechanism(self, values: np.ndarray) -> Mechanism:
        """The mechanism with the machine part of ``values`` applied."""
        ...

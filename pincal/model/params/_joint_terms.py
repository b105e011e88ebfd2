"""Joint-space error terms: errors that change the actuated joint values before kinematics.

A joint term models what a rigid geometry cannot: the actual joint value is
``q_i' = q_i + δq_i(q, θ)`` with ``δq_i = B_i(q) · θ_i`` linear in the term's
parameters θ_i (one small vector per actuated joint; a term on other joints — a
strut's length, :mod:`pincal.model.params._term_strut` — moves every actuator its change acts
through, :meth:`JointTerm.columns`). Each kind of term is one
:class:`JointTerm` subclass in its own module, registered here with
:func:`register_term`; its parameters are ordinary entries of a
:class:`pincal.model.ParameterSet` named ``<joint>.<dof>`` (e.g.
``shoulder_lift_joint.compliance``) with a zero origin twist, so rank analysis,
identification and reports treat them like the geometric parameters.

The basis ``B`` is evaluated at the commanded joint values on the nominal mechanism
(e.g. an encoder gain's), which makes ``δq`` exactly linear in θ. A load-dependent term
(``loaded``: a compliance) is evaluated by the identification on the current estimate's
geometry at the deflected joint values instead (:mod:`pincal.model.params._deflection`).

A term may also need per-pose conditions besides the joint values (``needs``, e.g.
the temperature of :mod:`pincal.model.params._term_temperature`), and may move the measured
frame directly instead of (or besides) the joints: :meth:`JointTerm.shift`, a world
position change ``δp = S · θ`` linear in θ, evaluated on the nominal mechanism too.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from pincal.errors import ParameterError

if TYPE_CHECKING:
    from pincal.model._mechanism import Mechanism

__all__ = [
    "JointTerm",
    "joint_term",
    "joint_term_units",
    "register_term",
    "term_kinds",
    "term_of_dof",
]


class JointTerm(ABC):
    """One kind of joint-space error term (a class per kind, one module each).

    Class attributes:
        kind: name used in ``--model geometric+<kind>`` (e.g. ``"compliance"``).
        dofs: parameter suffixes, one per basis column (``<joint>.<dof>``).
        prior: default 1σ of each parameter, in its SI unit.
    """

    kind: ClassVar[str]
    dofs: ClassVar[tuple[str, ...]]
    prior: ClassVar[float]
    #: per-pose conditions the term needs (``Measurements`` fields, e.g. ``"temperature"``)
    needs: ClassVar[tuple[str, ...]] = ()
    #: a load-dependent term (compliance): the identification evaluates its basis on the
    #: current estimate's geometry at the deflected joint values
    #: (:mod:`pincal.model.params._deflection`), not on the nominal one at the command
    loaded: ClassVar[bool] = False

    @abstractmethod
    def unit(self, joint_type: str) -> str:
        """SI unit of the parameters on a joint of URDF type ``joint_type``."""

    def check(self, mech: Mechanism, joint: str) -> None:
        """Raise :class:`ParameterError` when the term does not apply to ``joint``.

        The default: any actuated joint.
        """
        if joint not in mech.actuated:
            raise ParameterError(
                f"{self.kind} terms act on actuated joints; {joint!r} is not one of "
                f"{list(mech.actuated)}"
            )

    #: what the term sits on, for messages (a term on other joints overrides it)
    sits_on: ClassVar[str] = "actuated joint"

    def joints(self, mech: Mechanism) -> tuple[str, ...]:
        """Joints the term may sit on (default: the actuated ones; :meth:`check` decides)."""
        return tuple(mech.actuated)

    @abstractmethod
    def basis(self, mech: Mechanism, q_act: np.ndarray) -> np.ndarray:
        """Basis of δq at commanded joint values.

        Args:
            mech: the nominal mechanism.
            q_act: (m, n_act) commanded actuated joint values [rad, m].

        Returns:
            (m, n_act, len(dofs)): ``δq[:, a] = B[:, a, :] @ θ_a`` [rad, m].
        """

    def basis_at(
        self, mech: Mechanism, q_act: np.ndarray, conditions: Mapping[str, np.ndarray | None]
    ) -> np.ndarray:
        """:meth:`basis` with the per-pose ``conditions`` ({name in ``needs``: (m,)})."""
        return self.basis(mech, q_act)

    def shift(
        self, mech: Mechanism, q_act: np.ndarray, conditions: Mapping[str, np.ndarray | None]
    ) -> np.ndarray | None:
        """World position change of the measured frame, or None for a joint-space term.

        Returns:
            (m, n_act, 3, len(dofs)): ``δp = Σ_a S[:, a] @ θ_a`` [m per parameter unit].
        """
        return None

    def check_data(self, conditions: Mapping[str, np.ndarray | None]) -> None:
        """Raise when measured ``conditions`` cannot identify the term (default: fine)."""
        del conditions  # nothing to check for a term that needs no conditions

    def columns(
        self,
        mech: Mechanism,
        q_act: np.ndarray,
        conditions: Mapping[str, np.ndarray | None],
        joints: tuple[str, ...] | None = None,
    ) -> dict[str, np.ndarray]:
        """Basis per joint the term sits on: {joint: (m, n_act, len(dofs))}.

        ``δq += columns[joint] @ θ_joint`` over all actuated joints [rad, m]. The
        default places :meth:`basis_at` of each actuated joint on that joint alone; a
        term on other joints (a strut's length, :mod:`pincal.model.params._term_strut`) moves
        every actuator the joint's change acts through. ``joints``: the joints asked for
        (None: all; a term may return more).
        """
        del joints  # every actuated joint's column costs the same basis
        B = self.basis_at(mech, q_act, conditions)
        out = {}
        for i, a in enumerate(mech.actuated):
            col = np.zeros(B.shape)
            col[:, i, :] = B[:, i, :]
            out[a] = col
        return out

    def deflected(
        self, mech: Mechanism, joints: tuple[str, ...], theta: np.ndarray, u: np.ndarray
    ) -> np.ndarray | None:
        """The loaded joint values (m, n_act) when this kind is the only loaded one.

        None (the default): the generic fixed point ``q = u + L(q) θ`` of
        :mod:`pincal.model.params._deflection` on the term's columns. A term whose load
        acts on another machine than the rigid one its columns move (a strut's,
        lengthened) solves it exactly here.

        Args:
            mech: the machine at the current geometry.
            joints: the joints of ``theta``'s parameters (one per parameter).
            theta: (k,) the term's values [SI].
            u: (m, n_act) the command moved by the terms that are not loaded [rad, m].
        """
        del mech, joints, theta, u  # the generic fixed point
        return None

    def commands(
        self, mech: Mechanism, joints: tuple[str, ...], theta: np.ndarray, q: np.ndarray
    ) -> np.ndarray | None:
        """The inverse of :meth:`deflected`: commands (m, n_act) reaching joint values ``q``.

        None (the default): ``u = q − L(q) θ``, exact for the generic fixed point.
        """
        del mech, joints, theta, q
        return None


_TERMS: dict[str, JointTerm] = {}


def register_term(term: JointTerm) -> None:
    """Make a term kind available to presets, ``--model`` and the parameter sets."""
    clash = [d for d in term.dofs if d in _by_dof() and _by_dof()[d].kind != term.kind]
    if clash:
        raise ParameterError(f"joint term {term.kind!r}: dofs {clash} are already taken")
    _TERMS[term.kind] = term


def _by_dof() -> dict[str, JointTerm]:
    return {d: t for t in _TERMS.values() for d in t.dofs}


def term_of_dof(dof: str) -> JointTerm | None:
    """The term owning parameter suffix ``dof`` (None for a geometric dof)."""
    return _by_dof().get(dof)


def term_kinds() -> tuple[str, ...]:
    """Registered term kinds, in registration order."""
    return tuple(_TERMS)


def joint_term(kind: str) -> JointTerm:
    """The registered term of a kind.

    Raises:
        ParameterError: unknown kind (the valid ones listed).
    """
    if kind not in _TERMS:
        raise ParameterError(
            f"unknown error-model term {kind!r}; valid: geometric, {', '.join(_TERMS)}"
        )
    return _TERMS[kind]


def joint_term_units() -> frozenset[str]:
    """Every unit a registered joint term's parameters can have (e.g. ``"rad/(N·m)"``)."""
    return frozenset(t.unit(k) for t in _TERMS.values() for k in ("revolute", "prismatic"))

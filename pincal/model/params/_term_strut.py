"""Axial compliance of fixed-length struts under static load: ``δL_j = c_j · F_j``.

A hexaslide's struts — fixed-length links between a U-joint on an actuated carriage
and a ball joint on the platform — are not actuated, so their load is not an actuator
force (:mod:`pincal.model.params._term_compliance`): it comes from the loop-closure
forces ``F_j`` [N] (:mod:`pincal.model.params._strut_statics`; ``F_j > 0`` compresses
the strut). A strut of axial stiffness ``k`` has ``c_j = −1/k`` [m/N] (the convention of
the actuators' compliance); a payload (:func:`pincal.model.with_payload`) is part of
the load.

* **Deflection** (:meth:`StrutCompliance.deflected`): exact. The struts are lengthened
  by the fixed point ``δL = c ∘ F`` of the lengthened machine, actuators at the
  command, and the pose is returned as the rigid machine's actuator values reaching it
  (:mod:`pincal.model.params._strut_elongation`).
* **Columns** (:meth:`StrutCompliance.columns`, the Jacobian): first order. The
  elongation enters as the actuator change ``e_j F_j`` per unit compliance, with
  ``e_j = ∂q_act/∂L_j`` and ``F_j`` on the rigid machine at the joints reached (carriages
  moved, struts at ℓ). Its strut directions differ from the lengthened machine's by
  ~``e·δL/ℓ``: a 0.4 % force error at 0.5 mm of sag on the hexaslide, a column error
  of that relative size (tests/studies/test_deflection_truths.py).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from pincal.errors import ParameterError
from pincal.model.params._joint_terms import JointTerm, register_term
from pincal.model.params._strut_elongation import elongated_joints, elongation_commands
from pincal.model.params._strut_statics import (
    link_masses,
    pose_loads,
    strut_loads,
    struts,
)
from pincal.model.params._term_compliance import gravity_model, held_once
from pincal.model.reach import sample_actuators

if TYPE_CHECKING:
    from pincal.model._mechanism import Mechanism

__all__ = ["StrutCompliance"]


class StrutCompliance(JointTerm):
    """Axial compliance of a fixed-length strut [m/N] (1σ prior 1e-7 m/N: 10 µm at 100 N)."""

    kind: ClassVar[str] = "strut-compliance"
    dofs: ClassVar[tuple[str, ...]] = ("strut_compliance",)
    loaded: ClassVar[bool] = True
    prior: ClassVar[float] = 1e-7
    sits_on: ClassVar[str] = "fixed-length strut"

    def unit(self, joint_type: str) -> str:
        return "m/N"

    def joints(self, mech: Mechanism) -> tuple[str, ...]:
        return struts(mech)

    def check(self, mech: Mechanism, joint: str) -> None:
        found = struts(mech)
        if joint not in found:
            what = f"its struts are {list(found)}" if found else "it has none"
            raise ParameterError(
                f"{self.kind} terms act on fixed-length struts (a fixed joint whose origin "
                f"is a link between passive joints closing a loop); {joint!r} of "
                f"{mech.name!r} is not one: {what} (an actuated leg takes 'compliance')"
            )
        if sum(i.mass for i in mech.model.inertias) <= 0:
            raise ParameterError(
                f"model {mech.name!r} has no link masses: a strut compliance under gravity "
                f"needs <inertial> elements in the URDF (or a payload: --payload)"
            )
        held_once(mech)
        masses, model = link_masses(mech), gravity_model(mech)
        pose_loads(mech, model, mech.q_home, (joint,), masses, 0)
        if mech.n_closure_rows > mech.closure_rank:  # redundant loops: home may be special
            rows = sample_actuators(mech, 3, np.random.default_rng(0))
            for k, q in enumerate(mech.configurations(rows)):
                pose_loads(mech, model, q, (joint,), masses, k + 1)

    def basis(self, mech: Mechanism, q_act: np.ndarray) -> np.ndarray:
        raise ParameterError(
            f"{self.kind} sits on struts, not on actuated joints: use columns() or "
            f"pincal.model.joint_term_basis"
        )

    def columns(
        self,
        mech: Mechanism,
        q_act: np.ndarray,
        conditions: Mapping[str, np.ndarray | None],
        joints: tuple[str, ...] | None = None,
    ) -> dict[str, np.ndarray]:
        # only the struts asked for: a parallelogram bar's force is not determined
        names = tuple(j for j in struts(mech) if joints is None or j in joints)
        F, E = strut_loads(mech, q_act, names)
        return {j: (F[:, i, None] * E[:, i])[:, :, None] for i, j in enumerate(names)}

    def deflected(
        self, mech: Mechanism, joints: tuple[str, ...], theta: np.ndarray, u: np.ndarray
    ) -> np.ndarray:
        return elongated_joints(mech, joints, theta, u)

    def commands(
        self, mech: Mechanism, joints: tuple[str, ...], theta: np.ndarray, q: np.ndarray
    ) -> np.ndarray:
        return elongation_commands(mech, joints, theta, q)


register_term(StrutCompliance())

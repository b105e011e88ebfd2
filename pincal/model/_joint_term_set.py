"""Parameter sets with joint terms: building them, and the basis of δq over poses."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from pincal.errors import ParameterError
from pincal.model._joint_terms import joint_term, term_of_dof
from pincal.model._mechanism import Mechanism
from pincal.model._parameters import ParameterSet, origin_parameter
from pincal.model._term_compliance import Compliance
from pincal.model._term_strut import StrutCompliance
from pincal.model._term_transmission import Gain, Harmonics

__all__ = [
    "actual_joint_values",
    "joint_term_basis",
    "joint_term_prior",
    "split_model",
    "with_joint_terms",
]

#: the bundled term kinds (importing their modules registers them)
BUNDLED_TERMS = (Compliance, Gain, Harmonics, StrutCompliance)


def split_model(spec: str) -> tuple[str, ...]:
    """The term kinds of a model spec ``geometric[+kind…]`` (``"geometric"`` → ()).

    Raises:
        ParameterError: a spec not starting with ``geometric``, or an unknown kind.
    """
    parts = [p.strip() for p in str(spec).split("+")]
    if parts[0] != "geometric" or any(not p for p in parts):
        raise ParameterError(
            f"model {spec!r} must read 'geometric' or 'geometric+<term>[+<term>…]', e.g. "
            f"geometric+compliance"
        )
    kinds = tuple(dict.fromkeys(parts[1:]))
    for k in kinds:
        joint_term(k)
    return kinds


def with_joint_terms(mech: Mechanism, params: ParameterSet, kinds: Sequence[str]) -> ParameterSet:
    """``params`` followed by the terms ``kinds`` on every actuated joint they apply to.

    A joint a term does not apply to (a prismatic joint for harmonics) is skipped; a
    term that applies to no joint at all is an error, as is a mechanism the term
    cannot model (compliance of a closed loop).

    Raises:
        ParameterError: an unknown kind, or a kind that applies to no actuated joint.
    """
    names = list(params.names)
    for kind in kinds:
        term = joint_term(kind)
        fits, why = [], ""
        for a in term.joints(mech):
            try:
                term.check(mech, a)
            except ParameterError as exc:
                why = str(exc)
                continue
            fits += [f"{a}.{d}" for d in term.dofs if f"{a}.{d}" not in names]
        if not fits and not any(term_of_dof(n.rpartition(".")[2]) is term for n in names):
            raise ParameterError(
                f"no {term.sits_on} of {mech.name!r} takes a {kind} term{': ' if why else ''}{why}"
            )
        names += fits
    if len(names) == len(params):
        return params
    extra = [origin_parameter(mech, *n.rsplit(".", 1)) for n in names[len(params) :]]
    label = "+".join([params.label, *kinds])
    return ParameterSet([*params.parameters, *extra], label)


def joint_term_basis(mech: Mechanism, params: ParameterSet, q_act: np.ndarray) -> np.ndarray:
    """Basis ``B`` (m, n_act, n) of the joint changes: ``δq = B @ values`` [rad, m].

    Columns of geometric parameters are zero. ``q_act`` (m, n_act) are the commanded
    actuated values; ``mech`` the nominal mechanism the terms are evaluated on.
    """
    q_act = np.atleast_2d(np.asarray(q_act, dtype=float))
    B = np.zeros((q_act.shape[0], len(mech.actuated), len(params)))
    cache: dict[str, dict[str, np.ndarray]] = {}
    for k in params.joint_terms:
        p = params.parameters[k]
        term = term_of_dof(p.dof)
        assert term is not None
        if term.kind not in cache:
            cache[term.kind] = term.columns(mech, q_act)
        if p.joint not in cache[term.kind]:
            raise ParameterError(
                f"joint term {p.name!r} is on a joint that is not a {term.sits_on} of "
                f"{mech.name!r}"
            )
        B[:, :, k] = cache[term.kind][p.joint][:, :, term.dofs.index(p.dof)]
    return B


def joint_term_prior(params: ParameterSet) -> np.ndarray:
    """(n,) default 1σ of the joint-term parameters [their SI unit]; NaN for geometric ones."""
    out = np.full(len(params), np.nan)
    for k in params.joint_terms:
        term = term_of_dof(params.parameters[k].dof)
        assert term is not None
        out[k] = term.prior
    return out


def actual_joint_values(
    mech: Mechanism, params: ParameterSet, values: np.ndarray, q_act: np.ndarray
) -> np.ndarray:
    """The joint values the machine actually takes: ``q + δq`` (m, n_act) [rad, m].

    ``values`` (n,) of ``params``; only its joint terms act (the geometric ones are
    applied to the mechanism by :meth:`ParameterSet.apply`). Used to simulate a
    machine with joint errors: measure ``params.apply(mech, values)`` at these values
    and record the commanded ``q_act``.
    """
    q_act = np.atleast_2d(np.asarray(q_act, dtype=float))
    if not params.joint_terms.size:
        return q_act.copy()
    return q_act + joint_term_basis(mech, params, q_act) @ params.check_values(values)

"""Parameter sets with joint terms: building them, and the basis of δq over poses."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Protocol

import numpy as np

from pincal.errors import ParameterError
from pincal.model._mechanism import Mechanism
from pincal.model.params._joint_terms import joint_term, term_of_dof
from pincal.model.params._parameters import ParameterSet, origin_parameter
from pincal.model.params._term_compliance import Compliance
from pincal.model.params._term_strut import StrutCompliance
from pincal.model.params._term_temperature import Temperature
from pincal.model.params._term_transmission import Gain, Harmonics

__all__ = [
    "Conditions",
    "actual_shift",
    "check_term_data",
    "joint_term_bases",
    "joint_term_basis",
    "joint_term_prior",
    "joint_term_shift",
    "split_model",
    "with_joint_terms",
]

#: the bundled term kinds (importing their modules registers them)
BUNDLED_TERMS = (Compliance, Gain, Harmonics, Temperature, StrutCompliance)

#: per-pose conditions some terms need besides the joint values: {name: (m,) or None},
#: e.g. ``{"temperature": T}`` [°C] (``Measurements.conditions``)
Conditions = Mapping[str, "np.ndarray | None"]


class _Measured(Protocol):
    """What :func:`joint_term_bases` reads of a ``Measurements`` (the measure stage's)."""

    @property
    def q_act(self) -> np.ndarray: ...

    @property
    def conditions(self) -> Conditions: ...


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


def joint_term_basis(
    mech: Mechanism, params: ParameterSet, q_act: np.ndarray, conditions: Conditions | None = None
) -> np.ndarray:
    """Basis ``B`` (m, n_act, n) of the joint changes: ``δq = B @ values`` [rad, m].

    Columns of geometric parameters are zero. ``q_act`` (m, n_act) are the commanded
    actuated values; ``mech`` the nominal mechanism the terms are evaluated on;
    ``conditions`` the per-pose conditions a term needs (e.g. the temperature).

    Raises:
        ConditionError: a term's condition is missing or malformed.
    """
    q_act = np.atleast_2d(np.asarray(q_act, dtype=float))
    B = np.zeros((q_act.shape[0], len(mech.actuated), len(params)))
    terms = {int(k): term_of_dof(params.parameters[k].dof) for k in params.joint_terms}
    wanted: dict[str, tuple[str, ...]] = {}  # kind → the joints its parameters sit on
    for k, term in terms.items():
        assert term is not None
        wanted[term.kind] = (*wanted.get(term.kind, ()), params.parameters[k].joint)
    cache: dict[str, dict[str, np.ndarray]] = {}
    for k, term in terms.items():
        assert term is not None
        p = params.parameters[k]
        if term.kind not in cache:
            cache[term.kind] = term.columns(mech, q_act, conditions or {}, wanted[term.kind])
        if p.joint not in cache[term.kind]:
            raise ParameterError(
                f"joint term {p.name!r} is on a joint that is not a {term.sits_on} of "
                f"{mech.name!r}"
            )
        B[:, :, k] = cache[term.kind][p.joint][:, :, term.dofs.index(p.dof)]
    return B


def joint_term_shift(
    mech: Mechanism, params: ParameterSet, q_act: np.ndarray, conditions: Conditions | None = None
) -> np.ndarray | None:
    """Basis ``S`` (m, 3, n) of the measured frame's world position change ``δp = S @ values``.

    None when no term of ``params`` moves the measured frame directly (the joint-space
    terms); otherwise geometric and joint-space columns are zero. Arguments as for
    :func:`joint_term_basis`.
    """
    q_act = np.atleast_2d(np.asarray(q_act, dtype=float))
    act = {a: i for i, a in enumerate(mech.actuated)}
    cache: dict[str, np.ndarray | None] = {}
    S: np.ndarray | None = None
    for k in params.joint_terms:
        p = params.parameters[k]
        term = term_of_dof(p.dof)
        assert term is not None
        if term.kind not in cache:
            cache[term.kind] = term.shift(mech, q_act, conditions or {})
        part = cache[term.kind]
        if part is None or p.joint not in act:
            continue
        if S is None:
            S = np.zeros((q_act.shape[0], 3, len(params)))
        S[:, :, k] = part[:, act[p.joint], :, term.dofs.index(p.dof)]
    return S


def joint_term_bases(
    mech: Mechanism, params: ParameterSet, measurements: _Measured
) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The bases of an identification: δq (m, n_act, n) and δp (m, 3, n) at the data.

    ``measurements`` gives ``q_act`` (m, n_act) and ``conditions`` (a
    :class:`pincal.measure.Measurements`). (None, None) without joint terms; δp is None
    when no term moves the measured frame.

    Raises:
        ConditionError: data that cannot identify a term (:func:`check_term_data`).
    """
    if not params.joint_terms.size:
        return None, None
    cond, q_act = measurements.conditions, measurements.q_act
    check_term_data(params, cond)
    return (
        joint_term_basis(mech, params, q_act, cond),
        joint_term_shift(mech, params, q_act, cond),
    )


def check_term_data(params: ParameterSet, conditions: Conditions) -> None:
    """Refuse measured ``conditions`` that cannot identify the joint terms of ``params``.

    Raises:
        ConditionError: e.g. a temperature term without a temperature that varies.
    """
    seen = set()
    for k in params.joint_terms:
        term = term_of_dof(params.parameters[k].dof)
        if term is not None and term.kind not in seen:
            seen.add(term.kind)
            term.check_data(conditions)


def joint_term_prior(params: ParameterSet) -> np.ndarray:
    """(n,) default 1σ of the joint-term parameters [their SI unit]; NaN for geometric ones."""
    out = np.full(len(params), np.nan)
    for k in params.joint_terms:
        term = term_of_dof(params.parameters[k].dof)
        assert term is not None
        out[k] = term.prior
    return out


def actual_shift(
    mech: Mechanism,
    params: ParameterSet,
    values: np.ndarray,
    q_act: np.ndarray,
    conditions: Conditions | None = None,
) -> np.ndarray:
    """World position change (m, 3) of the measured frame by the terms [m] (zeros if none)."""
    q_act = np.atleast_2d(np.asarray(q_act, dtype=float))
    S = joint_term_shift(mech, params, q_act, conditions) if params.joint_terms.size else None
    if S is None:
        return np.zeros((q_act.shape[0], 3))
    return S @ params.check_values(values)

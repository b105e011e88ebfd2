"""Geometric parameters: named displacements of URDF joint origins.

Parameter k displaces the origin of URDF joint j along a unit twist ξ_k expressed in
the joint-origin frame. All parameters of one joint act together as
``origin ← origin · exp6(Σ_k δ_k ξ_k)``. The dof ``offset`` is the twist along a
movable joint's axis, i.e. exactly an encoder/prismatic zero offset.

Sets by preset name or entry list are built by :func:`pincal.model.parameters`
(:mod:`pincal.model.params._presets`): ``"full"`` (:func:`full_parameters`, every origin twist),
the sidecar's presets, and computed presets the caller passes as ``computed`` —
:func:`pincal.sensitivity.parameters` (exported as ``pincal.parameters``) passes
``"base"`` (the identifiable base set of ``full`` without its degenerate translations,
see :func:`degenerate_translations`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pincal.errors import ParameterError, UnknownNameError
from pincal.model._mechanism import Mechanism
from pincal.model.params._joint_terms import term_of_dof
from pincal.model.params._linearisation import Linearisation

__all__ = [
    "DOFS",
    "Parameter",
    "ParameterSet",
    "degenerate_translations",
    "full_parameters",
    "origin_dofs",
    "origin_parameter",
]

DOFS: tuple[str, ...] = ("tx", "ty", "tz", "rx", "ry", "rz", "offset")
_UNIT_TWISTS = {d: np.eye(6)[i] for i, d in enumerate(DOFS[:6])}
_EXCLUDED_TYPES = ("floating", "planar")
_REVOLUTE = ("revolute", "continuous")
_ZERO_LENGTH = 1e-12
"""Origin translations up to this norm [m] count as a zero-length link."""


@dataclass(frozen=True, eq=False)
class Parameter:
    """One geometric parameter.

    Attributes:
        name: ``<joint>.<dof>``.
        joint: URDF joint name.
        dof: one of ``tx ty tz rx ry rz offset``, or a joint term's dof
            (:mod:`pincal.model.params._joint_terms`, e.g. ``compliance``).
        twist: (6,) unit twist ``[v; ω]`` in the joint-origin frame (zero for a joint
            term: it does not move the origin).
        unit: ``"m"`` or ``"rad"`` (a joint term: its own, e.g. ``"rad/(N·m)"``).
    """

    name: str
    joint: str
    dof: str
    twist: np.ndarray
    unit: str

    def __post_init__(self) -> None:
        twist = np.array(self.twist, dtype=float)  # own read-only copy: hashing stays valid
        twist.setflags(write=False)
        object.__setattr__(self, "twist", twist)

    def _key(self) -> tuple:
        return (self.name, self.joint, self.dof, self.unit, tuple(self.twist.tolist()))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Parameter):
            return NotImplemented
        return self._key() == other._key()

    def __hash__(self) -> int:
        return hash(self._key())


class ParameterSet:
    """An ordered set of parameters of one mechanism.

    Attributes:
        parameters: tuple of :class:`Parameter`.
        names: parameter names, in order.
        units: ``"m"``/``"rad"`` per parameter.
        joints: URDF joints whose origins are touched, in first-use order.
        joint_terms: indices of the joint-term parameters (not geometric).
    """

    def __init__(self, parameters: Sequence[Parameter], label: str = "custom"):
        names = [p.name for p in parameters]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ParameterError(f"parameter set lists {dup} more than once")
        if not parameters:
            raise ParameterError("a parameter set needs at least one parameter")
        self.parameters = tuple(parameters)
        self.label = label
        self.names = tuple(names)
        self.units = tuple(p.unit for p in parameters)
        joints: dict[str, list[int]] = {}
        terms = []
        for k, p in enumerate(parameters):
            if term_of_dof(p.dof) is not None:
                terms.append(k)
            else:
                joints.setdefault(p.joint, []).append(k)
        self.joint_terms = np.array(terms, dtype=int)
        self.joints = tuple(joints)
        self._cols = {j: np.array(c) for j, c in joints.items()}
        self._twists = {
            j: np.stack([parameters[k].twist for k in c], axis=1) for j, c in joints.items()
        }

    def __len__(self) -> int:
        return len(self.parameters)

    def __repr__(self) -> str:
        return f"ParameterSet({self.label!r}, {len(self)} parameters)"

    def __eq__(self, other: object) -> bool:
        """Same parameters in the same order (the label is not compared)."""
        if not isinstance(other, ParameterSet):
            return NotImplemented
        return self.parameters == other.parameters

    def __hash__(self) -> int:
        return hash(self.parameters)

    def index(self, name: str) -> int:
        """Position of the parameter called ``name`` (UnknownNameError lists the names)."""
        if name not in self.names:
            raise UnknownNameError("parameter", name, self.names)
        return self.names.index(name)

    def subset(self, indices: Sequence[int] | np.ndarray, label: str | None = None) -> ParameterSet:
        """A new set with the parameters at ``indices`` (in that order)."""
        n = len(self)
        try:
            picked = [int(i) for i in indices]
        except (TypeError, ValueError) as exc:
            raise ParameterError(f"subset indices must be integers: {exc}") from exc
        bad = [i for i in picked if not -n <= i < n]
        if bad:
            raise ParameterError(f"subset indices {bad} out of range for {n} parameters")
        return ParameterSet([self.parameters[i] for i in picked], label or self.label)

    def check_values(self, values: np.ndarray | None) -> np.ndarray:
        """Values as a finite float (n,) array (None → zeros), else ParameterError."""
        if values is None:
            return np.zeros(len(self))
        try:
            values = np.asarray(values, dtype=float)
        except (TypeError, ValueError) as exc:
            raise ParameterError(f"parameter values must be numbers: {exc}") from exc
        if values.shape != (len(self),):
            raise ParameterError(
                f"expected {len(self)} parameter values for set {self.label!r}, got shape "
                f"{values.shape}"
            )
        if not np.all(np.isfinite(values)):
            raise ParameterError("parameter values contain NaN or inf")
        return values

    def linearise(self, values: np.ndarray | Linearisation | None) -> Linearisation:
        """This set linearised at ``values`` (n,) [SI] (default zeros).

        Build it once per evaluation point and pass it on (to :meth:`apply` and the
        sensitivity functions) instead of the values: the joint twists are then
        computed once. A linearisation of this set is returned as it is.

        Raises:
            ParameterError: values of the wrong shape or not finite, or a linearisation
                of another parameter set.
        """
        if isinstance(values, Linearisation):
            if values.names != self.names:
                raise ParameterError(
                    f"a linearisation of other parameters ({len(values.names)}: "
                    f"{', '.join(values.names[:3])}, …) was given for set {self.label!r}: "
                    f"linearise this set at the values instead"
                )
            return values
        values = np.array(self.check_values(values))  # own read-only copy
        values.setflags(write=False)
        twists = {}
        for j in self.joints:
            cols, Xi = self._cols[j], self._twists[j]
            v = Xi @ values[cols]
            eff = Xi if not np.any(v) else pin.Jexp6(v) @ Xi
            twists[j] = (cols, v, eff)
        return Linearisation(self.names, values, twists)

    def apply(self, mech: Mechanism, values: np.ndarray | Linearisation | None) -> Mechanism:
        """A new mechanism with the joint origins displaced by ``values`` (SI units).

        ``values`` (n,), or their :class:`Linearisation`. The input mechanism is not
        modified.
        """
        origins = {}
        for j, (_, v, _) in self.linearise(values).joint_twists.items():
            if j not in mech.tree.joints:
                raise UnknownNameError("joint", j, list(mech.tree.joints))
            origins[j] = mech.tree.joints[j].origin * pin.exp6(v)
        return mech.with_joint_origins(origins)

    def format_value(self, k: int, value: float) -> str:
        """Human-readable value: µm for lengths, µrad for angles, SI with unit otherwise."""
        if self.units[k] == "m":
            return f"{value * 1e6:+.3f} µm"
        if self.units[k] == "rad":
            return f"{value * 1e6:+.3f} µrad"
        return f"{value:+.4g} {self.units[k]}"


def origin_parameter(mech: Mechanism, joint: str, dof: str) -> Parameter:
    """The parameter ``joint.dof`` (placement twist, joint offset or non-geometric term)."""
    uj = mech.tree.joints[joint]
    term = term_of_dof(dof)
    if term is not None:
        term.check(mech, joint)
        return Parameter(f"{joint}.{dof}", joint, dof, np.zeros(6), term.unit(uj.type))
    if dof == "offset":
        if not uj.movable:
            raise ParameterError(f"joint {joint!r} is {uj.type}: it has no 'offset' parameter")
        twist = uj.offset_twist()
        unit = "m" if uj.type == "prismatic" else "rad"
    else:
        twist = _UNIT_TWISTS[dof]
        unit = "m" if dof.startswith("t") else "rad"
    return Parameter(f"{joint}.{dof}", joint, dof, twist, unit)


def origin_dofs(mech: Mechanism, joint: str) -> list[str]:
    """The placement DOF names of ``joint`` (a movable joint's own axis: its ``offset``)."""
    uj = mech.tree.joints[joint]
    dofs = list(DOFS[:6])
    if uj.movable:
        offset = uj.offset_twist()
        same = [d for d in dofs if np.allclose(np.abs(_UNIT_TWISTS[d]), np.abs(offset))]
        if same:  # the twist along a unit axis IS the offset: keep one name for it
            dofs.remove(same[0])
        dofs.append("offset")
    return dofs


def full_parameters(mech: Mechanism) -> ParameterSet:
    """Six origin twists for every URDF joint, floating joints excluded.

    For a movable joint the offset replaces the twist along its axis.
    """
    params = [
        origin_parameter(mech, j, d)
        for j, uj in mech.tree.joints.items()
        if uj.type not in _EXCLUDED_TYPES
        for d in origin_dofs(mech, j)
    ]
    return ParameterSet(params, "full")


def degenerate_translations(mech: Mechanism) -> tuple[str, ...]:
    """Translation parameters between coincident joint axes (emulated U and ball joints).

    ``J.tx``, ``J.ty`` and ``J.tz`` are *degenerate* when J is a passive revolute joint
    whose origin translation is zero (‖t‖ ≤ 1e-12 m: a zero-length link) and whose
    parent link hangs from a passive revolute joint P: the axes of P and J then pass
    through one point, the pair (or a chain of three) emulates one physical universal
    or spherical joint, and translating J's origin would split that joint into two
    joints an offset apart — an error the physical joint cannot have. Such
    translations also create distinct assemblies and break forward kinematics, so the
    ``base`` preset leaves them out. Actuated joints are never degenerate: the offset
    between two motor axes is a real geometric error.

    Args:
        mech: the mechanism.

    Returns:
        Parameter names ``<joint>.t?`` in URDF joint order (empty when there are none).
    """
    tree, actuated = mech.tree, set(mech.actuated)

    def passive_revolute(name: str) -> bool:
        return tree.joints[name].type in _REVOLUTE and name not in actuated

    out = []
    for name, uj in tree.joints.items():
        parent = tree.parent_joint.get(uj.parent)
        if (
            passive_revolute(name)
            and parent is not None
            and passive_revolute(parent)
            and float(np.linalg.norm(uj.origin.translation)) <= _ZERO_LENGTH
        ):
            out += [f"{name}.{d}" for d in origin_dofs(mech, name) if d.startswith("t")]
    return tuple(out)

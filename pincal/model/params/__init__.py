"""The parameters a calibration varies.

What a calibration varies: displacements of joint placements
(:class:`ParameterSet`, presets, directions), joint terms beyond geometry (compliance,
struts, temperature, transmission), deflection under load and payloads.
"""

from __future__ import annotations

from pincal.model.params._deflection import (
    actual_joint_values,
    deflected_joints,
    deflection_jacobian,
    loaded_terms,
    undeflected_commands,
)
from pincal.model.params._directions import (
    describe_direction,
    direction_record,
    parent_direction,
)
from pincal.model.params._joint_term_set import (
    actual_shift,
    check_term_data,
    joint_term_bases,
    joint_term_basis,
    joint_term_prior,
    joint_term_shift,
    split_model,
    with_joint_terms,
)
from pincal.model.params._joint_terms import (
    JointTerm,
    joint_term,
    joint_term_units,
    register_term,
    term_kinds,
)
from pincal.model.params._linearisation import Linearisation
from pincal.model.params._parameters import (
    DOFS,
    Parameter,
    ParameterSet,
    degenerate_translations,
    full_parameters,
)
from pincal.model.params._payload import Payload, with_payload
from pincal.model.params._presets import parameters
from pincal.model.params._strut_statics import strut_loads, struts
from pincal.model.params._term_temperature import REFERENCE_C

__all__ = [
    "DOFS",
    "REFERENCE_C",
    "JointTerm",
    "Linearisation",
    "Parameter",
    "ParameterSet",
    "Payload",
    "actual_joint_values",
    "actual_shift",
    "check_term_data",
    "deflected_joints",
    "deflection_jacobian",
    "degenerate_translations",
    "describe_direction",
    "direction_record",
    "full_parameters",
    "joint_term",
    "joint_term_bases",
    "joint_term_basis",
    "joint_term_prior",
    "joint_term_shift",
    "joint_term_units",
    "loaded_terms",
    "parameters",
    "parent_direction",
    "register_term",
    "split_model",
    "strut_loads",
    "struts",
    "term_kinds",
    "undeflected_commands",
    "with_joint_terms",
    "with_payload",
]

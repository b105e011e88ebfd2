"""Parameters and parameter sets compare by value and can be hashed."""

from __future__ import annotations

import numpy as np
import pytest

from pincal.model import Parameter, ParameterSet, load_mechanism, parameters


@pytest.fixture(scope="module")
def wedge():
    return load_mechanism("wedge3")


def test_parameters_built_twice_are_equal_and_hash_alike(wedge):
    a, b = parameters(wedge, "patent"), parameters(wedge, "patent")
    assert a.parameters[0] is not b.parameters[0]
    assert a.parameters == b.parameters
    assert {*a.parameters} == {*b.parameters}
    assert len({*a.parameters, *b.parameters}) == len(a)
    assert a == b and hash(a) == hash(b)
    assert {a: 1}[b] == 1


def test_different_parameters_differ(wedge):
    full = parameters(wedge, "full")
    p, q = full.parameters[0], full.parameters[1]
    assert p != q
    assert full != full.subset([1, 0, *range(2, len(full))])
    assert full != "full"


def test_twist_is_part_of_identity_and_read_only():
    p = Parameter("j.tx", "j", "tx", np.array([1.0, 0, 0, 0, 0, 0]), "m")
    q = Parameter("j.tx", "j", "tx", np.array([0.0, 1, 0, 0, 0, 0]), "m")
    assert p != q
    with pytest.raises(ValueError):
        p.twist[0] = 2.0
    assert ParameterSet([p]) == ParameterSet(
        [Parameter("j.tx", "j", "tx", [1, 0, 0, 0, 0, 0], "m")]
    )

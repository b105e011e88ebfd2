"""Bad input to the model's public API raises PincalError subclasses (never a bare
ValueError/KeyError/AttributeError); ShapeError stays a ValueError for old callers."""

from __future__ import annotations

import numpy as np
import pytest

from pincal.errors import ParameterError, PincalError, ShapeError
from pincal.model import load_mechanism, parameters


@pytest.fixture(scope="module")
def wedge():
    return load_mechanism("wedge3")


@pytest.mark.parametrize(
    "call",
    [
        lambda m: m.configuration(np.zeros(2)),
        lambda m: m.configuration(["a", "b", "c"]),
        lambda m: m.configurations(np.zeros((2, 4))),
        lambda m: m.forward(np.zeros((3, 1))),
        lambda m: m.frame_placement(np.zeros(3)),
        lambda m: m.kinematics(np.zeros(m.model.nq + 1)),
        lambda m: m.closure_residual("q"),
        lambda m: m.closure_jacobian(None),
        lambda m: m.actuators_of(np.zeros(2)),
        lambda m: m.with_actuators(m.q_home, np.zeros(5)),
        lambda m: m.inverse("pose"),
        lambda m: m.inverse(np.eye(3)),
        lambda m: m.inverse(2 * np.eye(4)),
        lambda m: m.inverse_configuration(m.frame_placement(m.q_home), q_guess=np.zeros(2)),
        lambda m: m.configuration(np.zeros(3), q_guess=np.zeros(1)),
    ],
)
def test_bad_shapes_are_shape_errors(wedge, call):
    with pytest.raises(ShapeError) as info:
        call(wedge)
    assert isinstance(info.value, PincalError) and isinstance(info.value, ValueError)
    assert "shape" in str(info.value) or "must be" in str(info.value)


def test_inverse_accepts_a_homogeneous_matrix(wedge):
    T = wedge.frame_placement(wedge.q_home)
    q_act = wedge.inverse(T.homogeneous)
    assert np.allclose(q_act, wedge.actuators_of(wedge.q_home), atol=1e-9)


@pytest.mark.parametrize(
    "call",
    [
        lambda p: p.check_values(["x"] * len(p)),
        lambda p: p.subset([0, 99]),
        lambda p: p.subset(["a"]),
    ],
)
def test_bad_parameter_input_is_a_parameter_error(wedge, call):
    with pytest.raises(ParameterError):
        call(parameters(wedge, "patent"))

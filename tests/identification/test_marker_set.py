"""Several markers on one link: closed-form registration of every offset, and the
stacked problem's Jacobian against finite differences."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from pincal.identification import MarkerSetProblem
from pincal.measure import (
    MarkerSetup,
    Measurements,
    marker_frame,
    marker_mechanism,
    marker_mechanisms,
    register_markers,
)
from pincal.model import BASE_JOINT, TOOL_JOINT, parameters, sample_actuators, with_joint_origin

T_TRUE = pin.SE3(pin.rpy.rpyToMatrix(0.3, 0.1, -0.5), np.array([0.8, 0.5, -0.2]))
MARKERS = (np.array([0.02, 0.04, 0.1]), np.array([-0.05, 0.0, 0.07]), np.array([0.0, -0.06, 0.03]))
SETUP = MarkerSetup("wrist_3_link", more_columns=(("a", "b", "c"), ("d", "e", "f")))


def _sets(noise: float):
    mech = marker_mechanism("ur5", SETUP)
    actual = with_joint_origin(mech, BASE_JOINT, T_TRUE)
    actual = with_joint_origin(actual, TOOL_JOINT, pin.SE3(np.eye(3), MARKERS[0]))
    for k in (1, 2):
        actual = with_joint_origin(actual, marker_frame(k)[0], pin.SE3(np.eye(3), MARKERS[k]))
    q = sample_actuators(mech, 12, np.random.default_rng(4))
    rng = np.random.default_rng(5)
    parts = []
    for k in range(3):
        frame = marker_frame(k)[1]
        P = np.array([actual.frame_placement(c, frame).translation
                      for c in actual.configurations(q)])  # fmt: skip
        P = P + rng.normal(0, noise, P.shape)
        parts.append(Measurements(q, P, None, ("x", "y", "z"), frame, tuple(mech.actuated)))
    return mech, tuple(parts)


def test_registration_recovers_the_frame_and_every_marker():
    mech, parts = _sets(0.0)
    reg = register_markers(mech, parts[0], more=parts[1:])
    assert np.allclose(reg.marker, MARKERS[0], atol=1e-9)
    for k in (1, 2):
        assert np.allclose(reg.more_markers[k - 1], MARKERS[k], atol=1e-9)
        origin = reg.mechanism.tree.joints[marker_frame(k)[0]].origin.translation
        assert np.allclose(origin, MARKERS[k], atol=1e-9)
    assert np.allclose(reg.T_instrument_base.translation, T_TRUE.translation, atol=1e-9)
    assert reg.fit.rms < 1e-9 and len(reg.fit.residuals) == 36  # every marker's rows


def test_stacked_jacobian_matches_finite_differences():
    mech, parts = _sets(1e-4)
    reg = register_markers(mech, parts[0], more=parts[1:])
    params = parameters(reg.mechanism, "chain")
    problem = MarkerSetProblem.build(marker_mechanisms(reg.mechanism, SETUP), params, parts)
    model = problem.model
    x = np.random.default_rng(6).normal(0, 1e-3, len(params))
    _, J, raw = model.evaluate(x)
    assert raw.shape == (36, 3) and J.shape == (108, len(params))
    h = 1e-7
    fd = np.empty_like(J)
    for i in range(len(params)):
        e = np.zeros(len(params))
        e[i] = h
        fd[:, i] = (model.evaluate(x + e, False)[0] - model.evaluate(x - e, False)[0]) / (2 * h)
    assert np.allclose(J, fd, atol=1e-5 * np.abs(J).max())
    # a marker's offset moves only its own rows
    for k in (1, 2):
        cols = [params.index(f"{marker_frame(k)[0]}.{d}") for d in ("tx", "ty", "tz")]
        rows = np.zeros(108, dtype=bool)
        rows[36 * k : 36 * (k + 1)] = True
        assert np.all(J[~rows][:, cols] == 0) and np.abs(J[rows][:, cols]).max() > 0

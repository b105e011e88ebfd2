"""Two chains sharing links in one problem: TALOS from its left sole, a marker on each wrist.

One marker table holds both markers' columns and every joint of both chains (sole → leg →
torso → left arm, and → right arm); the leg and the torso are calibrated once, from both
markers. The truth is Pinocchio's model of the URDF as shipped with every joint placement
displaced (``reroot_sim``: none of pincal's model or parameterisation).
"""

from __future__ import annotations

import numpy as np
import pytest

from pincal.identification import MarkerSetProblem, fit_markers
from pincal.io import read_marker_data
from pincal.measure import MarkerSetup, marker_mechanism, marker_mechanisms
from pincal.model import sample_actuators
from pincal.sensitivity import parameters
from tests.identification.reroot_sim import marker_points, perturbed_model

ROOT, LEFT, RIGHT = "left_sole_link", "arm_left_7_link", "arm_right_7_link"
RIGHT_MARKER = np.array([-0.02, 0.04, 0.07])  # [m] in the right wrist's frame
SETUP = MarkerSetup(LEFT, root=ROOT, columns=("xl", "yl", "zl"), length_unit="mm",
                    more_columns=(("xr", "yr", "zr"),), more_links=(RIGHT,))  # fmt: skip


@pytest.fixture(scope="module")
def two_arms():
    """(mechanism, truth, 120 configurations)."""
    mech = marker_mechanism("talos", SETUP)
    q = sample_actuators(mech, 120, np.random.default_rng(3))
    return mech, perturbed_model("talos", 1e-3, 0), q


def _table(path, mech, truth, q, sigma: float, seed: int):
    """The marker table (joints [rad], both markers [mm]) and its noise-free points [m]."""
    points = []
    for s in (0.0, sigma):
        left = marker_points(truth, ROOT, LEFT, mech.actuated, q, s, seed)
        right = marker_points(truth, ROOT, RIGHT, mech.actuated, q, s, seed + 1, RIGHT_MARKER)
        points.append((left, right))
    lines = [",".join([*mech.actuated, "xl", "yl", "zl", "xr", "yr", "zr"])]
    for i, qi in enumerate(q):
        values = (*qi, *(points[1][0][i] * 1e3), *(points[1][1][i] * 1e3))
        lines.append(",".join(repr(float(v)) for v in values))
    path.write_text("\n".join(lines) + "\n")
    return read_marker_data(path, mech, SETUP).sets, points[0]


def test_the_model_holds_both_chains_once(two_arms):
    mech, _, _ = two_arms
    chains = [j for j in mech.actuated if j.startswith(("leg_left", "torso", "arm_"))]
    assert len(mech.actuated) == 6 + 2 + 7 + 7 and chains == list(mech.actuated)
    joints = [e["joints"] for e in mech.presets["chain"]]
    assert len(joints) == len(set(joints))  # the shared leg and torso once
    assert {"arm_left_7_joint", "arm_right_7_joint", "torso_2_joint", "marker2_frame"} <= set(
        joints
    )
    assert mech.tree.joints["marker2_frame"].parent == RIGHT
    assert marker_mechanisms(mech, SETUP)[1].measured_frame == "marker2"


def _prediction(fit, sets, truth_points):
    """Noise-free truth − prediction [m] at poses ``sets`` and its Jacobian (fitted columns)."""
    reg = fit.registration.mechanism
    params = parameters(reg, "chain")
    names = list(np.array(fit.result.names)[fit.result.identified])
    exact = tuple(
        type(m)(m.q_act, p, None, m.components, m.frame, m.actuated)
        for m, p in zip(sets, truth_points, strict=True)
    )
    model = MarkerSetProblem.build(marker_mechanisms(reg, SETUP), params, exact, None, names).model
    _, J_w, raw = model.evaluate(fit.result.full_values)
    J = J_w * model.sigma.reshape(-1)[:, None]
    return raw.reshape(-1), J[:, fit.result.identified]


def test_exact_markers_on_both_wrists_are_reproduced(two_arms, tmp_path):
    mech, truth, q = two_arms
    sets, exact = _table(tmp_path / "t.csv", mech, truth, q, 0.0, 4)
    fit = fit_markers(mech, SETUP, [s.subset(np.arange(80)) for s in sets], prior=None)
    assert fit.result.success, fit.result.message
    assert np.abs(fit.result.residuals).max() < 1e-9
    new = [s.subset(np.arange(80, 120)) for s in sets]
    err, _ = _prediction(fit, new, [p[80:] for p in exact])
    assert np.abs(err).max() < 1e-9  # the nominal model is off by millimetres


def test_noisy_markers_predict_at_the_cramer_rao_level(two_arms, tmp_path):
    """10 noise draws: new poses' prediction errors against their covariance J C Jᵀ."""
    mech, truth, q = two_arms
    d2, rms = [], []
    for seed in range(10):
        sets, exact = _table(tmp_path / f"t{seed}.csv", mech, truth, q, 1e-4, 10 + 2 * seed)
        fit = fit_markers(mech, SETUP, [s.subset(np.arange(80)) for s in sets], prior=None)
        assert fit.result.success, fit.result.message
        err, J = _prediction(fit, [s.subset(np.arange(80, 120)) for s in sets],
                             [p[80:] for p in exact])  # fmt: skip
        w, V = np.linalg.eigh(J @ fit.result.covariance @ J.T)
        keep = w > 1e-10 * w.max()
        d2.append(float(np.sum((V.T @ err)[keep] ** 2 / w[keep])) / int(keep.sum()))
        rms.append(float(np.sqrt(np.mean(err**2))))
    se = np.std(d2, ddof=1) / np.sqrt(len(d2))
    print(f"d2/k {np.mean(d2):.3f} ± {se:.3f}; prediction RMS {np.mean(rms) * 1e3:.4f} mm")
    assert abs(np.mean(d2) - 1.0) < max(3 * se, 0.15), (np.mean(d2), se, d2)


def test_joint_columns_off_the_chains_are_named_once(two_arms, tmp_path):
    """One wrist's chain read from the two-arm table: the other arm's columns are said."""
    mech, truth, q = two_arms
    _table(tmp_path / "t.csv", mech, truth, q[:10], 1e-4, 4)
    one = MarkerSetup(LEFT, root=ROOT, columns=("xl", "yl", "zl"), length_unit="mm")
    read = read_marker_data(tmp_path / "t.csv", marker_mechanism("talos", one), one)
    said = [n for n in read.notes if "off the calibrated chain" in n]
    assert len(said) == 1 and "arm_right_1_joint" in said[0] and "torso" not in said[0]
    both = read_marker_data(tmp_path / "t.csv", mech, SETUP)
    assert not [n for n in both.notes if "off the calibrated chain" in n]

"""Residual structure against the pose coordinates: the ``trend:<coordinate>`` probes."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import pincal
from pincal.identification import check_quality, identify
from pincal.identification.gate._coordinate_probe import coordinate_columns, trend_size
from pincal.identification.gate._misspecification import probe_misspecification
from pincal.model import sample_actuators

NOISE = pincal.NoiseModel(0.01, 0.05)


@pytest.fixture(scope="module")
def campaign(stewart, stewart42):
    rng = np.random.default_rng(31)
    actual = stewart42.apply(stewart, rng.uniform(-1e-3, 1e-3, len(stewart42)))
    return pincal.simulate_measurements(actual, sample_actuators(stewart, 50, rng), NOISE, rng)


def _bent(meas: pincal.Measurements, size: float) -> pincal.Measurements:
    """x grows with the square of the tool's z: ``size`` [m] from the middle to the ends."""
    p = meas.positions.copy()
    z = p[:, 2]
    t = (z - z.min()) / (z.max() - z.min()) - 0.5
    p[:, 0] += size * 4 * t**2
    return dataclasses.replace(meas, positions=p)


def test_columns_per_coordinate(campaign, stewart):
    cols = coordinate_columns(campaign, tuple(stewart.actuated))
    assert set(cols) == {f"trend:actuator {a}" for a in stewart.actuated} | {
        "trend:tool x", "trend:tool y", "trend:tool z"}  # fmt: skip
    c = cols["trend:tool z"]
    assert c.shape == (50, 6, 12)
    t = c[:, 0, 0]  # the normalised coordinate on x
    assert t.min() == pytest.approx(-0.5) and t.max() == pytest.approx(0.5)
    assert np.all(c[:, 1:, 0] == 0)  # each column acts on one component
    assert coordinate_columns(dataclasses.replace(campaign).subset(range(5))) == {}


def test_trend_size_in_words():
    fitted = np.zeros((4, 6))
    fitted[:, 4] = [0.0, 1e-4, 2e-4, 3e-4]  # 0.3 mrad in ry
    fitted[:, 0] = [0.0, 1e-5, 0.0, 0.0]  # 0.01 mm in x
    text = trend_size("trend:tool z", fitted, ("x", "y", "z", "rx", "ry", "rz"))
    assert text == "a trend of 0.3 mrad in ry along the tool z"


@pytest.mark.parametrize("declared", [True, False])
def test_a_bent_guide_is_named_by_its_coordinate(stewart, stewart42, campaign, declared):
    """0.1 mm along x growing with z²: no scale, gain or drift; the trend probe names z."""
    meas = _bent(campaign, 0.1e-3)
    if not declared:
        meas = dataclasses.replace(meas, noise=None)
    result = identify(stewart, stewart42, meas)
    v = check_quality(result, meas, mech=stewart)
    assert not v.passed and "model" in [i.kind for i in v.refusals]
    assert v.cause == "model or instrument"
    assert v.cause_text.startswith("a trend of 0.1") and "in x along the tool z" in v.cause_text
    assert "pose coordinate" in v.cause_text
    best = min(v.probes, key=lambda p: p[2])
    assert best[0] == "trend:tool z" and best[1] > 0.3


def test_clean_campaign_passes_with_the_trend_probes_run(stewart, stewart42, campaign):
    result = identify(stewart, stewart42, campaign)
    v = check_quality(result, campaign, mech=stewart)
    assert v.passed, v.reason()
    assert sum(p[0].startswith("trend:") for p in v.probes) == 9
    assert _bent(campaign, 0.0).positions == pytest.approx(campaign.positions)


def test_trend_f_test_false_alarms_on_linear_gaussian_data():
    """Under a correct linear model each trend probe's p-value is uniform; at the gate's
    Bonferroni level the family-wise false-alarm rate over 400 campaigns is ≤ 2 %."""
    rng = np.random.default_rng(5)
    m, k, n = 40, 3, 12
    alarms, pvals = 0, []
    for _ in range(400):
        meas = pincal.Measurements(
            q_act=rng.uniform(-1, 1, (m, 4)), positions=rng.uniform(-0.3, 0.3, (m, 3)),
            rotations=None, components=("x", "y", "z"), frame="tool",
            actuated=("a", "b", "c", "d"),
        )  # fmt: skip
        cols = coordinate_columns(meas)
        A = rng.standard_normal((m * k, n))
        z = rng.standard_normal(m * k)
        probes = probe_misspecification(A, z, cols, np.full((m, k), 1e-5))
        assert len(probes) == 7
        pvals += [p.p_value for p in probes]
        alarms += any(p.p_value < 1e-3 / len(probes) for p in probes)
    assert alarms / 400 <= 0.02
    # uniform p-values: the share below 0.1 and 0.5 within 3 s.e. of 2800 draws
    pv = np.array(pvals)
    for level in (0.1, 0.5):
        assert abs(np.mean(pv < level) - level) < 3 * np.sqrt(level * (1 - level) / pv.size)


def test_tool_coordinates_are_the_models_not_the_noisy_measured_ones():
    """wedge3 measures x, z, ry; its tool z spans 3 mm. Regressing the z residual on the
    *measured* z (which carries that residual's noise) fired a 0.04 mm "trend" at
    p = 5e-9 on a clean campaign whose χ² matched the declared noise (p = 0.52); on the
    fitted model's positions it does not."""
    from pincal.model import load_mechanism, parameters

    mech = load_mechanism("wedge3")
    params = parameters(mech, next(iter(mech.presets)))
    rng = np.random.default_rng(1)  # the study's draw (scripts/studies/quality_gate.py)
    bound = np.array([1e-3 if u == "m" else 1e-2 for u in params.units])
    actual = params.apply(mech, rng.uniform(-bound, bound))
    meas = pincal.simulate_measurements(actual, sample_actuators(mech, 40, rng), NOISE, rng)
    result = identify(mech, params, meas)
    v = check_quality(result, meas, mech=mech)
    assert v.passed, v.reason()
    z = next(p for p in v.probes if p[0] == "trend:tool z")
    assert z[2] > 1e-3
    measured = coordinate_columns(meas, tuple(mech.actuated))["trend:tool z"]
    pos = meas.positions.copy()
    pos[:, 2] -= np.asarray(result.residuals)[:, list(meas.components).index("z")]
    model = coordinate_columns(meas, tuple(mech.actuated), pos)["trend:tool z"]
    assert not np.allclose(measured, model)

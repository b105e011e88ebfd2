"""A noisy campaign through the CLI on machines new to pincal reaches the Cramér–Rao
prediction within 2.5× (issue 36; the whole roster: scripts/studies/open_world_campaigns.py).

The MJCF four-bar loaded without a sidecar measures its rocker body at the rocker's own
pivot: a point the crank does not move. Before: `poses` rejected every candidate as
singular (σ_min NaN), then the fit crawled along directions placed only to ±1.4 m and the
gate refused it for a parameter moved 43 mm and for a "100 % scale of the measured
positions" — the probe fitted the measured pivot's own noise.

On the MJCF delta, the RUSR with a robot.yaml universal joint and the 2-RSU ankle the fit
is curved over its confidence region (the written covariance is inflated for it): the
prediction was 15×, 54× and 18× the achieved RMS. It propagated the inflated covariance
(the parameter-effects curvature: the fit errs along a valley where the outputs do not
change) through a Jacobian taken at the nominal, while the covariance is the solution's.
It now propagates the linear one through the Jacobian at the solution.
"""

from __future__ import annotations

import json
import re

import pytest

from tests.open_world import acceptance
from tests.open_world.roster import ROSTER

CASES = ["MJCF fourbar", "Agile Eye (Gosselin & Hamel 1994)"]


@pytest.mark.slow
@pytest.mark.parametrize("name", CASES)
def test_a_noisy_campaign_reaches_the_cramer_rao_prediction(name, tmp_path):
    machine = next(m for m in ROSTER if m.name == name)
    model = machine.write(tmp_path)
    after, predicted, _ = acceptance.prediction_ratio(acceptance.noisy_campaign(model, tmp_path))
    assert predicted is not None
    assert after <= 2.5 * predicted
    # the printed table's header keeps its two blocks apart, whichever is not measured
    text = acceptance.invoke("validate", tmp_path / "cal", "--data", tmp_path / "v.csv")
    header = text.splitlines()[1]
    assert re.search(r"\[mm\]\s+orientation \(", header), header


CURVED = ["MJCF delta", "rusr_ujoint", "2-RSU ankle"]


@pytest.mark.slow
@pytest.mark.parametrize("name", CURVED)
def test_a_curved_fit_predicts_its_validation_error_neither_pessimistic_nor_optimistic(
    name, tmp_path
):
    machine = next(m for m in ROSTER if m.name == name)
    model = machine.write(tmp_path)
    doc = acceptance.noisy_campaign(model, tmp_path)
    record = json.loads((tmp_path / "cal" / "identification.json").read_text())
    assert record["quality"]["uncertainty"]["method"] == "inflated"  # the case at stake
    after, predicted, _ = acceptance.prediction_ratio(doc)
    assert predicted is not None
    assert 1 / 2.5 <= predicted / after <= 2.5
    assert doc["predicted"]["covariance"] == "cramer-rao"
    # the model's own error, on fresh poses measured without noise (the noise dominates
    # the ratio above): over 10 noise seeds predicted/achieved was 1.07 ± 0.07 at most
    acceptance.invoke("simulate", model, "--random", 60, "--seed", 9, "--params", "base",
                      "--errors", "seed:3", "--error-size", "0.2,1", "--noise", "0,0",
                      "--out", tmp_path / "v0.csv")  # fmt: skip
    exact = json.loads(acceptance.invoke("validate", tmp_path / "cal", "--data",
                                         tmp_path / "v0.csv", "--json"))  # fmt: skip
    model_rms = exact["predicted"]["model_rms_position_mm"]
    assert 1 / 2.5 <= model_rms / exact["after"]["rms_position_mm"] <= 2.5

"""The constants an instrument file declares and the fit trusts, named in the gauge.

A sphere probe file declares the sphere's radius, a ballbar its bar length; the joint fit
does not fit them. When the fitted machine absorbs what an error of one does to the
readings, the data cannot check it, and the gauge says so with its 1σ (issue 25): the
1 % sphere-radius cell of ``scripts/studies/instrument_gate.py`` that no test of the
residuals can refuse.
"""

from __future__ import annotations

import dataclasses
import json
import re
from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np
import pytest

from pincal.identification import default_instrument, identify_instruments
from pincal.measure import Distance, add_instrument_kind, simulate_instrument
from pincal.model import load_mechanism, sample_actuators
from pincal.sensitivity import parameters
from tests.instruments.conftest import setups

RRR3 = str(Path(__file__).resolve().parents[1] / "model" / "machines" / "rrr3" / "rrr3.urdf")
LIMIT = 1e-3  # SCALE_STD_LIMIT: named past 1e-3 of the constant's value (1σ)


def _jacobian(fit) -> np.ndarray:
    """(N, p) the fit's whitened Jacobian of its fitted parameters at the solution."""
    A, z = fit.whitened
    return A.reshape(len(z), -1)


def _left(J: np.ndarray, c: np.ndarray) -> float:
    """‖c − J (J⁺ c)‖: what the fitted parameters leave of a whitened column."""
    return float(np.linalg.norm(c - J @ np.linalg.lstsq(J, c, rcond=None)[0]))


def _campaign(model, preset, kind, seed, below=None, n=60):
    """An actual machine as the study draws it, n random poses, the kind's set-up.

    ``below``: put the sphere centre this far [m] below the tool points' centre instead
    of the typical 0.1 m.
    """
    mech = load_mechanism(model)
    params = parameters(mech, preset or next(iter(mech.presets)))
    rng = np.random.default_rng(seed)
    bound = np.array([1e-3 if u == "m" else 1e-2 for u in params.units])
    actual = params.apply(mech, rng.uniform(-bound, bound))
    q = sample_actuators(mech, n, rng)
    inst, theta, ids = default_instrument(mech, kind, q, std=1e-5)
    if below is not None:
        theta = theta + np.array([0.0, 0.0, 0.1 - below])
    data = simulate_instrument(actual, inst, theta, q, rng, ids=ids)
    return mech, params, inst, data


def _lines(fit, word):
    return [g for g in fit.gauge if word in g]


def test_declared_constant_derivatives_are_exact(stewart_tool80):
    P = stewart_tool80[:20]
    for kind, (inst, theta, ids) in setups(P).items():
        v = inst.predict(P, theta, None if ids is None else ids[:20])[0]
        (c,) = inst.declared_constants(P, theta, None if ids is None else ids[:20])
        assert c.derivative.shape == (20,)
        if kind == "sphere":  # the readings as a function of the declared radius
            h = 1e-7
            up = dataclasses.replace(inst, radius=inst.radius + h).predict(P, theta)[0]
            down = dataclasses.replace(inst, radius=inst.radius - h).predict(P, theta)[0]
            np.testing.assert_allclose(c.derivative, (up - down) / (2 * h), atol=1e-7)
            assert (c.value, c.unit) == (inst.radius, "m")
        else:  # a relative scale k of the readings: v (1 + k)
            np.testing.assert_allclose(c.derivative, v, rtol=0, atol=0)
            assert (c.value, c.unit) == (1.0, "1")


def test_the_sphere_radius_is_named_on_the_typical_stewart_set_up():
    """The study's set-up: the centre 0.1 m below 60 random tool points. The radius is
    told only to ≈ 1 % (seed 0: ±239 µm), and that 1σ is the absorbed signal: a radius
    error δr leaves χ² λ = (δr / σ_r)² after the fit (the 1 % error of the study's cell:
    λ 0.3–0.8, the χ² no test of the residuals can see)."""
    mech, params, inst, data = _campaign("stewart_6ups", None, "sphere", 0)
    fit = identify_instruments(mech, params, [data])
    (line,) = _lines(fit, "radius")
    assert line.startswith("the sphere radius: a radius error passes into the calibrated "
                           "machine — the data tell it only to ±")  # fmt: skip
    assert line.endswith("(1σ) of its declared 20 mm; the radius rests on its declared value")
    told = float(re.search(r"±([\d.]+) µm", line).group(1)) * 1e-6
    J = _jacobian(fit)
    dr = 0.01 * inst.radius  # the study's fault
    lam = _left(J, np.full(J.shape[0], -dr / inst.std)) ** 2
    assert 0.1 < lam < 2.0  # all but ~3e-5 of its χ² (24 000) absorbed
    assert told == pytest.approx(dr / np.sqrt(lam), rel=5e-3)  # printed to 3 digits
    assert told > 5 * LIMIT * inst.radius  # far past the limit, not at its edge


def test_a_sphere_close_to_the_workspace_has_its_radius_told_and_not_named():
    """The centre 30 mm below the tool points' centre (60 random poses spanning ±58 mm):
    the directions to the tool points spread over a wide cone, so a constant change of
    every reading no longer trades with the centre's height and the machine: the radius
    is told to ≈ 11–14 µm (seeds 0–3), within 1e-3 of 20 mm, and not named."""
    mech, params, inst, data = _campaign("stewart_6ups", None, "sphere", 0, below=0.03)
    fit = identify_instruments(mech, params, [data])
    assert fit.result.success
    J = _jacobian(fit)
    std = 1.0 / _left(J, np.full(J.shape[0], -1.0 / inst.std))
    assert std < LIMIT * inst.radius
    assert _lines(fit, "radius") == []
    assert _lines(fit, "passes into the calibrated machine") == []


def test_the_ballbar_scale_line_is_unchanged_on_a_revolute_only_machine():
    """The 3-RRR's length scale rests on the bar: the line, word for word as before the
    constants were declared per kind, with 1σ = 1/‖(I − Π_J) v/σ‖."""
    mech, params, inst, data = _campaign(RRR3, "base", "distance", 1)
    fit = identify_instruments(mech, params, [data])
    (line,) = _lines(fit, "passes into the calibrated machine")
    m = re.fullmatch(
        r"the length scale: a scale error of the readings \(a bar length, a gain\) passes into "
        r"the calibrated machine — the data tell it only to ([\d.e+]+) % \(1σ\); the scale "
        r"rests on the instrument's own calibration",
        line,
    )
    assert m is not None, line
    J = _jacobian(fit)
    v = data.values - fit.residuals[0][:, 0]  # the model's readings at the solution
    assert m.group(1) == f"{100 / _left(J, v / inst.std):.2g}"


@dataclass(frozen=True)
class QuietBar(Distance):
    """A ballbar kind that declares no constant (registered only in this file)."""

    kind: ClassVar[str] = "quiet_bar"

    def declared_constants(self, P, theta, ids=None):
        return ()


@pytest.fixture(scope="module")
def quiet_bar():
    return add_instrument_kind(QuietBar)


def test_a_kind_that_declares_no_constant_gets_no_line(quiet_bar):
    """The same bar readings on the 3-RRR: the built-in ballbar's scale is named (test
    above); a kind declaring nothing gets no line — the gauge asks the kind, not its name."""
    mech, params, inst, data = _campaign(RRR3, "base", "distance", 1)
    quiet = dataclasses.replace(data, instrument=quiet_bar(inst.std))
    fit = identify_instruments(mech, params, [quiet])
    assert fit.result.success
    assert _lines(fit, "passes into the calibrated machine") == []
    assert any("rotation" in g for g in fit.gauge)  # the rest of the gauge is there


def test_several_instrument_files_each_name_their_own_constant():
    """Two bar files on the 3-RRR: each bar's scale is its own constant, named with its
    file's label."""
    mech, params, _, data = _campaign(RRR3, "base", "distance", 1, n=80)

    def part(rows):
        return dataclasses.replace(data, q_act=data.q_act[rows], values=data.values[rows])

    a, b = part(slice(0, 40)), part(slice(40, 80))
    fit = identify_instruments(mech, params, [a, b], labels=["bar_a", "bar_b"])
    lines = _lines(fit, "passes into the calibrated machine")
    assert [g.split(":")[0] for g in lines] == ["the length scale of bar_a",
                                                "the length scale of bar_b"]  # fmt: skip


def test_a_constant_the_fit_absorbs_wholly_is_said_not_told():
    """A dial gauge along z on the planar 3-RRR reads one height: its gain is all offset."""
    mech, params, _, data = _campaign(RRR3, "base", "point", 1)
    fit = identify_instruments(mech, params, [data])
    assert _lines(fit, "passes into the calibrated machine") == [
        "the gauge's gain: a gain error of the readings passes into the calibrated machine — "
        "the data do not tell it at all; the scale rests on the instrument's own calibration"
    ]


@pytest.mark.slow  # a 45-unknown joint fit and its curvature check, as the ballbar's CLI test
def test_calibrate_on_a_sphere_file_says_the_radius_rests_on_its_declared_value(tmp_path):
    """`pincal simulate --instrument sphere` → `pincal calibrate`: the line is on stdout
    (JSON ``gauge``), in report.txt under "not calibrated" and in identification.json."""
    from click.testing import CliRunner

    from pincal.cli import main

    data, out = tmp_path / "sphere.csv", tmp_path / "cal"
    args = ["simulate", "stewart_6ups", "--random", "60", "--instrument", "sphere", "--seed", "1"]
    res = CliRunner().invoke(main, [*args, "--out", str(data)])
    assert res.exit_code == 0, res.output
    res = CliRunner().invoke(
        main, ["calibrate", "stewart_6ups", "--data", str(data), "--out", str(out), "--json"]
    )
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout)
    (line,) = [g for g in doc["gauge"] if g.startswith("the sphere radius: a radius error")]
    assert "of its declared 20 mm; the radius rests on its declared value" in line
    report = (out / "report.txt").read_text()
    assert f"  {line}" in report.split("not calibrated (held at nominal")[1]
    assert line in json.loads((out / "identification.json").read_text())["gauge"]


def test_a_declared_constant_of_an_unjudgeable_unit_or_value_is_refused():
    from pincal.errors import MeasurementError
    from pincal.measure import DeclaredConstant

    for value, unit in ((0.01, "rad"), (0.0, "m"), (float("nan"), "1")):
        with pytest.raises(MeasurementError, match="unit must be 'm' or '1'"):
            DeclaredConstant("a tilt", value, unit, np.ones(3), "a tilt error", "it rests")

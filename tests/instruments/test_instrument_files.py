"""Instrument CSV files and the simulate → identify round trip."""

from __future__ import annotations

import json

import numpy as np
import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.errors import ColumnError, MeasurementFormatError
from pincal.identification import identify_instruments
from pincal.io import read_instrument_data, write_instrument_data
from pincal.measure import INSTRUMENT_KINDS, InstrumentData, simulate_instrument
from pincal.model import parameters
from tests.instruments.conftest import setups


@pytest.mark.parametrize("kind", INSTRUMENT_KINDS)
def test_files_round_trip_exactly_in_metres(
    kind, tmp_path, stewart, stewart_rows80, stewart_tool80
):
    inst, theta, ids = setups(stewart_tool80)[kind]
    data = simulate_instrument(
        stewart,
        inst,
        theta,
        stewart_rows80[:10],
        np.random.default_rng(0),
        None if ids is None else ids[:10],
    )
    data = InstrumentData(
        inst, data.q_act, data.values, data.actuated, data.frame, data.ids, theta + 1e-4
    )
    back = read_instrument_data(write_instrument_data(tmp_path / "a.csv", data), stewart)
    assert back.instrument == inst
    np.testing.assert_array_equal(back.q_act, data.q_act)
    np.testing.assert_array_equal(back.values, data.values)
    np.testing.assert_array_equal(back.initial, data.initial)
    if kind == "plane":
        np.testing.assert_array_equal(back.ids, data.ids)
    mm = read_instrument_data(write_instrument_data(tmp_path / "b.csv", data, "mm"), stewart)
    np.testing.assert_allclose(mm.values, data.values, rtol=1e-15, atol=1e-18)
    np.testing.assert_allclose(mm.instrument.std, inst.std, rtol=1e-15)


def test_bad_files_name_what_is_wrong(tmp_path, stewart):
    act = ",".join(stewart.actuated)
    cases = {
        "kind: laser\nstd: 1": (MeasurementFormatError, "kind 'laser' unknown"),
        "kind: point": (MeasurementFormatError, "'# std: …' is required: the 1σ noise"),
        "kind: sphere\nstd: 0.001": (MeasurementFormatError, "'# radius: …' is required"),
        "kind: point\nstd: 1\nframe: tool0": (MeasurementFormatError, "frame 'tool0'"),
    }
    for head, (exc, msg) in cases.items():
        lines = "\n".join(f"# {h}" for h in head.split("\n"))
        path = tmp_path / "x.csv"
        path.write_text(f"# pincal instrument 1\n{lines}\n{act},value\n" + "0," * 6 + "0\n")
        with pytest.raises(exc, match=msg):
            read_instrument_data(path, stewart)
    path.write_text(
        f"# pincal instrument 1\n# kind: plane\n# std: 1\n{act},value\n" + "0," * 6 + "0\n"
    )
    with pytest.raises(ColumnError, match="plane"):
        read_instrument_data(path, stewart)


@pytest.mark.slow
@pytest.mark.parametrize("kind", INSTRUMENT_KINDS)
def test_cli_simulate_instrument_then_identify(kind, tmp_path, stewart):
    out = tmp_path / f"{kind}.csv"
    res = CliRunner().invoke(
        main,
        [
            "simulate",
            "stewart_6ups",
            "--random",
            "70",
            "--instrument",
            kind,
            "--noise",
            "0.001,0",
            "--out",
            str(out),
        ],
    )
    assert res.exit_code == 0, res.output
    truth = json.loads(out.with_suffix(".truth.json").read_text())
    assert set(truth["instrument"]) and truth["preset"] == "stewart42"
    data = read_instrument_data(out, stewart)
    assert data.kind == kind and len(data) == 70 and data.instrument.std == pytest.approx(1e-6)
    params = parameters(stewart, "stewart42")
    fit = identify_instruments(stewart, params, [data])
    assert fit.result.success
    assert 0.4 < fit.result.reduced_chi2 < 2.0
    # validation: the calibrated machine + identified instrument predict fresh readings
    true_vals = np.array([p["value"] for p in truth["parameters"]])
    actual = params.apply(stewart, true_vals)
    th_true = np.array(list(truth["instrument"].values()))
    rows = data.q_act[:20] * 0.999 + data.q_act[20:40] * 0.001
    ids = None if kind != "plane" else np.arange(20) % 2
    fresh = simulate_instrument(actual, data.instrument, th_true, rows, ids=ids, noise=False)
    inst_fit = fit.values[len(params) :]
    model = fit.result.calibrated
    P = np.array([model.frame_placement(q).translation for q in model.configurations(rows)])
    pred = data.instrument.predict(P, inst_fit, ids)[0]  # the file holds the plane normals
    assert np.abs(pred - fresh.values).max() < 2e-5  # 20 µm vs mm-size errors

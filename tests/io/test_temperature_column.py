"""The optional per-pose ``temperature_C`` column (°C) of measurement files."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from pincal.errors import BadValueError, MeasurementError, MeasurementFormatError
from pincal.io import read_measurements, write_measurements
from pincal.measure import simulate_measurements
from pincal.model import load_mechanism, sample_actuators

RRR3 = Path(__file__).parents[1] / "model" / "machines" / "rrr3"


@pytest.fixture(scope="module")
def planar():
    """A planar 3-RRR measuring [x, y, rz], 6 poses with temperatures."""
    mech = load_mechanism(RRR3)
    rng = np.random.default_rng(2)
    meas = simulate_measurements(mech, sample_actuators(mech, 6, rng), None, rng)
    return mech, dataclasses.replace(meas, temperature=rng.uniform(15.0, 30.0, 6))


def test_round_trip_is_exact(planar, tmp_path):
    mech, meas = planar
    path = write_measurements(tmp_path / "m.csv", meas, length_unit="mm", angle_unit="deg")
    header = next(line for line in path.read_text().splitlines() if not line.startswith("#"))
    assert header.endswith(",temperature_C")
    back = read_measurements(path, mech)
    assert np.array_equal(back.temperature, meas.temperature)
    assert back.subset([1, 3]).temperature.tolist() == meas.temperature[[1, 3]].tolist()
    plain = write_measurements(tmp_path / "p.csv", dataclasses.replace(meas, temperature=None))
    assert "temperature_C" not in plain.read_text()
    assert read_measurements(plain, mech).temperature is None


def test_a_kelvin_column_is_refused_by_row(planar, tmp_path):
    mech, meas = planar
    path = write_measurements(tmp_path / "m.csv", dataclasses.replace(
        meas, temperature=meas.temperature + 273.15))  # fmt: skip
    with pytest.raises(BadValueError, match=r"row 1, column 'temperature_C'.*degrees Celsius"):
        read_measurements(path, mech)


def test_a_joint_cannot_be_called_like_the_column(planar, tmp_path):
    _, meas = planar
    clash = dataclasses.replace(meas, actuated=("temperature_C", *meas.actuated[1:]))
    with pytest.raises(MeasurementFormatError, match="temperature_C"):
        write_measurements(tmp_path / "m.csv", clash)


def test_measurements_check_the_shape(planar):
    _, meas = planar
    with pytest.raises(MeasurementError, match=r"temperature must be \(6,\)"):
        dataclasses.replace(meas, temperature=np.zeros(5))
    with pytest.raises(MeasurementError, match="finite"):
        dataclasses.replace(meas, temperature=np.full(6, np.nan))

"""Measurement / pose / command files: exact round trips and one error per bad file."""

from __future__ import annotations

import logging

import numpy as np
import pinocchio as pin
import pytest

from pincal.errors import (
    BadValueError,
    ColumnError,
    FrameMismatchError,
    MeasurementFormatError,
    NonFiniteValueError,
    PoseFitError,
    TooFewPosesError,
)
from pincal.io import (
    TargetMeasurements,
    check_enough_poses,
    read_commands,
    read_measurement_file,
    read_measurements,
    read_poses,
    write_commands,
    write_measurements,
    write_poses,
    write_target_measurements,
)
from pincal.measure import (
    Measurements,
    simulate_measurements,
)
from pincal.model import load_mechanism, sample_actuators


@pytest.fixture(scope="module")
def hexa():
    return load_mechanism("hexaslide_6pus")


@pytest.fixture(scope="module")
def meas(hexa) -> Measurements:
    rng = np.random.default_rng(3)
    m = simulate_measurements(hexa, sample_actuators(hexa, 5, rng), None, rng)
    std = rng.uniform(1e-6, 1e-5, (5, 6))
    return Measurements(
        m.q_act, m.positions, m.rotations, m.components, m.frame, m.actuated, None, std
    )


def test_si_matrix_round_trip_is_bit_exact(tmp_path, hexa, meas):
    p1 = write_measurements(tmp_path / "a.csv", meas)
    back = read_measurements(p1, hexa)
    for name in ("q_act", "positions", "rotations", "std"):
        assert np.array_equal(getattr(back, name), getattr(meas, name)), name
    assert back.components == meas.components and back.frame == meas.frame
    p2 = write_measurements(tmp_path / "b.csv", back)
    assert p1.read_text() == p2.read_text()


def test_mm_rotvec_round_trip_to_last_place(tmp_path, hexa, meas):
    path = write_measurements(
        tmp_path / "a.csv",
        meas,
        length_unit="mm",
        angle_unit="mrad",
        orientation="rotvec",
        actuator_units=["mm"] * 6,
    )
    text = path.read_text()
    assert "leg1_slide [mm]" in text and "rx,ry,rz" in text
    back = read_measurements(path, hexa)
    assert np.allclose(back.q_act, meas.q_act, rtol=4e-16, atol=0)
    assert np.allclose(back.positions, meas.positions, rtol=4e-16, atol=0)
    assert np.allclose(back.rotations, meas.rotations, rtol=0, atol=2e-15)
    assert np.allclose(back.std, meas.std, rtol=4e-16, atol=0)


def test_target_file_fits_the_poses(tmp_path, hexa, meas):
    local = np.array([[0.1, 0, 0], [-0.1, 0, 0], [0, 0.1, 0], [0, 0, 0.05]])
    pts = np.einsum("mij,nj->mni", meas.rotations, local) + meas.positions[:, None, :]
    tm = TargetMeasurements(
        meas.q_act, pts, local, ("A", "B", "C", "D"), "platform", meas.actuated, point_std=1e-5
    )
    path = write_target_measurements(tmp_path / "t.csv", tm, length_unit="mm")
    mf = read_measurement_file(path, hexa)
    assert mf.targets is not None and mf.targets.names == ("A", "B", "C", "D")
    assert np.allclose(mf.measurements.positions, meas.positions, atol=1e-15)
    assert np.allclose(mf.measurements.rotations, meas.rotations, atol=1e-14)
    assert mf.measurements.std.shape == (5, 6) and np.all(mf.measurements.std > 0)
    # a moved target in row 3 is reported with its row
    pts2 = pts.copy()
    pts2[2, 1] += [0.002, 0, 0]
    tm2 = TargetMeasurements(
        meas.q_act, pts2, local, tm.names, "platform", meas.actuated, max_residual=1e-4
    )
    write_target_measurements(tmp_path / "t2.csv", tm2)
    with pytest.raises(PoseFitError, match="data row 3") as exc:
        read_measurements(tmp_path / "t2.csv", hexa)
    assert exc.value.row == 3


def _good(tmp_path, meas):
    return write_measurements(tmp_path / "good.csv", meas).read_text().splitlines()


def _write(tmp_path, lines):
    p = tmp_path / "bad.csv"
    p.write_text("\n".join(lines) + "\n")
    return p


def test_missing_actuator_columns_are_listed(tmp_path, hexa, meas):
    lines = _good(tmp_path, meas)
    k = next(i for i, s in enumerate(lines) if s.startswith("leg1_slide"))
    lines[k] = lines[k].replace("leg2_slide", "legX_slide").replace("leg5_slide", "leg55")
    with pytest.raises(ColumnError, match="leg2_slide") as exc:
        read_measurements(_write(tmp_path, lines), hexa)
    assert exc.value.missing == ["leg2_slide", "leg5_slide"]


def test_nan_and_text_are_reported_with_row_and_column(tmp_path, hexa, meas):
    lines = _good(tmp_path, meas)
    k = next(i for i, s in enumerate(lines) if s.startswith("leg1_slide"))
    bad = lines.copy()
    cells = bad[k + 3].split(",")
    cells[7] = "nan"
    bad[k + 3] = ",".join(cells)
    with pytest.raises(NonFiniteValueError, match="row 3, column 'y'") as exc:
        read_measurements(_write(tmp_path, bad), hexa)
    assert (exc.value.row, exc.value.column) == (3, "y")
    cells[7] = "1,5"
    bad[k + 3] = ",".join(cells)
    with pytest.raises(MeasurementFormatError, match="row 3"):
        read_measurements(_write(tmp_path, bad), hexa)
    cells = lines[k + 2].split(",")
    cells[0] = "abc"
    bad[k + 3] = lines[k + 3]
    bad[k + 2] = ",".join(cells)
    with pytest.raises(BadValueError, match="row 2, column 'leg1_slide'"):
        read_measurements(_write(tmp_path, bad), hexa)


def test_header_errors(tmp_path, hexa, meas):
    lines = _good(tmp_path, meas)
    with pytest.raises(FrameMismatchError, match="tool0"):
        read_measurements(
            _write(tmp_path, [s.replace("frame: platform", "frame: tool0") for s in lines]), hexa
        )
    with pytest.raises(MeasurementFormatError, match="unknown length unit 'inch'"):
        read_measurements(
            _write(tmp_path, [s.replace("length_unit: m", "length_unit: inch") for s in lines]),
            hexa,
        )
    with pytest.raises(MeasurementFormatError, match="pincal measurements 1"):
        read_measurements(_write(tmp_path, lines[1:]), hexa)
    with pytest.raises(ColumnError, match="not understood"):
        k = next(i for i, s in enumerate(lines) if s.startswith("leg1_slide"))
        extra = [*lines[:k], lines[k] + ",temp", *[s + ",20.0" for s in lines[k + 1 :]]]
        read_measurements(_write(tmp_path, extra), hexa)


def test_wrong_length_unit_is_flagged(tmp_path, hexa, meas, caplog):
    lines = [s.replace("length_unit: m", "length_unit: mm") for s in _good(tmp_path, meas)]
    with caplog.at_level(logging.WARNING):
        mf = read_measurement_file(_write(tmp_path, lines), hexa)
    assert mf.suspect_units and "m declared as mm: set length_unit m" in mf.warnings[0]
    assert "length_unit" in caplog.text
    assert not read_measurement_file(tmp_path / "good.csv", hexa).suspect_units


def test_no_unit_warning_for_a_machine_whose_home_is_at_the_origin(tmp_path):
    """wedge3's measured frame is at the world origin at home: a distance from the origin
    says nothing about the unit (seed 1: median distance 30× the 1 mm floor, which 0.1's
    check took for a unit mistake); the spread of the poses does."""
    from pincal.io import write_measurements
    from pincal.measure import NoiseModel, simulate_measurements
    from pincal.model import load_mechanism, sample_actuators

    mech = load_mechanism("wedge3")
    rng = np.random.default_rng(1)
    m = simulate_measurements(mech, sample_actuators(mech, 30, rng), NoiseModel(0.001, 0.01), rng)
    for unit in ("m", "mm"):
        path = write_measurements(tmp_path / f"w_{unit}.csv", m, length_unit=unit)
        assert not read_measurement_file(path, mech).suspect_units


def test_too_few_poses(meas):
    check_enough_poses(meas.subset(range(5)), 30)
    with pytest.raises(TooFewPosesError, match="at least 9 poses"):
        check_enough_poses(meas.subset(range(5)), 54)


def test_poses_and_commands_files(tmp_path, hexa):
    poses = [
        pin.SE3(pin.rpy.rpyToMatrix(0.05, -0.1, 0.1), np.array([0.02, 0.01, 0.43])),
        pin.SE3.Identity(),
    ]
    for orient in ("rotvec", "rpy"):
        path = write_poses(tmp_path / f"p_{orient}.csv", poses, orientation=orient)
        for a, b in zip(read_poses(path), poses, strict=True):
            assert np.allclose(a.homogeneous, b.homogeneous, atol=1e-15)
    q = np.random.default_rng(0).uniform(0, 0.1, (3, 6))
    write_commands(tmp_path / "c.csv", hexa.actuated, q, [0, 2, 5], actuator_units=["mm"] * 6)
    idx, back = read_commands(tmp_path / "c.csv", hexa)
    assert idx.tolist() == [0, 2, 5] and np.allclose(back, q, rtol=1e-15)

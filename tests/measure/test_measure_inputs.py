"""Bad input to pincal.measure and pincal.compensation raises MeasurementError, not
ValueError/KeyError/IndexError/AttributeError; good input keeps its old results."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from pincal.compensation import compensate, poses_from_array
from pincal.errors import MeasurementError, PincalError
from pincal.measure import Measurements, NoiseModel, simulate_measurements


def _meas(m: int = 4, comps: tuple[str, ...] = ("x", "y", "z")) -> Measurements:
    rng = np.random.default_rng(0)
    return Measurements(
        rng.normal(size=(m, 2)), rng.normal(size=(m, 3)), None, comps, "f", ("a", "b")
    )


@pytest.mark.parametrize("comps", [("x", "q"), ("x", "x"), ()])
def test_invalid_components_are_refused_at_construction(comps):
    with pytest.raises(MeasurementError, match="components"):
        _meas(comps=comps)


def test_sequences_are_stored_as_float_arrays_and_text_is_refused():
    m = Measurements([[0.1, 0.2]], [[1, 2, 3]], None, ("x", "y", "z"), "f", ("a", "b"))
    assert isinstance(m.q_act, np.ndarray) and m.positions.dtype == float
    assert m.positions.tolist() == [[1.0, 2.0, 3.0]]
    with pytest.raises(MeasurementError, match="positions must be an array of numbers"):
        Measurements([[0.1, 0.2]], [["a", 2, 3]], None, ("x", "y", "z"), "f", ("a", "b"))


def test_subset_checks_indices_and_keeps_rows():
    meas = _meas()
    sub = meas.subset([3, 1])
    assert np.array_equal(sub.q_act, meas.q_act[[3, 1]])
    mask = np.array([True, False, True, False])
    assert np.array_equal(meas.subset(mask).positions, meas.positions[mask])
    assert len(meas.subset(slice(1, 3))) == 2
    assert np.array_equal(meas.subset([-1]).q_act, meas.q_act[[-1]])
    with pytest.raises(MeasurementError, match=r"in \[0, 4\)"):
        meas.subset([4])
    with pytest.raises(MeasurementError, match="integers"):
        meas.subset([0.5])
    with pytest.raises(MeasurementError, match="boolean mask"):
        meas.subset([True, False])


def test_noise_specification_errors_are_measurement_errors():
    with pytest.raises(MeasurementError, match="must be numbers"):
        NoiseModel.from_spec({"position": "ten"})
    with pytest.raises(MeasurementError, match="finite std"):
        NoiseModel("ten")  # type: ignore[arg-type]
    assert NoiseModel.from_spec({"position": 2}) == NoiseModel(2.0, 0.0)


def test_simulate_refuses_unknown_components(stewart, stewart_poses):
    with pytest.raises(MeasurementError, match="components"):
        simulate_measurements(stewart, stewart_poses[:2], components=("x", "w"))


def test_compensation_targets_as_lists_or_se3_and_bad_ones_refused(stewart, stewart_poses):
    rows = stewart_poses[:2]
    targets = [stewart.forward(r) for r in rows]
    as_rows = [[*T.translation, *pin.log3(T.rotation)] for T in targets]
    a = compensate(stewart, targets)
    b = compensate(stewart, as_rows)
    np.testing.assert_allclose(b.q_act, a.q_act, atol=1e-9)
    np.testing.assert_allclose(a.q_act, rows, atol=1e-7)
    with pytest.raises(MeasurementError, match="mix"):
        compensate(stewart, [targets[0], as_rows[1]])
    with pytest.raises(MeasurementError, match="must be numbers"):
        poses_from_array([["a"] * 6])
    with pytest.raises(PincalError):
        compensate(stewart, [[1.0, 2.0]])

"""The calibration directory: one writer, one reader, atomic, versioned, checked."""

from __future__ import annotations

import hashlib
import json
import shutil

import numpy as np
import pytest

from pincal.errors import CalibrationDirectoryError
from pincal.identification import identify, result_to_dict
from pincal.io import (
    CALIBRATED_SIDECAR,
    CALIBRATED_URDF,
    CALIBRATION_VERSION,
    MANIFEST,
    read_calibration,
    save_urdf,
    write_calibration,
    write_measurements,
)
from pincal.measure import NoiseModel, simulate_measurements
from pincal.model import load_mechanism, parameters, sample_actuators


@pytest.fixture(scope="module")
def wedge_result(tmp_path_factory):
    nominal = load_mechanism("wedge3")
    params = parameters(nominal, "patent")
    rng = np.random.default_rng(3)
    true = rng.normal(0, 2e-4, len(params))
    actual = params.apply(nominal, true)
    q = sample_actuators(nominal, 12, rng)
    meas = simulate_measurements(actual, q, NoiseModel(0.005, 0.01), rng)
    data = write_measurements(tmp_path_factory.mktemp("data") / "m.csv", meas)
    return nominal, identify(nominal, params, meas), data


def test_round_trip_manifest_and_calibrated_model(wedge_result, tmp_path):
    nominal, result, data = wedge_result
    cal = write_calibration(
        tmp_path / "cal", result, model_source="wedge3", data_files=[data],
        noise=NoiseModel(0.005, 0.01), texts={"report.txt": "hello\n"},
    )  # fmt: skip
    m = json.loads((tmp_path / "cal" / MANIFEST).read_text())
    assert m["format"] == "pincal calibration" and m["version"] == CALIBRATION_VERSION
    assert m["model"] == "wedge3" and m["preset"] == "patent" and m["pincal_version"]
    assert [p["name"] for p in m["parameters"]] == list(result.identified_names)
    assert m["data_files"][0]["sha256"] == hashlib.sha256(data.read_bytes()).hexdigest()
    assert m["noise"] == {"position_mm": 0.005, "orientation_mrad": 0.01}
    assert set(m["files"]) == {CALIBRATED_URDF, CALIBRATED_SIDECAR, "identification.json",
                               "report.txt"}  # fmt: skip
    assert cal.model == "wedge3" and cal.preset == "patent"
    np.testing.assert_array_equal(cal.result.values, result.values)
    np.testing.assert_allclose(cal.result.covariance, result.covariance, rtol=1e-12)
    q = sample_actuators(nominal, 3, np.random.default_rng(0))
    for row in q:
        a = cal.calibrated().forward(row)
        b = result.calibrated.forward(row)
        np.testing.assert_allclose(a.translation, b.translation, atol=1e-12)
    assert cal.nominal().name == "wedge3"
    assert not list(tmp_path.glob(".cal.*"))  # no temporary left behind


def test_missing_sidecar_changed_file_and_newer_version_are_named(wedge_result, tmp_path):
    _, result, _ = wedge_result
    write_calibration(tmp_path / "a", result)
    shutil.copytree(tmp_path / "a", tmp_path / "b")
    (tmp_path / "b" / CALIBRATED_SIDECAR).unlink()  # copying only the URDF
    with pytest.raises(CalibrationDirectoryError, match="missing.*calibrated.yaml"):
        read_calibration(tmp_path / "b")
    shutil.copytree(tmp_path / "a", tmp_path / "c")
    urdf = tmp_path / "c" / CALIBRATED_URDF
    urdf.write_text(urdf.read_text().replace("<robot", "<!-- x -->\n<robot", 1))
    with pytest.raises(CalibrationDirectoryError, match="SHA-256"):
        read_calibration(tmp_path / "c")
    shutil.copytree(tmp_path / "a", tmp_path / "d")
    m = json.loads((tmp_path / "d" / MANIFEST).read_text())
    m["version"] = CALIBRATION_VERSION + 1
    (tmp_path / "d" / MANIFEST).write_text(json.dumps(m))
    with pytest.raises(CalibrationDirectoryError, match="upgrade pincal"):
        read_calibration(tmp_path / "d")
    with pytest.raises(CalibrationDirectoryError, match="does not exist"):
        read_calibration(tmp_path / "nowhere")
    with pytest.raises(CalibrationDirectoryError, match="not a calibration directory"):
        read_calibration(tmp_path)


def test_write_is_whole_or_absent(wedge_result, tmp_path, monkeypatch):
    import pincal.io._calibration_write as mod

    _, result, _ = wedge_result

    def broken(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(mod, "save_urdf", broken)
    with pytest.raises(OSError):
        write_calibration(tmp_path / "cal", result)
    assert list(tmp_path.iterdir()) == []
    monkeypatch.undo()
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "notes.txt").write_text("mine")
    with pytest.raises(CalibrationDirectoryError, match="not a calibration directory"):
        write_calibration(tmp_path / "other", result)
    assert (tmp_path / "other" / "notes.txt").read_text() == "mine"


def test_rewriting_replaces_an_old_calibration(wedge_result, tmp_path):
    _, result, _ = wedge_result
    write_calibration(tmp_path / "cal", result, texts={"old.txt": "x"})
    write_calibration(tmp_path / "cal", result)
    assert not (tmp_path / "cal" / "old.txt").exists()
    assert read_calibration(tmp_path / "cal").model == "wedge3"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cal"]


def test_a_directory_without_manifest_is_not_a_calibration(wedge_result, tmp_path):
    """The pre-manifest layout is not read: nothing would prove its files belong together."""
    _, result, _ = wedge_result
    d = tmp_path / "old"
    d.mkdir()
    save_urdf(result.calibrated, d / "wedge3_calibrated.urdf")
    (d / "identification.json").write_text(json.dumps(result_to_dict(result)))
    with pytest.raises(CalibrationDirectoryError, match="has no calibration.json, the manifest"):
        read_calibration(d)



"""A calibration directory cannot lie: what the manifest lists is checked before use.

Each case edits a directory written by :func:`write_calibration` the way a user (or an
attacker) could, re-hashing where that would hide the edit, and asserts the read refuses
with a message naming the file and what is valid.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from pincal._limits import Limits
from pincal.cli import main
from pincal.errors import CalibrationDirectoryError, PincalError
from pincal.identification import identify
from pincal.io import (
    CALIBRATED_URDF,
    IDENTIFICATION_FILE,
    MANIFEST,
    read_calibration,
    write_calibration,
    write_measurements,
    write_poses,
)
from pincal.measure import NoiseModel, simulate_measurements
from pincal.model import load_mechanism, parameters, resolve_model_path, sample_actuators


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    """A wedge3 calibration whose nominal model is a copy (so it can be edited)."""
    root = tmp_path_factory.mktemp("integrity")
    urdf, side = resolve_model_path("wedge3")
    model = root / "model"
    model.mkdir()
    shutil.copy(urdf, model / Path(urdf).name)
    if side is not None:
        shutil.copy(side, model / Path(side).name)
    nominal = load_mechanism(model / Path(urdf).name)
    params = parameters(nominal, "patent")
    rng = np.random.default_rng(3)
    actual = params.apply(nominal, rng.normal(0, 2e-4, len(params)))
    q = sample_actuators(nominal, 12, rng)
    meas = simulate_measurements(actual, q, NoiseModel(0.005, 0.01), rng)
    data = write_measurements(root / "m.csv", meas)
    result = identify(nominal, params, meas)
    cal = write_calibration(
        root / "cal", result, model_source=str(model / Path(urdf).name), data_files=[data]
    )
    poses = [actual.forward(row) for row in q[:3]]
    write_poses(root / "targets.csv", poses, actuated=nominal.actuated, q_act=q[:3])
    return root, cal.path, model / Path(urdf).name


@pytest.fixture
def cal(made, tmp_path) -> Path:
    d = tmp_path / "cal"
    shutil.copytree(made[1], d)
    return d


def _manifest(d: Path) -> dict:
    return json.loads((d / MANIFEST).read_text())


def _save(d: Path, manifest: dict, rehash: bool = True) -> None:
    if rehash:
        for name in manifest.get("files", {}):
            if (d / name).is_file():
                manifest["files"][name] = hashlib.sha256((d / name).read_bytes()).hexdigest()
    (d / MANIFEST).write_text(json.dumps(manifest))


def _edit_ident(d: Path, change) -> None:
    doc = json.loads((d / IDENTIFICATION_FILE).read_text())
    change(doc)
    (d / IDENTIFICATION_FILE).write_text(json.dumps(doc))


def _shift_urdf(d: Path) -> None:
    """Move the first joint origin by 5 mm in calibrated.urdf."""
    text = (d / CALIBRATED_URDF).read_text()
    head, tail = text.split('xyz="', 1)
    x, rest = tail.split(" ", 1)
    (d / CALIBRATED_URDF).write_text(f'{head}xyz="{float(x) + 0.005!r} {rest}')


def test_a_written_calibration_reads_back_consistent(cal):
    c = read_calibration(cal)
    assert c.caveat is None
    assert set(c.manifest["model_files"]) and c.calibrated() is not None


def test_deleted_manifest_and_edited_urdf_is_refused(cal):
    (cal / MANIFEST).unlink()
    _shift_urdf(cal)
    with pytest.raises(CalibrationDirectoryError, match="has no calibration.json"):
        read_calibration(cal)


def test_manifest_without_files_is_refused(cal):
    m = _manifest(cal)
    del m["files"]
    _save(cal, m, rehash=False)
    _shift_urdf(cal)
    with pytest.raises(CalibrationDirectoryError, match="'files' must map each file"):
        read_calibration(cal)


@pytest.mark.parametrize("name", ["../../etc/hostname", "/etc/passwd", ".hidden", "a/b"])
def test_manifest_names_outside_the_directory_are_refused(cal, name):
    m = _manifest(cal)
    m["files"][name] = "0" * 64
    _save(cal, m, rehash=False)
    with pytest.raises(CalibrationDirectoryError, match="not a plain file name") as exc:
        read_calibration(cal)
    assert MANIFEST in str(exc.value)


def test_a_listed_file_over_the_cap_is_refused_without_reading(cal, monkeypatch):
    big = cal / "big.bin"
    with open(big, "wb") as fh:
        fh.truncate(3 * 1024 * 1024)  # sparse: nothing to read if the size is checked first
    m = _manifest(cal)
    m["files"]["big.bin"] = "0" * 64
    _save(cal, m, rehash=False)
    with (
        Limits(file_bytes=2**20).applied(),
        pytest.raises(CalibrationDirectoryError, match="over the 1 MB limit.*PINCAL_MAX_FILE_MB"),
    ):
        read_calibration(cal)


def test_a_listed_file_that_is_a_link_is_refused(cal, tmp_path):
    outside = tmp_path / "outside.txt"
    outside.write_text("secret\n")
    m = _manifest(cal)
    os.symlink(outside, cal / "notes.txt")
    m["files"]["notes.txt"] = hashlib.sha256(b"secret\n").hexdigest()
    _save(cal, m, rehash=False)
    with pytest.raises(CalibrationDirectoryError, match="is a symbolic link"):
        read_calibration(cal)


def test_edited_nominal_model_is_refused(made, tmp_path):
    _, d, urdf = made
    copy = tmp_path / "model"
    shutil.copytree(urdf.parent, copy)
    cal = tmp_path / "cal"
    shutil.copytree(d, cal)
    m = _manifest(cal)
    m["model_source"] = str(copy / urdf.name)
    m["model_files"] = {str(copy / p): h for p, h in
                        ((Path(k).name, v) for k, v in m["model_files"].items())}  # fmt: skip
    _save(cal, m)
    read_calibration(cal).nominal()  # the copy is the same model
    text = (copy / urdf.name).read_text()
    head, tail = text.split('xyz="', 1)
    (copy / urdf.name).write_text(f'{head}xyz="0.005 {tail.split(" ", 1)[1]}')
    with pytest.raises(CalibrationDirectoryError, match="changed after the calibration") as exc:
        read_calibration(cal).nominal()
    assert urdf.name in str(exc.value)


def test_identification_values_edited_and_rehashed_are_refused(cal):
    def shift(doc: dict) -> None:
        doc["parameters"][0]["value"] += 5e-3

    _edit_ident(cal, shift)
    m = _manifest(cal)
    m["parameters"][0]["value"] += 5e-3  # the attacker edits the manifest's copy too
    _save(cal, m)
    c = read_calibration(cal)  # the manifest agrees with identification.json now
    with pytest.raises(CalibrationDirectoryError, match="away from the nominal model"):
        c.calibrated()


def test_manifest_values_disagreeing_with_identification_are_refused(cal):
    m = _manifest(cal)
    m["parameters"][0]["value"] += 5e-3
    _save(cal, m)
    with pytest.raises(CalibrationDirectoryError, match="disagree"):
        read_calibration(cal)


def test_negative_definite_covariance_is_refused(cal):
    _edit_ident(cal, lambda doc: doc.update(covariance=(-np.eye(len(doc["covariance"]))).tolist()))
    _save(cal, _manifest(cal))
    with pytest.raises(CalibrationDirectoryError, match="negative variance"):
        read_calibration(cal)


def test_indefinite_covariance_is_refused(cal):
    def correlate_twice(doc: dict) -> None:
        c = np.array(doc["covariance"])
        c[0, 1] = c[1, 0] = 2.0 * np.sqrt(c[0, 0] * c[1, 1])  # a correlation of 2
        doc["covariance"] = c.tolist()

    _edit_ident(cal, correlate_twice)
    _save(cal, _manifest(cal))
    with pytest.raises(CalibrationDirectoryError, match="not positive semi-definite"):
        read_calibration(cal)


@pytest.mark.parametrize(
    "where, change",
    [
        (MANIFEST, lambda m: m.update(parameters="x")),
        (MANIFEST, lambda m: m.update(files=[CALIBRATED_URDF])),
        (MANIFEST, lambda m: m.update(noise="loud")),
        (MANIFEST, lambda m: m.update(version="1")),
        (IDENTIFICATION_FILE, lambda d: d.update(covariance="abc")),
        (IDENTIFICATION_FILE, lambda d: d.update(parameters={"a": 1})),
        (IDENTIFICATION_FILE, lambda d: d["parameters"][0].update(std="wide")),
    ],
)
def test_wrong_json_types_name_the_file(cal, where, change):
    doc = json.loads((cal / where).read_text())
    change(doc)
    (cal / where).write_text(json.dumps(doc))
    if where == IDENTIFICATION_FILE:
        _save(cal, _manifest(cal))
    with pytest.raises(CalibrationDirectoryError) as exc:
        read_calibration(cal)
    assert where in str(exc.value)


def test_deeply_nested_json_is_refused(cal):
    (cal / MANIFEST).write_text("[" * 100_000 + "]" * 100_000)
    with pytest.raises(CalibrationDirectoryError, match="nested too deeply|JSON"):
        read_calibration(cal)


def test_a_forced_calibration_is_announced_on_every_use(made, cal):
    root = made[0]
    m = _manifest(cal)
    m["quality"] = {"passed": False, "overridden": True, "reason": "reduced χ² 412 > 100"}
    _save(cal, m)
    assert "written with --force past the quality gate" in read_calibration(cal).caveat
    targets, out = root / "targets.csv", cal.parent / "c.csv"
    args = ["compensate", str(cal), "--targets", str(targets), "--out", str(out)]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    assert "pincal: warning: calibration" in res.stderr and "--force" in res.stderr


@pytest.mark.parametrize(
    "name, text", [(CALIBRATED_URDF, "<robot"), ("calibrated.yaml", "a: [b\n")]
)
def test_a_malformed_file_of_the_directory_is_named(cal, name, text):
    (cal / name).write_text(text)
    _save(cal, _manifest(cal))  # re-hashed: the content, not the hash, is what is wrong
    with pytest.raises(PincalError) as exc:
        read_calibration(cal).calibrated()
    assert f"cal/{name}" in str(exc.value)

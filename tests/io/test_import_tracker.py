"""Import of a tracker point export + controller log into a ``targets`` file."""

from __future__ import annotations

import hashlib
import json
from datetime import UTC, datetime, timedelta
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.errors import BadValueError, ImportMatchError, MeasurementError, PoseFitError
from pincal.io import (
    TargetMeasurements,
    TrackerImportOptions,
    import_tracker,
    read_measurement_file,
    read_measurements,
    write_target_measurements,
)
from pincal.io._delimited import read_table
from pincal.measure import simulate_measurements
from pincal.model import COMPONENTS, load_mechanism, parameters, sample_actuators

LOCAL = np.array([[0.08, 0.0, 0.02], [-0.04, 0.07, 0.01], [-0.04, -0.07, 0.03], [0.0, 0.0, 0.09]])
NAMES = ("SMR1", "SMR2", "SMR3", "SMR4")
M = 9


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    """A simulated campaign: actual machine with errors, tracker points with noise."""
    nominal = load_mechanism("hexaslide_6pus")
    params = parameters(nominal, "pus54")
    rng = np.random.default_rng(7)
    actual = params.apply(nominal, rng.uniform(-1e-3, 1e-3, len(params)))
    q = sample_actuators(nominal, M, rng)
    meas = simulate_measurements(actual, q, None, rng, COMPONENTS)
    pts = np.einsum("mij,tj->mti", meas.rotations, LOCAL) + meas.positions[:, None, :]
    pts = pts + rng.normal(0.0, 1e-5, pts.shape)
    data = TargetMeasurements(q, pts, LOCAL, NAMES, nominal.measured_frame, nominal.actuated)
    orig = tmp_path_factory.mktemp("orig") / "orig.csv"
    write_target_measurements(orig, data)
    return nominal, data, orig


def _num(v: float, comma: bool) -> str:
    s = repr(float(v))
    return s.replace(".", ",") if comma else s


def _write_pair(tmp, data, *, delim=";", comma=True, unit=1e3, time=False, seed=3):
    """Long-format points (mm, shuffled) + log (mm, shuffled) + targets; the log order."""
    rng = np.random.default_rng(seed)
    t0 = datetime(2026, 11, 23, 9, 0, tzinfo=UTC)
    ids = [f"P{i + 1:02d}" for i in range(M)]
    times = [t0 + timedelta(seconds=20 * i) for i in range(M)]
    rows = []
    for i in range(M):
        for j, n in enumerate(NAMES):
            key = (times[i] + timedelta(seconds=0.1 * j)).isoformat() if time else ids[i]
            rows.append([key, n, *(_num(v * unit, comma) for v in data.points[i, j])])
    head = "Timestamp" if time else "Group"
    lines = [f"# exported by a tracker{delim}units mm", delim.join([head, "Name", "X", "Y", "Z"])]
    lines += [delim.join(rows[k]) for k in rng.permutation(len(rows))]
    (tmp / "points.txt").write_text("\n".join(lines) + "\n")
    order = rng.permutation(M)
    key = "time" if time else "pose"
    log = [delim.join([key, *(f"{a} [mm]" for a in data.actuated)])]
    for i in order:
        k = times[i].isoformat() if time else ids[i]
        log.append(delim.join([k, *(_num(v * 1e3, comma) for v in data.q_act[i])]))
    (tmp / "log.csv").write_text("\n".join(log) + "\n")
    tl = [delim.join(["point", "x", "y", "z"])]
    tl += [
        delim.join([n, *(_num(v * unit, comma) for v in p)])
        for n, p in zip(NAMES, LOCAL, strict=True)
    ]
    (tmp / "targets.csv").write_text("\n".join(tl) + "\n")
    return order


def _digest(tmp):
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in tmp.iterdir()}


def _compare(nominal, orig, out, order):
    a = read_measurements(orig, nominal)
    b = read_measurements(out, nominal)
    np.testing.assert_allclose(b.q_act, a.q_act[order], rtol=0, atol=1e-12)
    np.testing.assert_allclose(b.positions, a.positions[order], rtol=0, atol=1e-12)
    np.testing.assert_allclose(b.rotations, a.rotations[order], rtol=0, atol=1e-12)
    ta = read_measurement_file(orig, nominal).targets
    tb = read_measurement_file(out, nominal).targets
    np.testing.assert_allclose(tb.points, ta.points[order], rtol=0, atol=1e-12)
    np.testing.assert_allclose(tb.targets_local, ta.targets_local, rtol=0, atol=1e-12)


def test_pose_id_import_semicolon_decimal_comma_mm(campaign, tmp_path):
    nominal, data, orig = campaign
    order = _write_pair(tmp_path, data)
    before = _digest(tmp_path)
    opts = TrackerImportOptions(length_unit="mm", point_columns={"pose": "Group"})
    res = import_tracker(
        tmp_path / "points.txt", tmp_path / "log.csv", tmp_path / "targets.csv", nominal, opts
    )
    assert res.match == "pose" and res.max_time_offset is None
    assert res.pose_ids == tuple(f"P{i + 1:02d}" for i in order)
    out = write_target_measurements(tmp_path / "out.csv", res.targets)
    _compare(nominal, orig, out, order)
    before["out.csv"] = _digest(tmp_path)["out.csv"]
    assert _digest(tmp_path) == before  # inputs untouched


def test_time_import_tab_cli_json(campaign, tmp_path):
    nominal, data, orig = campaign
    order = _write_pair(tmp_path, data, delim="\t", comma=False, time=True)
    out = tmp_path / "out.csv"
    args = ["import-tracker", str(tmp_path / "points.txt"), "--log", str(tmp_path / "log.csv"),
            "--targets", str(tmp_path / "targets.csv"), "--model", "hexaslide_6pus",
            "--unit", "mm", "--tolerance", "0.5", "--out", str(out), "--json"]  # fmt: skip
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    summary = json.loads(res.output)
    assert summary["match"] == "time" and summary["poses"] == M
    assert summary["max_time_offset_s"] == pytest.approx(0.3)
    _compare(nominal, orig, out, order)
    # a tighter tolerance leaves the later targets of each pose unmatched: listed lines
    res = CliRunner().invoke(main, [*args[:-5], "--tolerance", "0.15", "--out", str(out)])
    assert res.exit_code == 1
    assert "ImportMatchError" in res.output and "points have no controller-log row" in res.output


def test_unmatched_and_missing_rows_are_listed(campaign, tmp_path):
    nominal, data, _ = campaign
    _write_pair(tmp_path, data)
    opts = TrackerImportOptions(length_unit="mm")
    files = (tmp_path / "points.txt", tmp_path / "log.csv", tmp_path / "targets.csv")
    log = files[1].read_text().splitlines()
    files[1].write_text("\n".join([*log, log[1].replace("P", "Q", 1)]) + "\n")
    with pytest.raises(ImportMatchError, match=r"1 rows have no tracker points.*lines 11") as e:
        import_tracker(*files, nominal, opts)
    assert e.value.log_lines == [11]
    files[1].write_text("\n".join(log) + "\n")
    pts = files[0].read_text().splitlines()
    gone = pts.pop(5)
    files[0].write_text("\n".join(pts) + "\n")
    pose, name = gone.split(";")[:2]
    with pytest.raises(ImportMatchError, match=f"pose '{pose}'.*{name}"):
        import_tracker(*files, nominal, opts)
    files[0].write_text("\n".join([*pts, gone, gone]) + "\n")
    with pytest.raises(ImportMatchError, match="measured twice"):
        import_tracker(*files, nominal, opts)


def test_bad_cell_unit_and_fit_errors(campaign, tmp_path):
    nominal, data, _ = campaign
    _write_pair(tmp_path, data)
    files = (tmp_path / "points.txt", tmp_path / "log.csv", tmp_path / "targets.csv")
    with pytest.raises(MeasurementError, match="length unit .* is unknown; state it"):
        import_tracker(*files, nominal)
    pts = files[0].read_text().splitlines()
    cells = pts[4].split(";")
    cells[3] = "abc"
    files[0].write_text("\n".join([*pts[:4], ";".join(cells), *pts[5:]]) + "\n")
    with pytest.raises(BadValueError, match=r"points.txt line 5, column 'Y': 'abc'"):
        import_tracker(*files, nominal, TrackerImportOptions(length_unit="mm"))
    cells[3] = "0,5"  # a target moved by ~0.5 m in one pose
    files[0].write_text("\n".join([*pts[:4], ";".join(cells), *pts[5:]]) + "\n")
    opts = TrackerImportOptions(length_unit="mm", max_residual=0.1)
    with pytest.raises(PoseFitError, match=f"pose '{cells[0]}' \\(log line"):
        import_tracker(*files, nominal, opts)


def test_out_must_not_be_an_input(campaign, tmp_path):
    _, data, _ = campaign
    _write_pair(tmp_path, data)
    before = _digest(tmp_path)
    res = CliRunner().invoke(main, [
        "import-tracker", str(tmp_path / "points.txt"), "--log", str(tmp_path / "log.csv"),
        "--targets", str(tmp_path / "targets.csv"), "--model", "hexaslide_6pus",
        "--unit", "mm", "--out", str(tmp_path / "log.csv")])  # fmt: skip
    assert res.exit_code == 1 and "inputs are never modified" in res.output
    assert _digest(tmp_path) == before


@pytest.mark.parametrize(
    ("text", "delim", "dec", "value"),
    [
        ("a,b\n1.5,2\n", ",", ".", 1.5),
        ("a;b\n1,5;2\n", ";", ",", 1.5),
        ("a\tb\n-1,5e-3\t2\n", "\t", ",", -1.5e-3),
        ("# note, with; marks\na;b\n1.5;2\n", ";", ".", 1.5),
    ],
)
def test_delimiter_and_decimal_detection(tmp_path, text, delim, dec, value):
    p = tmp_path / "t.txt"
    p.write_text(text)
    t = read_table(p)
    assert (t.delimiter, t.decimal) == (delim, dec)
    assert t.number(0, 0) == value
    assert t.lines[0] == text.count("\n")


def test_wrong_field_count_names_line(tmp_path):
    p = tmp_path / "t.csv"
    p.write_text("a;b\n1;2\n3\n")
    with pytest.raises(MeasurementError, match="t.csv line 3: 1 fields"):
        read_table(p)


def test_documented_example_files_import(tmp_path):
    ex = Path(__file__).resolve().parents[2] / "docs" / "examples" / "tracker"
    nominal = load_mechanism("hexaslide_6pus")
    files = (ex / "points.csv", ex / "controller_log.csv", ex / "targets_local.csv")
    before = {p: p.read_bytes() for p in files}
    by_pose = import_tracker(*files, nominal, TrackerImportOptions(point_std=0.005))
    by_time = import_tracker(
        *files, nominal, TrackerImportOptions(match="time", tolerance=5.0, point_std=0.005)
    )
    assert by_pose.match == "pose" and by_time.max_time_offset == pytest.approx(3.0)
    np.testing.assert_array_equal(by_pose.targets.points, by_time.targets.points)
    assert by_pose.targets.point_std == pytest.approx(5e-6)
    out = write_target_measurements(tmp_path / "t.csv", by_pose.targets)
    meas = read_measurements(out, nominal)
    assert len(meas) == 16 and meas.std is not None
    with pytest.raises(ImportMatchError, match="points have no controller-log row"):
        import_tracker(*files, nominal, TrackerImportOptions(match="time", tolerance=2.5))
    assert {p: p.read_bytes() for p in files} == before


def test_ambiguous_time_and_unknown_points(tmp_path):
    ex = Path(__file__).resolve().parents[2] / "docs" / "examples" / "tracker"
    nominal = load_mechanism("hexaslide_6pus")
    log, targets = ex / "controller_log.csv", ex / "targets_local.csv"
    with pytest.raises(ImportMatchError, match="within 30.0 s of two controller-log rows") as e:
        import_tracker(ex / "points.csv", log, targets, nominal, TrackerImportOptions("time", 30.0))
    assert e.value.points_lines[0] == 5  # P1 SMR3, 29 s before the P2 log row
    lines = (ex / "points.csv").read_text().splitlines()
    extra = "P3;BASE1;1000,0;0,0;0,0;2026-11-23T09:31:05.000"
    (tmp_path / "p.csv").write_text("\n".join([*lines[:9], extra, *lines[9:]]) + "\n")
    with pytest.raises(ImportMatchError, match=r"points \['BASE1'\] .* lines 10;"):
        import_tracker(tmp_path / "p.csv", log, targets, nominal)
    for match in ("pose", "time"):
        opts = TrackerImportOptions(match, 5.0, ignore_unknown_points=True)
        got = import_tracker(tmp_path / "p.csv", log, targets, nominal, opts)
        ref = import_tracker(ex / "points.csv", log, targets, nominal, opts)
        np.testing.assert_array_equal(got.targets.points, ref.targets.points)

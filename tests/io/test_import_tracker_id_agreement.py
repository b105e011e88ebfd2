"""``import-tracker --match time``: when both files give pose ids, they must agree."""

from __future__ import annotations

from datetime import UTC, datetime, timedelta

import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.errors import ImportMatchError
from pincal.io import TrackerImportOptions, import_tracker
from tests.io.test_import_tracker import LOCAL, NAMES, M, campaign  # noqa: F401 - fixture


def _write(tmp, data, swap: bool) -> None:
    """Points and log with both pose ids and times; ``swap`` exchanges two log ids."""
    t0 = datetime(2026, 11, 23, 9, 0, tzinfo=UTC)
    ids = [f"P{i + 1}" for i in range(M)]
    times = [(t0 + timedelta(seconds=20 * i)).isoformat() for i in range(M)]
    pts = ["Group,Timestamp,Name,X,Y,Z"]
    for i in range(M):
        for j, n in enumerate(NAMES):
            pts.append(
                ",".join([ids[i], times[i], n, *(repr(float(v)) for v in data.points[i, j])])
            )
    (tmp / "points.csv").write_text("\n".join(pts) + "\n")
    log_ids = list(ids)
    if swap:
        log_ids[1], log_ids[2] = log_ids[2], log_ids[1]
    log = [",".join(["pose", "time", *data.actuated])]
    for i in range(M):
        log.append(",".join([log_ids[i], times[i], *(repr(float(v)) for v in data.q_act[i])]))
    (tmp / "log.csv").write_text("\n".join(log) + "\n")
    tl = ["point,x,y,z"] + [
        ",".join([n, *map(repr, map(float, p))]) for n, p in zip(NAMES, LOCAL, strict=True)
    ]
    (tmp / "targets.csv").write_text("\n".join(tl) + "\n")


def test_time_match_with_agreeing_ids_imports(campaign, tmp_path):  # noqa: F811
    nominal, data, _ = campaign
    _write(tmp_path, data, swap=False)
    opts = TrackerImportOptions(match="time", tolerance=1.0, length_unit="m")
    res = import_tracker(tmp_path / "points.csv", tmp_path / "log.csv", tmp_path / "targets.csv",
                         nominal, opts)  # fmt: skip
    assert res.match == "time" and len(res.pose_ids) == M


def test_time_match_with_disagreeing_ids_is_refused(campaign, tmp_path):  # noqa: F811
    nominal, data, _ = campaign
    _write(tmp_path, data, swap=True)
    opts = TrackerImportOptions(match="time", tolerance=1.0, length_unit="m")
    with pytest.raises(ImportMatchError, match="another pose id") as exc:
        import_tracker(tmp_path / "points.csv", tmp_path / "log.csv", tmp_path / "targets.csv",
                       nominal, opts)  # fmt: skip
    msg = str(exc.value)
    assert "'P2'" in msg and "'P3'" in msg and "points.csv" in msg and "--match pose" in msg
    assert exc.value.points_lines[:4] == [6, 7, 8, 9]  # the 4 points of P2


def test_cli_time_match_with_disagreeing_ids_is_refused(campaign, tmp_path):  # noqa: F811
    _, data, _ = campaign
    _write(tmp_path, data, swap=True)
    args = ["import-tracker", str(tmp_path / "points.csv"), "--log", str(tmp_path / "log.csv"),
            "--targets", str(tmp_path / "targets.csv"), "--model", "hexaslide_6pus",
            "--match", "time", "--tolerance", "1", "--unit", "m",
            "--out", str(tmp_path / "out.csv")]  # fmt: skip
    res = CliRunner().invoke(main, args)
    assert (
        res.exit_code == 1 and "ImportMatchError" in res.output and "another pose id" in res.output
    )
    assert not (tmp_path / "out.csv").exists()

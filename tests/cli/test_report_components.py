"""Reports split position and orientation by what was measured, name the components and
keep each block's unit — through the CLI: poses → simulate → calibrate → validate → report.

Machines measuring [x, y, rz] (the planar 3-RRR of tests/model/machines/rrr3, written in
another engineer's habits), [x, y, z] (the delta of tests/open_world/machines.py,
``measured: position``), [y, z, rx, ry] (pkm5 as bundled), [x, y, z, rx, ry] (the
Stewart platform with rz left out of its sidecar) and the full pose (stewart_6ups). The
numbers of every report (report.txt, report.md / .json / .html) must be the ones the CLI
printed.
"""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.model import load_mechanism
from tests.open_world.machines import delta_4r, write_machine

RRR3 = str(Path(__file__).parents[1] / "model" / "machines" / "rrr3" / "rrr3.urdf")
POS, ORI = ("x", "y", "z"), ("rx", "ry", "rz")


def _variant(tmp: Path, model: str, measured: str) -> str:
    """A copy of bundled ``model`` whose sidecar declares ``measured: <measured>``."""
    src = Path(load_mechanism(model).source)
    src = src if src.is_dir() else src.parent
    tag = re.sub(r"\W", "", measured)
    name = f"{model}_{tag}"
    dst = tmp / name
    dst.mkdir()
    shutil.copy(src / f"{model}.urdf", dst / f"{name}.urdf")
    text = (src / f"{model}.yaml").read_text()
    text, n = re.subn(r"(?m)^measured:.*$", f"measured: {measured}", text)
    assert n == 1
    (dst / f"{name}.yaml").write_text(text)
    return str(dst / f"{name}.urdf")


# (id, model (or a variant to build), preset, expected components)
CASES = [
    ("rrr3", RRR3, None, "base", ("x", "y", "rz")),
    ("delta", "delta", None, "base", ("x", "y", "z")),
    ("pkm5", "pkm5", None, "identifiable20", ("y", "z", "rx", "ry")),
    ("stewart-5", "stewart_6ups", "[x, y, z, rx, ry]", "base", ("x", "y", "z", "rx", "ry")),
    ("stewart", "stewart_6ups", None, "stewart42", POS + ORI),
]
#: cases run in the slow lane only (~10 s of calibration each); the fast lane keeps a
#: mixed planar set (rrr3) and a position-only one (delta)
SLOW_CASES = {"pkm5", "stewart-5", "stewart"}


def _ok(args: list[str]):
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output + (res.stderr or "")
    return res


def _label(block: str, comps: tuple[str, ...]) -> str:
    names = [c for c in comps if c in (POS if block == "position" else ORI)]
    return f"{block} ({' '.join(names)})"


def _table(report: dict, title: str, k: int = 0) -> dict[str, list]:
    """{first cell: row} of table k of the report.json section ``title``."""
    section = next(s for s in report["sections"] if s["title"] == title)
    return {str(row[0]): row for row in section["tables"][k]["rows"]}


@pytest.fixture(
    scope="module",
    params=[
        pytest.param(c, id=c[0], marks=[pytest.mark.slow] if c[0] in SLOW_CASES else [])
        for c in CASES
    ],
)
def campaign(request, tmp_path_factory):
    """Runs the campaign once per machine; returns what the CLI printed and wrote."""
    _, model, measured, preset, comps = request.param
    tmp = tmp_path_factory.mktemp(request.param[0])
    if measured is not None:
        model = _variant(tmp, model, measured)
    elif model == "delta":
        model = str(write_machine(tmp, "delta", *delta_4r()))
    _ok(["poses", model, "--count", "30", "--candidates", "random:150", "--restarts", "1",
         "--preset", preset, "--out", str(tmp / "poses.csv")])  # fmt: skip
    _ok(["simulate", model, "--poses", str(tmp / "poses.csv"), "--params", preset,
         "--out", str(tmp / "m.csv")])  # fmt: skip
    _ok(["simulate", model, "--random", "15", "--seed", "9", "--params", preset,
         "--out", str(tmp / "v.csv")])  # fmt: skip
    cal = tmp / "cal"
    res = _ok(["calibrate", model, "--data", str(tmp / "m.csv"), "--params", preset,
               "--out", str(cal), "--json"])  # fmt: skip
    doc = json.loads(res.stdout)
    text = _ok(["validate", str(cal), "--data", str(tmp / "v.csv"),
                "--out", str(tmp / "v.json")]).stdout  # fmt: skip
    val = json.loads((tmp / "v.json").read_text())
    _ok(["report", str(cal), "--validation", str(tmp / "v.json"),
         "--truth", str(tmp / "m.truth.json"), "--design", str(tmp / "poses.json")])  # fmt: skip
    return {
        "comps": comps,
        "doc": doc,
        "validate_text": text,
        "validation": val,
        "txt": (cal / "report.txt").read_text(),
        "md": (cal / "report.md").read_text(),
        "html": (cal / "report.html").read_text(),
        "json": json.loads((cal / "report.json").read_text()),
    }


def _blocks(comps: tuple[str, ...]) -> list[tuple[str, str, str]]:
    """(block, unit of the summary keys, its label) of the measured blocks."""
    out = []
    for block, unit in (("position", "mm"), ("orientation", "mrad")):
        if any(c in (POS if block == "position" else ORI) for c in comps):
            out.append((block, unit, _label(block, comps)))
    return out


def test_the_calibration_records_and_names_its_components(campaign):
    comps, doc = campaign["comps"], campaign["doc"]
    assert tuple(doc["components"]) == comps
    report = campaign["json"]
    assert report["components"]["measured"] == list(comps)
    assert report["components"]["position"] == [c for c in comps if c in POS]
    assert report["components"]["orientation"] == [c for c in comps if c in ORI]
    data = _table(report, "Data and noise")
    assert data["measured components"][1] == " ".join(comps)
    assert f"| measured components | {' '.join(comps)} |" in campaign["md"]
    for _, _, label in _blocks(comps):
        assert f"noise σ {label}" in data
    shown = {b for b, _, _ in _blocks(comps)}
    for block in {"position", "orientation"} - shown:  # a block not measured: no row
        assert not any(k.startswith(f"noise σ {block}") for k in data)


def test_residuals_in_every_report_are_the_cli_numbers(campaign):
    comps, doc = campaign["comps"], campaign["doc"]
    rows = _table(campaign["json"], "Residuals")
    assert set(rows) == {label for _, _, label in _blocks(comps)}
    for block, unit, label in _blocks(comps):
        before, after = doc["residuals"]["before"], doc["residuals"]["after"]
        expected = [before[f"rms_{block}_{unit}"], before[f"max_{block}_{unit}"],
                    after[f"rms_{block}_{unit}"], after[f"max_{block}_{unit}"]]  # fmt: skip
        got = rows[label][2:]
        assert got == pytest.approx([round(v * 1e3, 3) for v in expected], abs=1.5e-3)
        assert rows[label][1] == ("µm" if block == "position" else "µrad")
        md_row = f"| {label} | {rows[label][1]} | "
        assert md_row in campaign["md"] and label in campaign["html"]
        # report.txt: the line the CLI printed
        assert f"{label} RMS {after[f'rms_{block}_{unit}']:.6f}" in campaign["txt"]
    for block in ("position", "orientation"):
        if not any(c in (POS if block == "position" else ORI) for c in comps):
            assert f"{block} (" not in campaign["txt"].split("residuals before")[1]


def test_prediction_is_per_block_and_near_the_achieved(campaign):
    comps = campaign["comps"]
    # Cramér–Rao only for the linear covariance at the declared noise (the files declare it)
    linear = campaign["doc"]["quality"]["uncertainty"]["method"] == "linear"
    title = "Prediction (Cramér–Rao) vs achievement" if linear else "Prediction vs achievement"
    rows = _table(campaign["json"], title)
    assert ("Cramér–Rao" in campaign["md"].split("Prediction")[1].split("\n")[0]) == linear
    for _, _, label in _blocks(comps):
        predicted, achieved = rows[f"{label} residual RMS per component"][2:]
        assert 0.5 < achieved / predicted < 2.0  # the same unit: a fit at the noise level
    assert "RMS(error / σ) of the parameters" in rows  # the simulated truth is shown


def test_validation_section_is_the_validate_numbers(campaign):
    comps, val = campaign["comps"], campaign["validation"]
    assert tuple(val["components"]) == comps
    header = campaign["validate_text"].splitlines()[1]
    for _, unit, label in _blocks(comps):
        assert f"{label} [{unit}]" in header
    rows = _table(campaign["json"], "Validation")
    assert len(rows) == 2 * len(_blocks(comps))
    for block, unit, label in _blocks(comps):
        for stat in ("rms", "max"):
            row = rows[f"{stat.upper() if stat == 'rms' else stat} {label}"]
            assert row[2] == pytest.approx(round(val["before"][f"{stat}_{block}_{unit}"] * 1e3, 3))
            assert row[3] == pytest.approx(round(val["after"][f"{stat}_{block}_{unit}"] * 1e3, 3))
    predicted = _table(campaign["json"], "Validation", 1)
    for block, unit, label in _blocks(comps):
        value = val["predicted"][f"model_rms_{block}_{unit}"]
        assert predicted[f"RMS {label}, calibrated model"][2] == pytest.approx(
            round(value * 1e3, 3)
        )

"""A report a metrologist can sign: self-contained HTML, one convention in HTML/MD/JSON,
noise stated, outliers and poorly determined parameters flagged."""

from __future__ import annotations

import dataclasses
import json
import shutil
import subprocess
from html.parser import HTMLParser

import numpy as np
import pytest
from click.testing import CliRunner

import pincal
from pincal.cli import main
from pincal.identification import identify, result_from_dict, result_to_dict
from pincal.report import calibration_report
from pincal.report._sections import poorly_determined


class _Sources(HTMLParser):
    def __init__(self):
        super().__init__()
        self.img: list[str] = []
        self.links: list[str] = []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "img":
            self.img.append(a.get("src", ""))
        for key in ("href", "src"):
            if key in a and tag != "img":
                self.links.append(a[key])


@pytest.fixture(scope="module")
def calibration(tmp_path_factory, stewart, stewart42, stewart_poses):
    """Stewart, 30 poses, noise not declared, one pose 0.3 mm off."""
    rng = np.random.default_rng(21)
    truth = rng.normal(0.0, 3e-4, len(stewart42))
    noise = pincal.NoiseModel(0.01, 0.02)
    meas = pincal.simulate_measurements(stewart42.apply(stewart, truth), stewart_poses, noise, rng)
    positions = meas.positions.copy()
    positions[7] += [3e-4, 0.0, -2e-4]
    meas = dataclasses.replace(meas, positions=positions, noise=None)
    res = identify(stewart, stewart42, meas)
    out = tmp_path_factory.mktemp("cal")
    notes = {"data": "meas.csv", "truth": dict(zip(stewart42.names, truth, strict=True))}
    (out / "identification.json").write_text(json.dumps(result_to_dict(res, notes)))
    return out, res


def test_report_is_self_contained_and_consistent(calibration, tmp_path):
    src, res = calibration
    files = calibration_report(src, tmp_path / "rep")
    assert sorted(p.name for p in (tmp_path / "rep").iterdir()) == [
        "report.html",
        "report.json",
        "report.md",
    ]  # no side folder of plots
    page = files.html.read_text()
    parser = _Sources()
    parser.feed(page)
    assert len(parser.img) >= 5 and all(s.startswith("data:image/png;base64,") for s in parser.img)
    assert parser.links == []
    doc = json.loads(files.json.read_text())
    md = files.markdown.read_text()
    # noise stated: estimated σ in µm / µrad in all three
    assert doc["noise"]["source"] == "estimated"
    sigma_um = round(res.weighting.position_std * 1e6, 3)
    assert doc["noise"]["position_um"] == sigma_um
    assert f"{sigma_um:.6g}" in md and f"{sigma_um:.6g}" in page
    # the same parameter numbers, units in every parameter table header
    section = next(s for s in doc["sections"] if s["title"] == "Identified parameters")
    table = section["tables"][0]
    assert table["headers"][1] == "value [µm | µrad]" and table["headers"][2] == "2σ [µm | µrad]"
    for row in table["rows"]:
        name, value, two_sigma = row[0], row[1], row[2]
        k = res.identified_names.index(name)
        assert two_sigma == round(2 * res.std[k] * 1e6, 3)
        assert f"| {name} | {value:.6g} | {two_sigma:.6g} |" in md
        assert f"<td>{value:.6g}</td><td>{two_sigma:.6g}</td>" in page
    for s in doc["sections"]:
        for t in s["tables"]:
            assert any(u in h for h in t["headers"] for u in ("µm", "µrad", "unit", "σ]")) or (
                s["title"] in ("Large residuals",)
            ), (s["title"], t["headers"])
    # the displaced pose is an outlier in all three
    assert 7 in doc["flags"]["outlier_poses"]
    assert "| 7 | " in md and "<td>7</td>" in page
    # the noise is estimated: the linear covariance is not called a Cramér–Rao bound
    assert "## Prediction vs achievement" in md and "Prediction (Cramér–Rao)" not in md
    assert "not a Cramér–Rao bound: the noise is not known" in md


def test_poorly_determined_parameter_is_flagged(tmp_path):
    """A parameter with 2σ = 3.7 mm (and an angle with 2σ = 2 mrad) is flagged."""
    names, units = ("leg1.tx", "leg1.ty", "leg1.rx", "leg1.ry"), ("m", "m", "rad", "rad")
    std = [1.85e-3, 1e-5, 1e-3, 1e-5]
    doc = {
        "version": 2,
        "model": "stewart_6ups",
        "parameters": [
            {"name": n, "value": 1e-4, "std": s, "unit": u, "initial": 0.0}
            for n, s, u in zip(names, std, units, strict=True)
        ],
        "covariance": np.diag(np.square(std)).tolist(),
    }
    res = result_from_dict(doc)
    assert poorly_determined(res) == ["leg1.tx", "leg1.rx"]
    (tmp_path / "identification.json").write_text(json.dumps(doc))
    files = calibration_report(tmp_path)
    report = json.loads(files.json.read_text())
    assert report["flags"]["poorly_determined"] == ["leg1.rx", "leg1.tx"]
    assert "| leg1.tx | 100 | 3700 | µm |" in files.markdown.read_text()


def test_cli_report_writes_three_files(calibration, tmp_path):
    src, _ = calibration
    res = CliRunner().invoke(main, ["report", str(src), "--out", str(tmp_path), "--json"])
    assert res.exit_code == 0, res.output
    paths = json.loads(res.stdout)
    assert set(paths) == {"html", "markdown", "json"}
    assert all((tmp_path / name).is_file() for name in ("report.html", "report.md", "report.json"))


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("chromium") is None, reason="needs chromium")
def test_report_renders_alone_in_headless_chromium(calibration, tmp_path):
    """report.html copied alone into an empty folder renders with all its plots."""
    src, _ = calibration
    files = calibration_report(src, tmp_path / "rep")
    alone = tmp_path / "alone"
    alone.mkdir()
    shutil.copy(files.html, alone / "report.html")
    shot = tmp_path / "shot.png"
    cmd = [
        "chromium", "--headless", "--no-sandbox", "--disable-gpu",
        "--disable-background-networking", "--disable-component-update", "--no-first-run",
        f"--screenshot={shot}", "--window-size=1200,2000", "--virtual-time-budget=5000",
        (alone / "report.html").as_uri(),
    ]  # fmt: skip
    subprocess.run(cmd, check=True, capture_output=True, timeout=120, cwd=alone)
    assert shot.stat().st_size > 50_000  # text, tables and plots, not a blank page
    assert sorted(p.name for p in alone.iterdir()) == ["report.html"]

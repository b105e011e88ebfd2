"""Tests of `pincal view` / `pincal report`, the help texts and the one-line errors."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import click
import numpy as np
import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.errors import MeasurementError
from pincal.io import read_actuator_rows
from pincal.model import (
    bundled_models,
    load_mechanism,
)

BUNDLED = ["aacmm", "hexaslide_6pus", "pkm5", "stewart_6ups", "wedge3"]


def _invoke(*args: str, **kwargs):
    return CliRunner().invoke(main, list(args), **kwargs)


# ----------------------------------------------------------------------------- help


def test_group_help_lists_every_command_with_examples_and_exit_codes():
    res = _invoke("--help")
    assert res.exit_code == 0
    for name in main.commands:
        assert name in res.output
    assert "Exit codes" in res.output and "pincal view" in res.output


@pytest.mark.parametrize("command", sorted(main.commands))
def test_each_subcommand_has_help(command):
    res = _invoke(command, "--help")
    assert res.exit_code == 0, res.output
    assert res.output.startswith("Usage: ")
    assert len(res.output.splitlines()) > 4


@pytest.mark.parametrize("command", ["view", "report"])
def test_new_commands_document_examples(command):
    assert "Examples:" in _invoke(command, "--help").output


# ----------------------------------------------------------------------------- errors


@pytest.mark.parametrize(
    "args",
    [
        ["info", "no_such_model"],
        ["view", "no_such_model", "--html", "x.html"],
        ["report", "no_such_dir"],
    ],
)
def test_errors_are_one_line_exit_1_and_debug_shows_traceback(args, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 1
    assert res.output.count("\n") == 1 and res.output.startswith("pincal: error: ")
    assert "Traceback" not in res.output
    res = CliRunner().invoke(main, ["--debug", *args])
    assert res.exit_code != 0 and res.exception is not None
    assert not isinstance(res.exception, SystemExit)  # propagated with its traceback


def test_usage_errors_exit_2():
    assert _invoke("view", "stewart_6ups").exit_code == 2  # neither --html nor --live
    assert _invoke("view", "stewart_6ups", "--random", "0", "--html", "x").exit_code == 2
    assert _invoke("no-such-command").exit_code == 2


# ----------------------------------------------------------------------------- poses CSV


def test_poses_csv_reader_orders_columns_by_actuated_names(tmp_path):
    path = tmp_path / "poses.csv"
    path.write_text("# comment\nb, a ,extra\n2.0,1.0,x\n\n4,3,y\n")
    rows = read_actuator_rows(path, ("a", "b"))
    np.testing.assert_array_equal(rows, [[1.0, 2.0], [3.0, 4.0]])


@pytest.mark.parametrize(
    "text, match",
    [
        ("", "empty"),
        ("a,b\n", "no poses"),
        ("a\n1\n", r"lacks actuated joint\(s\) \['b'\]"),
        ("a,b\n1,zz\n", "line 2: non-numeric"),
        ("a,b\n1,nan\n", "NaN"),
        ("a,b\n1\n", "1 values for 2 header columns"),
    ],
)
def test_poses_csv_errors(tmp_path, text, match):
    path = tmp_path / "poses.csv"
    path.write_text(text)
    with pytest.raises(MeasurementError, match=match):
        read_actuator_rows(path, ("a", "b"))


# ----------------------------------------------------------------------------- view


def test_view_writes_html_from_a_poses_file_only_where_asked(tmp_path):
    mech = load_mechanism("stewart_6ups")
    q_home = mech.actuators_of(mech.q_home)
    rows = np.array([q_home, q_home + 0.02 * np.array([1, -1, 1, -1, 1, -1])])
    poses = tmp_path / "in" / "poses.csv"
    poses.parent.mkdir()
    poses.write_text(
        ",".join(mech.actuated) + "\n" + "\n".join(",".join(str(float(v)) for v in r) for r in rows)
    )
    out = tmp_path / "out" / "view.html"
    res = _invoke("view", "stewart_6ups", "--poses", str(poses), "--html", str(out), "--json")
    assert res.exit_code == 0, res.output
    summary = json.loads(res.stdout)
    assert summary == {"model": "stewart_6ups", "poses": 2, "up": "+z", "html": str(out)}
    page = out.read_text()
    assert "stewart_6ups: 2 poses" in page and "axes of frame <b>effector</b>" in page
    assert [p.name for p in poses.parent.iterdir()] == ["poses.csv"]  # nothing beside inputs
    assert [p.name for p in out.parent.iterdir()] == ["view.html"]


def test_view_uses_sidecar_up_direction(tmp_path):
    out = tmp_path / "pkm5.html"
    res = _invoke("view", "pkm5", "--random", "2", "--html", str(out), "--json")
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout)["up"] == "-z"
    assert "world <b>-z</b> pointing up" in out.read_text()


@pytest.fixture(scope="module")
def demo_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo")
    res = _invoke("demo", "--poses", "30", "--validation", "10", "--no-report", "--out", str(out))
    assert res.exit_code == 0, res.output
    return out


def test_view_calibrated_arrows_match_independent_forward_kinematics(demo_dir, tmp_path):
    mech = load_mechanism("stewart_6ups")
    cal = load_mechanism(demo_dir / "calibrated.urdf")
    q_act = mech.actuators_of(mech.q_home)
    poses = tmp_path / "poses.csv"
    poses.write_text(",".join(mech.actuated) + "\n" + ",".join(str(float(v)) for v in q_act) + "\n")
    out = tmp_path / "cal.html"
    res = _invoke(
        "view", "stewart_6ups", "--poses", str(poses), "--calibrated", str(demo_dir),
        "--html", str(out), "--json",
    )  # fmt: skip
    assert res.exit_code == 0, res.output
    expected = np.linalg.norm(cal.forward(q_act).translation - mech.forward(q_act).translation)
    summary = json.loads(res.stdout)
    assert summary["max_prediction_change_mm"] == pytest.approx(expected * 1e3, rel=1e-6)
    assert expected > 1e-4  # the demo's errors are 0.5 mm: a visible change
    assert f"pose 0: {expected * 1e3:.3f} mm" in out.read_text()


# ----------------------------------------------------------------------------- report


@pytest.mark.slow
def test_report_assembles_demo_output(demo_dir, tmp_path):
    res = _invoke("report", str(demo_dir), "--out", str(tmp_path / "rep"), "--json")
    assert res.exit_code == 0, res.output
    files = json.loads(res.stdout)
    md = Path(files["markdown"]).read_text()
    data = json.loads((demo_dir / "identification.json").read_text())
    rms_after = data["validation_after"]["rms_position_mm"]
    assert f"{round(rms_after * 1e3, 3):.6g}" in md  # the number from the JSON, in µm
    assert md.count("| leg") >= 12 and "see report.html" in md
    assert not (tmp_path / "rep" / "report_plots").exists()  # plots embedded in the page
    assert '<img src="data:image/png;base64,' in Path(files["html"]).read_text()
    assert not (demo_dir / "report.md").exists()  # --out respected


def test_report_uses_optional_histories(tmp_path):
    data = {
        "version": 2,
        "model": "m",
        "parameters": [
            {"name": "j.tx", "value": 1e-4, "std": 1e-5, "unit": "m", "true": 1.1e-4, "initial": 0},
            {"name": "j.rx", "value": -2e-4, "std": 3e-5, "unit": "rad", "true": -2e-4,
             "initial": 0},
        ],
        "covariance": [[1e-10, 0.0], [0.0, 9e-10]],
        "validation_before": {"rms_position_mm": 1.0, "max_position_mm": 2.0},
        "validation_after": {"rms_position_mm": 0.01, "max_position_mm": 0.02},
        "validation_errors": {
            "before": {"position": [1e-3, 2e-3, 1.5e-3]},
            "after": {"position": [1e-5, 2e-5, 1e-5]},
        },
        "cost_history": [1.0, 1e-3, 1e-6],
        "index_history": {"O1": [1.0, 2.0, 3.0]},
    }
    (tmp_path / "identification.json").write_text(json.dumps(data))
    res = _invoke("report", str(tmp_path))
    assert res.exit_code == 0, res.output
    md = (tmp_path / "report.md").read_text()
    page = (tmp_path / "report.html").read_text()
    for name in ("validation_position", "convergence", "index_history"):
        assert '<img src="data:image/png;base64,' in page and f'alt="{name}"' in page
    assert "| j.tx | 100 | 20 | µm | 110 | -1 |" in md  # (value − true)/σ = −1


@pytest.mark.parametrize(
    "content, match",
    [
        ("{", "not valid JSON"),
        ("[]", "JSON object"),
        ('{"model": "m"}', "written by pincal 0.1"),
        ('{"version": 2, "model": "m"}', "'parameters'"),
        ('{"version": 2, "model": "m", "parameters": [{"name": "a", "value": "x"}]}', "value"),
        (
            '{"version": 2, "model": "m", "parameters": '
            '[{"name": "a", "value": 1, "std": 1, "initial": 0, "unit": "in"}]}',
            "unit",
        ),
    ],
)
def test_report_rejects_malformed_json_in_one_line(tmp_path, content, match):
    (tmp_path / "identification.json").write_text(content)
    res = _invoke("report", str(tmp_path))
    assert res.exit_code == 1 and res.output.count("\n") == 1
    assert "ReportError" in res.output and match in res.output
    assert sorted(p.name for p in tmp_path.iterdir()) == ["identification.json"]


# ----------------------------------------------------------------------------- browser

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


def _screenshot(html: Path, png: Path) -> np.ndarray:
    import matplotlib.image

    subprocess.run(
        [
            CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu",
            "--disable-background-networking", "--hide-scrollbars", "--window-size=800,600",
            "--virtual-time-budget=2000", f"--screenshot={png}", html.resolve().as_uri(),
        ],
        check=True, capture_output=True, timeout=120,
    )  # fmt: skip
    return matplotlib.image.imread(png)[..., :3]


def _foreground(image: np.ndarray) -> np.ndarray:
    pane = image[140:]  # below the legend
    background = np.median(pane, axis=1, keepdims=True)
    return np.max(np.abs(pane - background), axis=2) > 0.08


def test_bundled_models_are_the_ones_tested():
    assert sorted(bundled_models()) == BUNDLED


@pytest.mark.slow
@pytest.mark.skipif(CHROMIUM is None, reason="chromium is not installed (apt-get install chromium)")
@pytest.mark.parametrize("model", BUNDLED)
def test_every_bundled_model_renders_and_poses_differ(model, tmp_path):
    images = []
    for seed in (1, 2):
        html = tmp_path / f"{model}_{seed}.html"
        res = _invoke(
            "view", model, "--random", "1", "--seed", str(seed), "--no-animate",
            "--html", str(html),
        )  # fmt: skip
        assert res.exit_code == 0, res.output
        images.append(_screenshot(html, tmp_path / f"{model}_{seed}.png"))
    for image in images:
        fg = _foreground(image)
        assert fg.mean() > 0.02, f"{model}: mechanism covers only {fg.mean():.1%} of the pane"
        rows, cols = np.nonzero(fg)
        # framed: the drawing is not squeezed into a corner nor cut all around
        assert np.ptp(cols) > 0.25 * fg.shape[1] and np.ptp(rows) > 0.25 * fg.shape[0]
    changed = np.max(np.abs(images[0] - images[1]), axis=2) > 0.08
    assert changed.mean() > 0.002, f"{model}: two poses look the same ({changed.mean():.2%})"


def test_click_group_is_click():
    assert isinstance(main, click.Group)

"""Issue 38's re-attack, cases of other shapes than the first round's tests, one fixture per class.

A calibration of a model directory copied from the bundled wedge3 (``proj/wmod``), its
data file and its calibration directory; then per class the shapes the re-attack found
not good:

* 2 — the manifest's data file (``validate --cv``) a device, a FIFO, a directory or a
  sparse file over the cap (it was hashed for minutes: a hang; the others were "not
  found"), and a campaign's ``measurements.file`` a device ("does not exist");
* 3 — the marker route: a joint's title twice ("missing" the other joint), a unit in
  parentheses ("no marker column"), a ``--marker`` 1e300 mm away (a URDF joint the user
  never wrote was named);
* 4 — a socket file's ``# joint_reference: home`` (ignored: read as absolute), a
  malformed reference (its example named the ``columns`` header);
* 6 — ``report --name`` over its own ``--validation`` or ``--truth`` input (overwritten);
* 7 — a project (model directory + calibration) moved whole (the nominal model was
  looked for at the old absolute path only; the message named an option validate lacks).
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.model import load_mechanism

WEDGE = Path(__file__).resolve().parents[2] / "models" / "wedge3"


def _run(*args, cwd: Path | None = None):
    old = os.getcwd()
    if cwd is not None:
        os.chdir(cwd)
    try:
        return CliRunner().invoke(main, [str(a) for a in args])
    finally:
        os.chdir(old)


def _refused(res, code: int, *words: str) -> str:
    assert res.exit_code == code, res.output
    assert "Traceback" not in res.output and "np.float64(" not in res.output
    line = res.output.strip().splitlines()[-1]
    for w in words:
        assert w in line, line
    return line


@pytest.fixture(scope="module")
def proj(tmp_path_factory):
    """proj/: wmod/ (wedge3's files), m.csv + m.truth.json, cal/ fitted on them from wmod."""
    d = tmp_path_factory.mktemp("proj")
    shutil.copytree(WEDGE, d / "wmod")
    res = _run("simulate", d / "wmod", "--random", "20", "--errors", "seed:3", "--seed", "1",
               "--out", d / "m.csv")  # fmt: skip
    assert res.exit_code == 0, res.output
    res = _run("calibrate", d / "wmod", "--params", "patent", "--data", d / "m.csv",
               "--out", d / "cal", "--force")  # fmt: skip
    assert res.exit_code == 0, res.output
    return d


def _copy(proj: Path, tmp_path: Path) -> Path:
    """A copy of the project whose calibration names its own data file and model."""
    dst = tmp_path / "p"
    shutil.copytree(proj, dst, symlinks=True)
    doc = json.loads((dst / "cal" / "calibration.json").read_text())
    for f in doc["data_files"]:
        f["path"] = f["absolute_path"] = str(dst / "m.csv")
    (dst / "cal" / "calibration.json").write_text(json.dumps(doc))
    return dst


# ---- class 2: the manifest's data file is read as every input is


def _plant(kind: str, p: Path) -> str:
    if kind == "device":
        return "/dev/zero"
    target = p / "planted.csv"
    if kind == "fifo":
        os.mkfifo(target)
    elif kind == "directory":
        target.mkdir()
    else:  # a sparse file over the 1 MB cap set below
        with open(target, "wb") as fh:
            fh.truncate(50 << 20)
    return str(target)


@pytest.mark.parametrize(("kind", "kind_word"), [
    ("device", "CalibrationDirectoryError"), ("fifo", "CalibrationDirectoryError"),
    ("directory", "CalibrationDirectoryError"), ("sparse", "InputLimitError"),
])  # fmt: skip
def test_the_fitted_data_file_is_guarded(proj, tmp_path, monkeypatch, kind, kind_word):
    p = _copy(proj, tmp_path)
    doc = json.loads((p / "cal" / "calibration.json").read_text())
    planted = _plant(kind, p)
    for f in doc["data_files"]:  # every place recorded (relative to the directory too)
        f["path"] = f["absolute_path"] = f["relative_path"] = planted
    (p / "cal" / "calibration.json").write_text(json.dumps(doc))
    monkeypatch.setenv("PINCAL_MAX_FILE_MB", "1")
    line = _refused(_run("validate", p / "cal", "--cv", "3", cwd=tmp_path), 1, kind_word)
    assert "not found where it was given" not in line  # it is there: say what it is
    if kind != "sparse":
        assert "not a regular file" in line


def test_a_campaign_data_file_that_is_a_device_is_named_so(tmp_path):
    (tmp_path / "c.yaml").write_text(
        "model: wedge3\npreset: patent\nout: cal\nmeasurements: {source: file, file: /dev/zero}"
        "\nvalidation: {source: none}\nreport: false\n"
    )
    _refused(_run("run", tmp_path / "c.yaml"), 1, "CampaignError", "not a regular file")


# ---- class 3: the marker route's titles and marker


@pytest.fixture(scope="module")
def marker_table():
    """(title, rows) of 12 UR5 poses (marker position [mm] from nominal FK, joints [rad])."""
    from pincal.measure import MarkerSetup, marker_mechanism
    from pincal.model import sample_actuators

    mech = marker_mechanism("ur5", MarkerSetup("wrist_3_link"))
    q = sample_actuators(mech, 12, np.random.default_rng(1))
    P = np.array([mech.frame_placement(c).translation for c in mech.configurations(q)])
    rows = [",".join(f"{v:.6f}" for v in P[i] * 1e3) + "," + ",".join(f"{v:.9f}" for v in q[i])
            for i in range(len(q))]  # fmt: skip
    return ",".join(["x", "y", "z", *mech.actuated]), rows


@pytest.mark.parametrize(("title_from", "title_to", "extra", "code", "words"), [
    ("wrist_3_joint", "elbow_joint", [], 1, ("ColumnError", "'elbow_joint'", "same title")),
    ("x,y,z", "x (mm),y (mm),z (mm)", [], 1, ("ColumnError", "'x [mm]'", "parentheses")),
    ("x,y,z", "x,y,z", ["--marker", "1e300,0,0"], 2, ("--marker", "mm from the link's origin")),
    ("x,y,z", "x,y,z", ["--marker", "0,0,10,1e300"], 2, ("--marker", "σ")),
])  # fmt: skip
def test_marker_titles_and_marker_are_named(tmp_path, marker_table, title_from, title_to, extra,
                                            code, words):  # fmt: skip
    title, rows = marker_table
    f = tmp_path / "t.csv"
    f.write_text(title.replace(title_from, title_to, 1) + "\n" + "\n".join(rows) + "\n")
    res = _run("calibrate", "ur5", "--link", "wrist_3_link", "--length-unit", "mm", *extra,
               "--data", f, "--out", tmp_path / "cal")  # fmt: skip
    _refused(res, code, *words)
    assert not (tmp_path / "cal").exists()


# ---- class 4: a socket file's joint reference


@pytest.fixture(scope="module")
def sockets(tmp_path_factory):
    s = tmp_path_factory.mktemp("sockets") / "s.csv"
    res = _run("simulate", "ur5", "--random", "20", "--instrument", "socket",
               "--errors", "seed:3", "--seed", "1", "--out", s)  # fmt: skip
    assert res.exit_code == 0, res.output
    return s


def _values(cal: Path) -> dict[str, float]:
    return {p["name"]: p["value"] for p in
            json.loads((cal / "calibration.json").read_text())["parameters"]}  # fmt: skip


@pytest.mark.parametrize("reference", ["home", "shoulder_pan_joint=0.2 elbow_joint=-0.3"])
def test_a_socket_file_reads_its_joint_reference(tmp_path, sockets, reference):
    """Readings written relative to the reference give the calibration of the absolute
    file (the header was ignored: the readings were taken as absolute)."""
    mech = load_mechanism("ur5")
    if reference == "home":
        ref = mech.actuators_of(mech.q_home)
        assert np.abs(ref).max() > 0.1
    else:
        ref = np.zeros(len(mech.actuated))
        ref[[0, 2]] = 0.2, -0.3
    lines = sockets.read_text().splitlines()
    k = next(i for i, ln in enumerate(lines) if not ln.startswith("#"))
    rel = [",".join(f"{float(v) - r:.15g}" for v, r in zip(ln.split(",")[:-1], ref, strict=True))
           + "," + ln.split(",")[-1] for ln in lines[k + 1:]]  # fmt: skip
    f = tmp_path / "rel.csv"
    f.write_text("\n".join([*lines[:k], f"# joint_reference: {reference}", lines[k], *rel]) + "\n")
    for data, out in ((sockets, "a"), (f, "b")):
        res = _run("calibrate", "ur5", "--data", data, "--out", tmp_path / out)
        assert res.exit_code == 0, res.output
    a, b = _values(tmp_path / "a"), _values(tmp_path / "b")
    assert a.keys() == b.keys()
    assert max(abs(a[n] - b[n]) for n in a) < 1e-6


def test_a_malformed_joint_reference_shows_its_own_header(tmp_path, sockets):
    lines = sockets.read_text().splitlines()
    f = tmp_path / "bad.csv"
    f.write_text("\n".join([lines[0], "# joint_reference: {elbow_joint: 0.1}", *lines[1:]]) + "\n")
    line = _refused(_run("calibrate", "ur5", "--data", f, "--out", tmp_path / "cal"), 1,
                    "MeasurementFormatError", "'# joint_reference:")  # fmt: skip
    assert "columns:" not in line


# ---- class 6: a report's outputs are not its inputs


@pytest.mark.parametrize(("option", "stem"), [("--validation", "v"), ("--truth", "m.truth")])
def test_report_out_is_not_its_own_input(proj, tmp_path, option, stem):
    p = _copy(proj, tmp_path)
    given = p / f"{stem}.json"
    if option == "--validation":
        res = _run("validate", p / "cal", "--data", p / "m.csv", "--out", given)
        assert res.exit_code == 0, res.output
    before = given.read_bytes()
    res = _run("report", p / "cal", option, given, "--out", p, "--name", stem)
    _refused(res, 1, "OutputPathError", f"the input {option}")
    assert given.read_bytes() == before


# ---- class 7: a project moved whole


@pytest.mark.parametrize("how", ["moved", "copied"])
def test_a_project_moved_whole_finds_its_model(proj, tmp_path, how):
    p = _copy(proj, tmp_path)
    res = _run("calibrate", p / "wmod", "--params", "patent", "--data", p / "m.csv",
               "--out", p / "cal2", "--force")  # fmt: skip
    assert res.exit_code == 0, res.output
    shutil.rmtree(p / "cal")
    dst = tmp_path / "elsewhere"
    (shutil.move if how == "moved" else shutil.copytree)(p, dst)
    if how == "copied":
        shutil.rmtree(p)
    res = _run("validate", dst / "cal2", "--data", dst / "m.csv")
    assert res.exit_code == 0, res.output
    # the moved model is an input where it is now: never written over
    side = dst / "wmod" / "wedge3.yaml"
    before = side.read_bytes()
    res = _run("validate", dst / "cal2", "--data", dst / "m.csv", "--out", side)
    _refused(res, 1, "OutputPathError", "nominal model's sidecar")
    assert side.read_bytes() == before
    # the moved model is used only as hashed: an edited sidecar is not the model fitted
    side.write_text(side.read_text() + "\n# edited\n")
    line = _refused(_run("validate", dst / "cal2", "--data", dst / "m.csv"), 1,
                    "CalibrationDirectoryError", "nominal model")  # fmt: skip
    assert "pass the model" not in line  # validate has no such option


def test_a_reading_out_of_range_by_its_reference_names_the_reference(tmp_path, marker_table):
    """Absolute readings under '# joint_reference: home': the range error says home was added
    (it named the sum alone, a value the file does not hold)."""
    title, rows = marker_table
    cells = rows[0].split(",")
    cells[5] = "-3.1"  # elbow_joint, inside ±π; home adds −45°
    f = tmp_path / "t.csv"
    lines = ["# joint_reference: home", title, ",".join(cells), *rows[1:]]
    f.write_text("\n".join(lines) + "\n")
    res = _run("calibrate", "ur5", "--link", "wrist_3_link", "--length-unit", "mm",
               "--data", f, "--out", tmp_path / "cal")  # fmt: skip
    _refused(res, 1, "ActuatorRangeError", "relative to home", "joint_reference")


# ---- class 10: a pincal file of another kind says which command reads it


@pytest.mark.parametrize(("command", "words"), [
    (["validate", "{cal}", "--data", "{sockets}"], ("sockets", "pincal validate --cv")),
    (["compensate", "{cal}", "--targets", "{m}", "--out", "{tmp}/c.csv"],
     ("measurements", "pincal calibrate --data")),
])  # fmt: skip
def test_a_file_of_another_kind_says_where_it_is_read(proj, sockets, tmp_path, command, words):
    args = [a.format(cal=proj / "cal", sockets=sockets, m=proj / "m.csv", tmp=tmp_path)
            for a in command]  # fmt: skip
    _refused(_run(*args), 1, "MeasurementFormatError", *words)

"""`acceptance --calibrated` warns when it simulates another machine than the calibrated one."""

from __future__ import annotations

from click.testing import CliRunner

from pincal.cli import main


def test_acceptance_names_the_options_of_the_calibrated_machine(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # the manifest records the data path as typed
    run = CliRunner().invoke
    assert run(main, ["simulate", "wedge3", "--random", "30", "--errors", "seed:4",
                      "--error-size", "0.5,5", "--out", "m.csv"]).exit_code == 0  # fmt: skip
    assert run(main, ["calibrate", "wedge3", "--data", "m.csv", "--out", "cal"]).exit_code == 0
    other = run(main, ["acceptance", "wedge3", "--calibrated", "cal", "--cycles", "3"])
    assert other.exit_code == 0, other.output
    assert "not the one the calibration was fitted on" in other.output
    assert "--errors seed:4 --params patent --error-size 0.5,5" in other.output
    same = run(main, ["acceptance", "wedge3", "--calibrated", "cal", "--cycles", "3",
                      "--errors", "seed:4", "--error-size", "0.5,5"])  # fmt: skip
    assert same.exit_code == 0, same.output
    assert "not the one the calibration" not in same.output


def test_acceptance_reads_the_truth_beside_the_fitted_data_as_an_input(tmp_path, monkeypatch):
    """The ``.truth.json`` found beside the fitted data file (through the manifest) is
    read as every input is: a list (it was a traceback: 'list' has no 'get') or a sparse
    file over the size cap (it was read whole: 6.5 GB for 3 GB) is no truth, not a crash."""
    monkeypatch.chdir(tmp_path)
    run = CliRunner().invoke
    assert run(main, ["simulate", "wedge3", "--random", "30", "--out", "m.csv"]).exit_code == 0
    assert run(main, ["calibrate", "wedge3", "--data", "m.csv", "--out", "cal"]).exit_code == 0
    monkeypatch.setenv("PINCAL_MAX_FILE_MB", "1")
    for plant in ("list", "sparse"):
        (tmp_path / "m.truth.json").unlink()
        if plant == "list":
            (tmp_path / "m.truth.json").write_text("[]\n")
        else:
            with open(tmp_path / "m.truth.json", "wb") as fh:
                fh.truncate(50 << 20)
        res = run(main, ["acceptance", "wedge3", "--calibrated", "cal", "--cycles", "3"])
        assert res.exit_code == 0, (plant, res.output)
        assert "not the one the calibration" not in res.output


def test_acceptance_says_what_differs_and_refuses_another_model(tmp_path, monkeypatch):
    """Issue 39, item 4: a 5-bar's "after" 2.40 mm was worse than "before" 2.27 mm because
    acceptance drew another machine than `simulate` had; the warning now says which
    settings differ (there → here), and a calibration of another robot is refused before
    anything is simulated (it commanded a Stewart platform with a wedge's controller,
    then stopped on an unreachable pose after the 'before' table)."""
    monkeypatch.chdir(tmp_path)
    run = CliRunner().invoke
    assert run(main, ["simulate", "wedge3", "--random", "30", "--errors", "seed:4",
                      "--error-size", "0.5,5", "--out", "m.csv"]).exit_code == 0  # fmt: skip
    assert run(main, ["calibrate", "wedge3", "--data", "m.csv", "--out", "cal"]).exit_code == 0
    other = run(main, ["acceptance", "wedge3", "--calibrated", "cal", "--cycles", "3",
                       "--params", "full", "--error-size", "0.5,5"])  # fmt: skip
    assert other.exit_code == 0, other.output
    said = " ".join(other.output.split())
    warning = next(line for line in other.output.splitlines() if "warning" in line)
    differs = "--params patent there, full here; --errors seed:4 there, seed:0 here"
    assert f"m.truth.json: {differs})" in said
    assert "--error-size 0.5,5 there" not in said  # the same size: not named
    assert "pass --errors seed:4 --params patent --error-size 0.5,5" in warning  # one line
    wrong = run(main, ["acceptance", "stewart_6ups", "--calibrated", "cal", "--cycles", "3"])
    assert wrong.exit_code != 0
    said = " ".join(wrong.output.split())
    assert "ParameterError" in said and "of model 'wedge3'" in said, said
    assert "pass its model: pincal acceptance wedge3 --calibrated cal" in said
    assert "before calibration" not in said  # refused before simulating anything

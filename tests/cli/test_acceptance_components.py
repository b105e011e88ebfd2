"""`pincal acceptance` / `validate` on machines measuring fewer than six components.

The ISO 9283 test cube (square) is built on the measured components, inside the declared
(or sampled) workspace, checked by forward kinematics; AP/AP_a/b/c follow one convention.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.model import load_mechanism
from pincal.validation import ORIENTATION_CONVENTION
from tests.cli._checks import assert_clean_failure

MACHINES = Path(__file__).resolve().parents[1] / "model" / "machines"
RRR3 = MACHINES / "rrr3" / "rrr3.urdf"
FIVEBAR = MACHINES / "fivebar" / "fivebar.urdf"


def _run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


def _acceptance(tmp_path, *args):
    """Run acceptance with --out; the printed text and the JSON report."""
    out = tmp_path / "acc.json"
    res = _run("acceptance", *args, "--out", out)
    assert res.exit_code == 0, res.output
    return res.stdout, json.loads(out.read_text())


def _inside(cube, mech):
    """The test points lie in the stated box and are reached (IK then FK returns them)."""
    idx = ["xyz".index(a) for a in cube["axes"]]
    P = np.array(cube["points"])
    lo, hi = np.array(cube["bounds"]).T
    assert np.all(P[:, idx] >= lo - 1e-9) and np.all(P[:, idx] <= hi + 1e-9), (P, lo, hi)
    h = cube["edge"] / 2
    c = np.array(cube["centre"])[idx]
    assert np.all(c - h >= lo - 1e-9) and np.all(c + h <= hi + 1e-9)  # the whole cube
    comps = [k for k, n in enumerate(("x", "y", "z", "rx", "ry", "rz")) if n in cube["components"]]
    R = mech.frame_placement(mech.q_home).rotation
    for p in P:
        T = mech.forward(mech.inverse(pin.SE3(R, p)))
        err = np.concatenate([T.translation - p, pin.log3(R.T @ T.rotation)])
        assert np.max(np.abs(err[comps])) < 1e-6


@pytest.fixture(scope="module")
def rrr3_campaign(tmp_path_factory):
    """A clean simulated calibration of the planar 3-RRR (measures x y rz)."""
    d = tmp_path_factory.mktemp("rrr3")
    res = _run("simulate", RRR3, "--random", 40, "--params", "base", "--out", d / "m.csv")
    assert res.exit_code == 0, res.output
    res = _run("calibrate", RRR3, "--data", d / "m.csv", "--params", "base", "--out", d / "cal")
    assert res.exit_code == 0, res.output
    return d


def test_planar_machine_gets_a_square_in_its_plane_and_small_ap(rrr3_campaign, tmp_path):
    d = rrr3_campaign
    text, rep = _acceptance(
        tmp_path, RRR3, "--params", "base", "--calibrated", d / "cal", "--cycles", 10
    )
    cube = rep["cube"]
    assert cube["shape"] == "square" and cube["axes"] == ["x", "y"]
    assert cube["components"] == ["x", "y", "rz"] and cube["workspace"] == "declared"
    np.testing.assert_allclose(cube["bounds"], [[-0.05, 0.05], [-0.05, 0.05]])
    assert cube["edge"] > 0.02  # a real square, not a point
    np.testing.assert_allclose(np.array(cube["points"])[:, 2], 0.0, atol=1e-9)  # z: home's
    _inside(cube, load_mechanism(RRR3))
    assert "test square in x y" in text and "inside the declared workspace" in text
    assert ORIENTATION_CONVENTION in text
    before, after = rep["before"], rep["after"]
    assert after["components"] == ["x", "y", "rz"]
    for run in (before, after):  # only rz is judged among the rotations
        assert all(a[0] is None and a[1] is None and a[2] is not None for a in run["AP_abc"])
        assert all(x[2] is None for x in run["AP_xyz"])
    # before: the simulated errors (mm); after: the calibration residual (≈ 10 µm noise)
    assert min(before["AP_p"]) > 1e-3
    assert max(after["AP_p"]) < 2e-5, after["AP_p"]
    assert max(abs(a[2]) for a in after["AP_abc"]) < 1e-4  # rad


def test_stewart_cube_lies_in_the_declared_workspace(tmp_path):
    text, rep = _acceptance(tmp_path, "stewart_6ups", "--errors", "none", "--cycles", 5)
    cube = rep["cube"]
    assert cube["shape"] == "cube" and cube["workspace"] == "declared"
    assert cube["components"] == ["x", "y", "z", "rx", "ry", "rz"]
    np.testing.assert_allclose(cube["bounds"], [[-0.06, 0.06], [-0.06, 0.06], [0.41, 0.49]])
    assert 0.07 < cube["edge"] <= 0.08 + 1e-12  # the 80 mm z range, not the actuator limits
    _inside(cube, load_mechanism("stewart_6ups"))
    assert "inside the declared workspace" in text
    # the actual machine is the nominal one: AP is the repeatability's barycentre scatter
    assert max(rep["before"]["AP_p"]) < 1e-5
    assert np.nanmax(np.abs(np.array(rep["before"]["AP_abc"], dtype=float))) < 1e-4


def test_position_only_machine_without_workspace_uses_the_sampled_one(tmp_path):
    text, rep = _acceptance(tmp_path, FIVEBAR, "--errors", "none", "--cycles", 5)
    cube = rep["cube"]
    assert cube["shape"] == "square" and cube["axes"] == ["x", "y"]
    assert cube["components"] == ["x", "y"] and cube["workspace"] == "sampled"
    _inside(cube, load_mechanism(FIVEBAR))
    assert "inside the sampled reachable workspace" in text
    assert "orientation not measured" in text
    assert all(v is None for row in rep["before"]["AP_abc"] for v in row)
    assert max(rep["before"]["AP_p"]) < 1e-5


def _rrr3_with(tmp_path, replace: dict[str, str]) -> Path:
    """A copy of rrr3 whose sidecar has lines replaced (the URDF unchanged)."""
    d = tmp_path / "machine"
    d.mkdir()
    (d / "rrr3.urdf").write_text(RRR3.read_text())
    sidecar = RRR3.with_suffix(".yaml").read_text()
    for old, new in replace.items():
        assert old in sidecar
        sidecar = sidecar.replace(old, new)
    (d / "rrr3.yaml").write_text(sidecar)
    return d / "rrr3.urdf"


def test_refuses_when_no_square_fits_the_declared_workspace(tmp_path):
    tiny = _rrr3_with(tmp_path, {"x: [-0.05, 0.05]": "x: [0.0, 0.0004]"})
    res = _run("acceptance", tiny, "--errors", "none", "--cycles", 3)
    assert_clean_failure(res, "NoTestCubeError")
    assert "declared workspace" in res.stderr and "widen the sidecar's workspace.pose" in (
        res.stderr
    )


def test_refuses_with_fewer_than_two_measured_position_components(tmp_path):
    one_axis = _rrr3_with(tmp_path, {"measured: [x, y, rz]": "measured: [x, rz]"})
    res = _run("acceptance", one_axis, "--errors", "none", "--cycles", 3)
    assert_clean_failure(res, "NoTestCubeError")
    assert "at least two measured position components" in res.stderr


def test_refuses_a_planar_machine_declared_as_measuring_z(tmp_path):
    """rpr3 (planar, sidecar measures the full pose): z never moves, so no cube; say so."""
    res = _run("acceptance", MACHINES / "rpr3" / "rpr3.urdf", "--errors", "none")
    assert_clean_failure(res, "NoTestCubeError")
    assert "sampled reachable workspace" in res.stderr
    assert "does not move its measured frame along z" in res.stderr


def test_validate_uses_the_same_convention_and_components(rrr3_campaign):
    d = rrr3_campaign
    res = _run("simulate", RRR3, "--random", 6, "--seed", 9, "--params", "base",
               "--out", d / "held.csv")  # fmt: skip
    assert res.exit_code == 0, res.output
    res = _run("validate", d / "cal", "--data", d / "held.csv", "--json")
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout)
    assert doc["orientation_convention"] == ORIENTATION_CONVENTION
    for row in doc["iso9283"]:
        assert row["after"]["AP_a_mrad"] is None and row["after"]["AP_b_mrad"] is None
        assert abs(row["after"]["AP_c_mrad"]) < 0.2
        assert row["after"]["AP_p_mm"] < 0.05 < row["before"]["AP_p_mm"]
    res = _run("validate", d / "cal", "--data", d / "held.csv")
    assert res.exit_code == 0, res.output
    assert f"AP_c only (measured): {ORIENTATION_CONVENTION}" in res.stdout
    assert "AP_p, RP_l over x y;" in res.stdout


def test_measured_cycles_are_judged_on_their_components(tmp_path):
    """--data on rrr3: x y rz measured; AP_p over x y, only AP_c among the angles."""
    from pincal.io import write_measurements
    from pincal.measure import Measurements
    from pincal.sensitivity import parameters
    from pincal.validation import iso_test_cube, pose_characteristics, simulate_cycles

    nominal = load_mechanism(RRR3)
    cube = iso_test_cube(nominal, rng=1)
    params = parameters(nominal, "base")
    actual = params.apply(nominal, np.full(len(params), 2e-4))
    q, pos, rot = simulate_cycles(actual, nominal, cube.poses, 4, 1e-6, 3)
    m = Measurements(np.repeat(q, 4, axis=0), pos.reshape(-1, 3), rot.reshape(-1, 3, 3),
                     ("x", "y", "rz"), nominal.measured_frame, nominal.actuated)  # fmt: skip
    data = write_measurements(tmp_path / "cycles.csv", m)
    res = _run("acceptance", RRR3, "--data", data, "--json")
    assert res.exit_code == 0, res.output
    got = json.loads(res.stdout)["measured"]
    assert got["components"] == ["x", "y", "rz"]
    ref = pose_characteristics(cube.poses, pos, rot, ("x", "y", "rz"))
    np.testing.assert_allclose(got["AP_p"], ref.ap_p, atol=1e-9)
    xy = np.linalg.norm(pos.mean(axis=1)[:, :2] - cube.points[:, :2], axis=1)
    np.testing.assert_allclose(got["AP_p"], xy, atol=1e-9)  # z plays no part
    assert all(a[0] is None and a[1] is None for a in got["AP_abc"])

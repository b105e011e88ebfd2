"""ISO 9283 pose accuracy / repeatability and the test cube."""

from __future__ import annotations

import json
import math

import numpy as np
import pinocchio as pin
import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.errors import MeasurementError, PincalError
from pincal.validation import (
    iso_test_cube,
    pose_characteristics,
    simulate_cycles,
)


def _by_definition(cmd, pos, rot):
    """AP/RP written out from ISO 9283's definitions, loop by loop."""
    out = []
    for j, T in enumerate(cmd):
        n = len(pos[j])
        xb = [sum(p[k] for p in pos[j]) / n for k in range(3)]
        ap_p = math.sqrt(sum((xb[k] - T.translation[k]) ** 2 for k in range(3)))
        l = [math.sqrt(sum((p[k] - xb[k]) ** 2 for k in range(3))) for p in pos[j]]  # noqa: E741
        lb = sum(l) / n
        s_l = math.sqrt(sum((li - lb) ** 2 for li in l) / (n - 1))

        # a, b, c: ISO 9283's angles about the base x, y, z axes, R = Rz(c) Ry(b) Rx(a),
        # read off the matrix; AP_a = ā − a_c with each difference wrapped to ±π
        def abc(R):
            return (math.atan2(R[2, 1], R[2, 2]), -math.asin(R[2, 0]), math.atan2(R[1, 0], R[0, 0]))

        def wrap(x):
            return (x + math.pi) % (2 * math.pi) - math.pi

        angs = [[wrap(u - v) for u, v in zip(abc(R), abc(T.rotation), strict=True)] for R in rot[j]]
        ap_abc, rp_abc = [], []
        for k in range(3):
            mean = sum(a[k] for a in angs) / n
            ap_abc.append(mean)
            rp_abc.append(3 * math.sqrt(sum((a[k] - mean) ** 2 for a in angs) / (n - 1)))
        out.append((ap_p, ap_abc, lb + 3 * s_l, rp_abc))
    return out


def test_ap_rp_match_the_definition():
    rng = np.random.default_rng(4)
    cmd = [pin.SE3(pin.exp3(rng.normal(0, 0.3, 3)), rng.normal(0, 0.2, 3)) for _ in range(5)]
    pos = np.array(
        [
            [
                T.translation + np.array([1e-3, -2e-3, 5e-4]) + rng.normal(0, 2e-5, 3)
                for _ in range(30)
            ]
            for T in cmd
        ]
    )
    rot = np.array(
        [
            [
                T.rotation @ pin.exp3(np.array([1e-3, 0, -2e-3]) + rng.normal(0, 5e-5, 3))
                for _ in range(30)
            ]
            for T in cmd
        ]
    )
    pc = pose_characteristics(cmd, pos, rot)
    ref = _by_definition(cmd, pos, rot)
    for j, (ap_p, ap_abc, rp_l, rp_abc) in enumerate(ref):
        assert pc.ap_p[j] == pytest.approx(ap_p, rel=1e-12)
        np.testing.assert_allclose(pc.ap_abc[j], ap_abc, rtol=1e-9, atol=1e-13)
        assert pc.rp_l[j] == pytest.approx(rp_l, rel=1e-12)
        np.testing.assert_allclose(pc.rp_abc[j], rp_abc, rtol=1e-9)
    assert pc.cycles == 30 and len(pc.lines("x")) == 9
    assert 2.2e-3 < pc.ap_p.max() < 2.4e-3  # the offset of 2.29 mm
    with pytest.raises(MeasurementError, match="2 cycles"):
        pose_characteristics(cmd, pos[:, :1], rot[:, :1])
    # a command at c = 179.9°: attained angles on both sides of ±180° are wrapped
    turn = pin.SE3(pin.rpy.rpyToMatrix(0.0, 0.0, np.pi - 1e-3), np.zeros(3))
    across = np.array([[pin.rpy.rpyToMatrix(0.0, 0.0, np.pi + d) for d in (1e-3, 3e-3)]])
    pc = pose_characteristics([turn], np.zeros((1, 2, 3)), across)
    assert pc.ap_abc[0, 2] == pytest.approx(3e-3, abs=1e-12)
    gimbal = pin.SE3(pin.rpy.rpyToMatrix(0.0, np.pi / 2, 0.0), np.zeros(3))
    with pytest.raises(MeasurementError, match="b = ±90°"):
        pose_characteristics([gimbal], np.zeros((1, 2, 3)), np.array([[gimbal.rotation] * 2]))
    with pytest.raises(MeasurementError, match="positions"):
        pose_characteristics(cmd[:2], pos, rot)


def test_test_cube_lies_in_the_declared_workspace_with_the_standard_points(stewart):
    cube = iso_test_cube(stewart, n_samples=100, rng=0)
    h = cube.edge / 2
    lim = stewart.workspace.pose  # x, y ±60 mm, z 410..490 mm: the cube is 80 mm
    assert cube.workspace == "declared" and cube.axes == ("x", "y", "z")
    assert cube.edge == pytest.approx(0.08, abs=1e-4)
    for k, a in enumerate("xyz"):
        assert lim[a][0] - 1e-12 <= cube.centre[k] - h and cube.centre[k] + h <= lim[a][1] + 1e-12
    for T in cube.poses:
        T_back = stewart.forward(stewart.inverse(T))  # reached, by forward kinematics
        np.testing.assert_allclose(T_back.translation, T.translation, atol=1e-6)
    P = cube.points
    np.testing.assert_allclose(P[0], cube.centre)
    diag = 2 * h * math.sqrt(3)  # the diagonal plane's diagonal is the cube's diagonal
    corners = [
        cube.centre + h * np.array(s) for s in ((1, 1, 1), (-1, -1, 1), (-1, -1, -1), (1, 1, -1))
    ]
    for p, c in zip(P[1:], corners, strict=True):
        assert np.linalg.norm(p - c) == pytest.approx(0.1 * diag, rel=1e-12)
        # in the diagonal plane x = y (through C1, C2, C7, C8)
        assert (p - cube.centre)[0] == pytest.approx((p - cube.centre)[1], abs=1e-12)
    with pytest.raises(PincalError, match="0.08..0.12"):
        iso_test_cube(stewart, n_samples=10, inset=0.2)


def test_calibration_improves_accuracy_not_repeatability(stewart, stewart42):
    cube = iso_test_cube(stewart, n_samples=60, rng=1)
    actual = stewart42.apply(stewart, np.random.default_rng(0).uniform(-1e-3, 1e-3, len(stewart42)))
    _, pos, rot = simulate_cycles(actual, stewart, cube.poses, 10, 2e-6, 0)
    before = pose_characteristics(cube.poses, pos, rot)
    _, pos, rot = simulate_cycles(actual, actual, cube.poses, 10, 2e-6, 0)
    after = pose_characteristics(cube.poses, pos, rot)
    assert after.ap_p.max() < 0.05 * before.ap_p.max()
    np.testing.assert_allclose(after.rp_l, before.rp_l, rtol=0.2)


@pytest.mark.slow
def test_cli_acceptance_before_and_after_and_from_data(tmp_path):
    runner = CliRunner()
    meas = tmp_path / "m.csv"
    assert (
        runner.invoke(
            main, ["simulate", "stewart_6ups", "--random", "30", "--out", str(meas)]
        ).exit_code
        == 0
    )
    cal = tmp_path / "cal"
    res = runner.invoke(main, ["calibrate", "stewart_6ups", "--data", str(meas), "--out", str(cal)])
    assert res.exit_code == 0, res.output
    out = tmp_path / "acc.json"
    res = runner.invoke(
        main,
        [
            "acceptance",
            "stewart_6ups",
            "--calibrated",
            str(cal),
            "--cycles",
            "8",
            "--out",
            str(out),
        ],
    )
    assert res.exit_code == 0, res.output
    rep = json.loads(out.read_text())
    assert max(rep["after"]["AP_p"]) < 0.1 * max(rep["before"]["AP_p"])
    assert "before calibration" in res.output and "after calibration" in res.output
    res2 = runner.invoke(
        main,
        [
            "acceptance",
            "stewart_6ups",
            "--calibrated",
            str(cal / "identification.json"),
            "--cycles",
            "8",
            "--out",
            str(out),
        ],
    )
    assert res2.exit_code == 0, res2.output
    again = json.loads(out.read_text())["after"]  # the URDF and the values agree
    np.testing.assert_allclose(again["AP_p"], rep["after"]["AP_p"], rtol=1e-6, atol=1e-12)
    np.testing.assert_allclose(again["RP_l"], rep["after"]["RP_l"], rtol=1e-6)
    # measured cycles: rows with equal actuator values are one commanded pose
    from pincal.io import write_measurements
    from pincal.measure import Measurements
    from pincal.model import load_mechanism, parameters

    nominal = load_mechanism("stewart_6ups")
    cube = iso_test_cube(nominal, n_samples=60, rng=1)
    params = parameters(nominal, "stewart42")
    actual = params.apply(nominal, np.full(len(params), 2e-4))
    q, pos, rot = simulate_cycles(actual, nominal, cube.poses, 5, 1e-6, 3)
    rows = np.repeat(q, 5, axis=0)
    m = Measurements(
        rows,
        pos.reshape(-1, 3),
        rot.reshape(-1, 3, 3),
        ("x", "y", "z", "rx", "ry", "rz"),
        nominal.measured_frame,
        nominal.actuated,
    )
    data = write_measurements(tmp_path / "cycles.csv", m)
    res = runner.invoke(
        main, ["acceptance", "stewart_6ups", "--data", str(data), "--out", str(out)]
    )
    assert res.exit_code == 0, res.output
    got = json.loads(out.read_text())["measured"]
    ref = pose_characteristics(cube.poses, pos, rot)
    np.testing.assert_allclose(got["AP_p"], ref.ap_p, atol=1e-9)
    np.testing.assert_allclose(got["RP_l"], ref.rp_l, rtol=1e-9)


def test_unmeasured_tool_axis_turn_does_not_leak_into_a_and_b():
    """A machine measuring rx ry (in its measured frame) at a pose tilted 0.3 rad: a turn
    of 50 mrad about the tool axis, which the instrument does not see, leaves AP_a and
    AP_b those of the measured tilt alone (written from the definition), where reading
    the angles off the whole matrix would move them by ≈ 0.3 × 50 mrad."""
    from pincal.validation import point_accuracy

    Rc = pin.rpy.rpyToMatrix(0.2, 0.3, 0.4)
    cmd = pin.SE3(Rc, np.array([0.0, 0.0, 0.5]))
    seen = np.array([1e-3, -2e-3, 0.0])
    attained = Rc @ pin.exp3(seen + np.array([0.0, 0.0, 0.05]))

    def abc(R):
        return np.array([math.atan2(R[2, 1], R[2, 2]), -math.asin(R[2, 0])])

    expected = abc(Rc @ pin.exp3(seen)) - abc(Rc)
    leaky = abc(attained) - abc(Rc)
    pa = point_accuracy(cmd, cmd.translation[None], attained[None], ("z", "rx", "ry"))
    assert np.allclose(pa.ap_abc[:2], expected, atol=1e-12)
    assert np.isnan(pa.ap_abc[2])
    assert np.max(np.abs(leaky - expected)) > 5e-3  # the case is one where it matters
    full = point_accuracy(cmd, cmd.translation[None], attained[None])  # all three seen
    assert np.allclose(full.ap_abc[:2], leaky, atol=1e-12)

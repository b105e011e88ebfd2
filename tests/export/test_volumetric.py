"""`pincal export --format volumetric-map`, read back and applied as a controller would.

The controller is written here from the format's equations (1)–(2) (trilinear weights
of a cell's reachable nodes renormalised, the nearest reachable node where a cell has
none, points clamped to the grid), reading the CSV as written; the machine's nominal
kinematics are the controller's own. Checked: at every reachable node the written
command correction brings the calibrated machine to the node (≤ 1 µm: what the format
expresses), the map's forward correction agrees with the projection the header reports,
and a rotary Delta (positions only) is compensated from ≈ 0.8 mm to micrometres.
"""

from __future__ import annotations

import csv
import io

import numpy as np
import pinocchio as pin
import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.export import CalibratedMachine, export_calibration
from pincal.model import Mechanism, load_mechanism, parameters
from tests.export.test_rotary_delta import _moved
from tests.open_world.first_machines import delta_elbows


def _read(text: str) -> tuple[list[np.ndarray], np.ndarray, list[dict]]:
    """(axes, node values (n_x, n_y, n_z, 6 + n_act) NaN where unreachable, rows)."""
    rows = list(csv.DictReader(io.StringIO("".join(ln for ln in text.splitlines(True)
                                                   if not ln.startswith("#")))))  # fmt: skip
    xyz = np.array([[float(r[f"{c}_m"]) for c in "xyz"] for r in rows])
    axes = [np.unique(xyz[:, i]) for i in range(3)]
    names = [k for k in rows[0] if k.startswith(("d", "du_"))]
    vals = np.full((*(a.size for a in axes), len(names)), np.nan)
    for r, p in zip(rows, xyz, strict=True):
        if r["reachable"] == "1":
            idx = tuple(int(np.searchsorted(a, v)) for a, v in zip(axes, p, strict=True))
            vals[idx] = [float(r[k]) for k in names]
    return axes, vals, rows


def _interpolate(axes: list[np.ndarray], vals: np.ndarray, p: np.ndarray) -> np.ndarray:
    """The format's interpolation, written from its description."""
    p = np.clip(p, [a[0] for a in axes], [a[-1] for a in axes])
    lo = [min(max(int(np.searchsorted(a, x, side="right")) - 1, 0), max(a.size - 2, 0))
          for a, x in zip(axes, p, strict=True)]  # fmt: skip
    total, acc = 0.0, np.zeros(vals.shape[-1])
    for corner in np.ndindex(2, 2, 2):
        w, idx = 1.0, []
        for a, x, i, c in zip(axes, p, lo, corner, strict=True):
            if a.size == 1:
                if c:
                    w = 0.0
                idx.append(0)
                continue
            t = (x - a[i]) / (a[i + 1] - a[i])
            w *= t if c else 1.0 - t
            idx.append(i + c)
        v = vals[tuple(idx)]
        if w > 0 and not np.isnan(v).any():
            acc, total = acc + w * v, total + w
    if total > 0:
        return acc / total
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1)
    d = np.where(np.isnan(vals).any(axis=-1), np.inf, np.linalg.norm(grid - p, axis=-1))
    return vals[np.unravel_index(int(np.argmin(d)), d.shape)]


@pytest.fixture(scope="module")
def delta() -> tuple[Mechanism, Mechanism]:
    urdf, sidecar = delta_elbows("spherical")
    nominal = Mechanism(urdf, sidecar, name="delta")
    return nominal, _moved(nominal)


def test_delta_map_compensates_to_micrometres(delta):
    nominal, calibrated = delta
    exp = export_calibration(CalibratedMachine.from_mechanisms(calibrated, nominal),
                             "volumetric-map", poses=60)  # fmt: skip
    axes, vals, rows = _read(exp.text)
    assert [a.size for a in axes] == [9, 9, 9] and np.isfinite(vals).any()
    n_act = len(nominal.actuated)
    # every reachable node: the written command correction reaches it on the calibrated machine
    for r in rows[::7]:
        if r["reachable"] != "1":
            continue
        node = np.array([float(r[f"{c}_m"]) for c in "xyz"])
        u_nom = np.array([float(r[f"u_nom_{j}"]) for j in nominal.actuated])
        du = np.array([float(r[f"du_{j}"]) for j in nominal.actuated])
        p_nom = nominal.frame_placement(nominal.configuration(u_nom)).translation
        p_cal = calibrated.frame_placement(calibrated.configuration(u_nom + du)).translation
        assert np.linalg.norm(p_nom - node) < 1e-9 and np.linalg.norm(p_cal - node) < 1e-6
        dp = np.array([float(r[f"d{c}_m"]) for c in "xyz"])
        p_err = calibrated.frame_placement(calibrated.configuration(u_nom)).translation - node
        assert np.allclose(dp, p_err, atol=1e-11)
    # forward (1) at the projection's readings: this controller gives the header's figures
    q = exp.projection.q_act
    err, plain = [], []
    for u in q:
        p = nominal.frame_placement(nominal.configuration(u)).translation
        ref = calibrated.frame_placement(calibrated.configuration(u)).translation
        err.append(np.linalg.norm(p + _interpolate(axes, vals, p)[:3] - ref))
        plain.append(np.linalg.norm(p - ref))
    rms = float(np.sqrt(np.mean(np.square(err))))
    assert rms == pytest.approx(exp.projection.position_rms, rel=1e-6)
    assert max(err) == pytest.approx(exp.projection.position_max, rel=1e-6)
    assert np.sqrt(np.mean(np.square(plain))) > 5e-4  # the errors are 0.5 mm and more
    assert rms < 5e-6 and max(err) < 3e-5  # compensated to micrometres (9 nodes per axis)
    # inverse (2): a target's command, corrected by the map, lands on it
    target = nominal.frame_placement(nominal.configuration(q[0])).translation
    u = nominal.actuators_of(nominal.inverse_configuration(pin.SE3(np.eye(3), target)))
    u = u + _interpolate(axes, vals, target)[6 : 6 + n_act]
    miss = calibrated.frame_placement(calibrated.configuration(u)).translation - target
    assert np.linalg.norm(miss) < 3e-5


def test_a_map_says_it_holds_one_orientation_only():
    """A Stewart's error depends on the platform's orientation: the map (at the home
    orientation) compensates poses at that orientation and reports the rest."""
    nominal = load_mechanism("stewart_6ups")
    ps = parameters(nominal, "stewart42")
    calibrated = ps.apply(nominal, np.random.default_rng(0).uniform(-2e-4, 2e-4, len(ps)))
    exp = export_calibration(CalibratedMachine.from_mechanisms(calibrated, nominal),
                             "volumetric-map", poses=30)  # fmt: skip
    assert any("orientation" in s for s in exp.projection.not_expressed)
    axes, vals, _ = _read(exp.text)
    home = nominal.frame_placement(nominal.q_home)
    rng = np.random.default_rng(3)
    lo, hi = [a[0] for a in axes], [a[-1] for a in axes]
    for _ in range(5):  # targets at the home orientation inside the grid
        p = rng.uniform(lo, hi) * 0.6 + 0.4 * home.translation
        target = pin.SE3(home.rotation, p)
        u = nominal.actuators_of(nominal.inverse_configuration(target))
        u_map = u + _interpolate(axes, vals, p)[6:]
        got = calibrated.frame_placement(calibrated.configuration(u_map))
        plain = calibrated.frame_placement(calibrated.configuration(u))
        assert np.linalg.norm(got.translation - p) < 0.1 * np.linalg.norm(plain.translation - p)
    assert exp.projection.orientation_rms > 1e-4  # tilted poses: not expressed, and said


def test_export_volumetric_map_from_the_cli(tmp_path, ur5_calibration):
    out = tmp_path / "map.csv"
    args = ["export", str(ur5_calibration), "--format", "volumetric-map", "--out", str(out)]
    res = CliRunner().invoke(main, [*args, "--poses", "20"])
    assert res.exit_code == 0, res.output
    text = out.read_text()
    assert text.startswith("# pincal export --format volumetric-map")
    assert "cannot express:" in text and "x_m,y_m,z_m,reachable" in text
    axes, _, rows = _read(text)
    assert len(rows) == np.prod([a.size for a in axes])  # every node written, unreachable too


def test_a_redundant_arm_map_names_what_it_cannot_hold(delta):
    """An articulated-arm CMM (6 joints, [x y z] measured) reaches a position in many
    configurations whose errors differ: the map holds one per node and says so; a Delta
    (3 actuators, 3 components) has nothing of the kind to say."""
    arm = load_mechanism("aacmm")
    ps = parameters(arm, "dh")
    moved = ps.apply(arm, np.random.default_rng(0).uniform(-1e-4, 1e-4, len(ps)))
    exp = export_calibration(CalibratedMachine.from_mechanisms(moved, arm), "volumetric-map",
                             poses=20)  # fmt: skip
    said = [s for s in exp.projection.not_expressed if "configuration reaching" in s]
    assert said and "6 actuators for 3 imposed components" in said[0]
    assert not any("orientation" in s for s in exp.projection.not_expressed)  # not measured
    nominal, calibrated = delta
    plain = export_calibration(CalibratedMachine.from_mechanisms(calibrated, nominal),
                               "volumetric-map", poses=10)  # fmt: skip
    assert not any("configuration reaching" in s for s in plain.projection.not_expressed)

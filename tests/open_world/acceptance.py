"""The acceptance checks every machine style of tests/open_world/ runs.

1. FK/IK round trip: ``inverse(forward(q_act))`` gives q_act and the pose back ≤ 1e-9.
2. The analytic identification Jacobian of the ``base`` preset equals central finite
   differences (h = 1e-6) to 1e-6 of its largest entry, at zero and at random values.
3. Noise-free recovery of the ``base`` parameters (the identifiable ones) ≤ 1e-9.
4. The CLI: ``pincal simulate`` (errors on ``--params base``, no noise) →
   ``pincal calibrate`` (recovers the simulated errors) → ``pincal compensate``
   (commands with which the simulated actual machine reaches the targets).
5. A noisy campaign through the CLI (:func:`noisy_campaign`): ``info → poses → simulate
   → calibrate → validate`` with the defaults and the default instrument noise; the
   validation RMS on fresh poses within 2.5× of the Cramér–Rao prediction (issue 36).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import scipy.linalg
from click.testing import CliRunner

from pincal.cli import main
from pincal.identification import identify
from pincal.io import read_commands, write_poses
from pincal.measure import simulate_measurements
from pincal.model import COMPONENTS, Mechanism, load_mechanism, sample_actuators
from pincal.sensitivity import identification_jacobian, parameters

ALL = ("x", "y", "z", "rx", "ry", "rz")


def _measured_error(mech: Mechanism, a: pin.SE3, b: pin.SE3) -> float:
    comps = [ALL.index(c) for c in mech.measured_components]
    err = np.concatenate([b.translation - a.translation, pin.log3(a.rotation.T @ b.rotation)])
    return float(np.max(np.abs(err[comps])))


def check_round_trip(mech: Mechanism, n: int = 4, seed: int = 3) -> None:
    """FK then IK then FK: actuator values and measured components back to ≤ 1e-9."""
    for row in sample_actuators(mech, n, np.random.default_rng(seed)):
        T = mech.forward(row)
        q_act = mech.inverse(T, q_guess=mech.q_home)
        assert _measured_error(mech, T, mech.forward(q_act)) <= 1e-9
        assert np.max(np.abs(q_act - row)) <= 1e-9


def _stack(mech: Mechanism, rows: np.ndarray, R_ref: list[np.ndarray]) -> np.ndarray:
    out = []
    for row, R0 in zip(rows, R_ref, strict=True):
        T = mech.forward(row)
        out.append(np.concatenate([T.translation, pin.log3(R0.T @ T.rotation)]))
    return np.concatenate(out)


def check_jacobian(
    mech: Mechanism, n_poses: int = 2, seed: int = 4, size: int | None = None
) -> float:
    """Analytic identification Jacobian of the base preset = central differences.

    ``size``: check a seeded random subset of that many base parameters (all: None).
    Returns the largest |entry| of the Jacobian [m or rad per m or rad].
    """
    params = parameters(mech, "base")
    if size is not None and size < len(params):
        pick = np.sort(np.random.default_rng(7).choice(len(params), size, replace=False))
        params = parameters(mech, [params.names[i] for i in pick])
    rows = sample_actuators(mech, n_poses, np.random.default_rng(seed))
    largest = 0.0
    for values in (np.zeros(len(params)), np.random.default_rng(7).normal(0, 2e-4, len(params))):
        J = identification_jacobian(mech, params, rows, values, components=ALL)
        at = params.apply(mech, values)
        R_ref = [at.forward(r).rotation for r in rows]
        h, cols = 1e-6, []
        for k in range(len(params)):
            e = np.zeros(len(params))
            e[k] = h
            plus = _stack(params.apply(mech, values + e), rows, R_ref)
            minus = _stack(params.apply(mech, values - e), rows, R_ref)
            cols.append((plus - minus) / (2 * h))
        J_fd = np.stack(cols, axis=1)
        assert np.max(np.abs(J - J_fd)) <= 1e-6 * np.max(np.abs(J))
        largest = max(largest, float(np.max(np.abs(J))))
    return largest


def check_recovery(
    mech: Mechanism, n_poses: int = 30, size: float = 2e-4, tol: float | None = 1e-9
) -> np.ndarray:
    """Noise-free recovery of the base parameters ≤ ``tol`` (None: not checked); the
    calibrated model predicts the measured components at fresh poses ≤ 1e-9 either
    way. Returns the recovered values."""
    params = parameters(mech, "base")
    rows = sample_actuators(mech, n_poses, np.random.default_rng(11))
    truth = np.random.default_rng(1).normal(0, size, len(params))
    meas = simulate_measurements(params.apply(mech, truth), rows)
    res = identify(mech, params, meas)
    assert res.success, res.message
    assert res.identified.all(), res.message
    actual = params.apply(mech, truth)
    for row in sample_actuators(mech, 5, np.random.default_rng(12)):
        assert _measured_error(mech, actual.forward(row), res.calibrated.forward(row)) <= 1e-9
    if tol is not None:
        assert np.max(np.abs(res.values - truth)) <= tol
    return res.values


def invoke(*args: str) -> str:
    """Run ``pincal ARGS``; assert success; return stdout."""
    res = CliRunner().invoke(main, [str(a) for a in args])
    assert res.exit_code == 0, res.output + repr(res.exception)
    return res.stdout


def controlled_components(mech: Mechanism) -> tuple[str, ...]:
    """As many measured components as the machine has degrees of freedom: those best
    moved by the actuators at home (column-pivoted QR of the actuator Jacobian)."""
    comps = tuple(mech.measured_components)
    if len(comps) <= mech.mobility:
        return comps
    rows = [COMPONENTS.index(c) for c in comps]
    q0 = mech.actuators_of(mech.q_home)
    T0, h, cols = mech.forward(q0), 1e-7, []
    for k in range(len(q0)):
        dq = np.zeros(len(q0))
        dq[k] = h
        T = mech.forward(q0 + dq)
        twist = np.r_[T.translation - T0.translation, pin.log3(T0.rotation.T @ T.rotation)]
        cols.append(twist[rows] / h)
    J = np.stack(cols, axis=1)  # (components, actuators)
    _, _, piv = scipy.linalg.qr(J.T, pivoting=True)
    keep = sorted(piv[: mech.mobility])
    return tuple(comps[i] for i in keep)


def check_cli(
    model: str | Path,
    tmp_path: Path,
    poses: int = 30,
    param_tol: float | None = 1e-8,
    target_rows: np.ndarray | None = None,
) -> dict:
    """simulate → calibrate → compensate through the CLI with the base preset.

    The calibrated parameters match the simulated errors to ``param_tol`` (None: not
    checked; the CSV holds values to 1e-12 relative) and the compensation commands
    bring the simulated actual machine to the targets: the poses it reaches at
    ``target_rows`` (default: 5 random workspace rows).

    Returns:
        ``{"calibrate": identification.json, "commands": (m, n_act), "targets": rows}``.
    """
    data = tmp_path / "meas.csv"
    invoke(
        "simulate",
        model,
        "--random",
        poses,
        "--params",
        "base",
        "--errors",
        "seed:3",
        "--error-size",
        "0.2,1",
        "--noise",
        "0,0",
        "--out",
        data,
    )
    truth = json.loads(data.with_suffix(".truth.json").read_text())
    doc = json.loads(
        invoke(
            "calibrate",
            model,
            "--data",
            data,
            "--params",
            "base",
            "--out",
            tmp_path / "cal",
            "--json",
        )
    )
    true = {p["name"]: p["value"] for p in truth["parameters"]}
    found = {p["name"]: p["value"] for p in doc["parameters"]}
    assert set(found) == set(true)
    if param_tol is not None:
        assert max(abs(found[n] - true[n]) for n in true) <= param_tol
    # targets: poses the actual (simulated) machine reaches at fresh actuator values
    nominal = load_mechanism(model)
    base = parameters(nominal, "base")
    actual = base.apply(nominal, np.array([true[n] for n in base.names]))
    rows = (
        sample_actuators(nominal, 5, np.random.default_rng(21))
        if target_rows is None
        else np.asarray(target_rows, dtype=float)
    )
    targets = [actual.forward(r) for r in rows]
    write_poses(tmp_path / "targets.csv", targets, length_unit="m", angle_unit="rad")
    urdf = next((tmp_path / "cal").glob("*.urdf"))
    invoke(
        "compensate",
        urdf,
        "--targets",
        tmp_path / "targets.csv",
        "--components",
        ",".join(controlled_components(nominal)),
        "--out",
        tmp_path / "cmd.csv",
    )
    idx, commands = read_commands(tmp_path / "cmd.csv", nominal)
    assert list(idx) == list(range(len(rows)))
    for q_act, T in zip(commands, targets, strict=True):
        assert _measured_error(nominal, T, actual.forward(q_act)) <= 1e-7
    if param_tol is not None:  # the calibrated model is the actual one: same commands
        assert np.max(np.abs(commands - rows)) <= 1e-6
    return {"calibrate": doc, "commands": commands, "targets": rows}


def noisy_campaign(model: str | Path, folder: Path, poses: int = 30) -> dict:
    """``info → poses → simulate → calibrate → validate`` on ``model`` with the defaults.

    ``poses --count poses --preset base`` (O1 from random:300 candidates); an actual
    machine with seeded errors (0.2 mm / 1 mrad on ``--params base``) measured at those
    poses with the default instrument noise (0.01 mm / 0.02 mrad); ``calibrate --params
    base``; ``validate`` on 60 fresh random poses of the same actual machine.

    Returns:
        validate's JSON (``before``/``after`` errors, the Cramér–Rao ``predicted``).
    """
    invoke("info", model)
    invoke("poses", model, "--count", poses, "--preset", "base", "--candidates",
           "random:300", "--out", folder / "p.csv")  # fmt: skip
    errors = ("--params", "base", "--errors", "seed:3", "--error-size", "0.2,1")
    invoke("simulate", model, "--poses", folder / "p.csv", *errors, "--out", folder / "m.csv")
    invoke("simulate", model, "--random", 60, "--seed", 9, *errors, "--out", folder / "v.csv")
    invoke("calibrate", model, "--data", folder / "m.csv", "--params", "base",
           "--out", folder / "cal")  # fmt: skip
    return json.loads(invoke("validate", folder / "cal", "--data", folder / "v.csv", "--json"))


def prediction_ratio(doc: dict) -> tuple[float, float | None, str]:
    """(achieved RMS, Cramér–Rao RMS with the noise or None when withheld, unit) of a
    validate JSON: position [mm], or orientation [mrad] for a machine measuring none."""
    block = "position" if doc["after"]["rms_position_mm"] is not None else "orientation"
    unit = "mm" if block == "position" else "mrad"
    return (doc["after"][f"rms_{block}_{unit}"],
            doc["predicted"][f"observed_rms_{block}_{unit}"], unit)  # fmt: skip

"""ISO 9283 acceptance of a machine, as ``pincal acceptance`` runs it.

Two ways: measured repeated poses (:func:`measured_characteristics`: the rows with equal
actuator values are one commanded pose, commanded by the nominal or the calibrated
model), or a simulation on the ISO test cube (:func:`pincal.validation.iso_test_cube`,
recorded by :func:`cube_doc`): the actual machine carries the uniform errors of
``pincal simulate`` (:func:`acceptance_machine`) and is commanded through
:func:`cycle_characteristics` by the nominal model (before) or by the calibrated one
(after, :func:`calibrated_controller`). :func:`other_machine` says when the simulated machine
is not the one the calibration was fitted on. Nothing is printed or written.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from pincal._files import read_text
from pincal.errors import CalibrationDirectoryError, MeasurementError, ParameterError, PincalError
from pincal.io import (
    IDENTIFICATION_FILE,
    MANIFEST,
    CalibrationDirectory,
    read_calibration,
    read_identification,
    read_measurements,
)
from pincal.measure import Measurements
from pincal.model import Mechanism, ParameterSet
from pincal.sensitivity import parameters
from pincal.validation import (
    PoseCharacteristics,
    TestCube,
    pose_characteristics,
    simulate_cycles,
)

__all__ = [
    "AcceptanceMachine",
    "acceptance_machine",
    "calibrated_controller",
    "cube_doc",
    "cycle_characteristics",
    "fitted_truths",
    "held_out_machine",
    "measured_characteristics",
    "other_machine",
]


def calibrated_controller(
    spec: str,
    nominal: Mechanism,
    announce: Callable[[CalibrationDirectory], None] | None = None,
) -> Mechanism:
    """The calibrated machine from a calibration directory or an identification.json.

    A calibration directory is read (and checked) by :func:`pincal.io.read_calibration`
    and passed to ``announce`` (its caveat, for the caller to show); a directory without
    a manifest, or a file, through its identification.json
    (:func:`pincal.io.read_identification`): the record's values applied to ``nominal``.

    Raises:
        CalibrationDirectoryError / ParameterError: nothing usable at ``spec``, or a
            calibration of another model (another robot name or actuated joints than
            ``nominal``'s: its controller would command a machine it does not describe).
    """
    path = Path(spec)
    if (path / MANIFEST).is_file():  # a calibration directory: read (and checked) as one
        cal = read_calibration(path)
        if announce is not None:
            announce(cal)
        calibrated = cal.calibrated()
        if (calibrated.name, calibrated.actuated) != (nominal.name, nominal.actuated):
            model = cal.manifest.get("model") or calibrated.name
            raise ParameterError(
                f"calibration {spec!r} is of model {model!r} (robot {calibrated.name!r}), not "
                f"of MODEL's robot {nominal.name!r}: its 'after' figures would command another "
                f"machine; pass its model: pincal acceptance {model} --calibrated {spec}"
            )
        return calibrated
    if path.is_dir():
        path = path / IDENTIFICATION_FILE
    record = read_identification(path)
    try:
        return record.applied_to(nominal)
    except ParameterError as exc:
        raise ParameterError(f"{str(path)!r}: {exc}") from None


@dataclass(frozen=True)
class AcceptanceMachine:
    """The actual machine of a simulated acceptance test.

    Attributes:
        params: the parameter set of the errors (a preset of the nominal model).
        values: (len(params),) the errors drawn [m, rad] (zeros without errors).
        actual: the nominal model with ``values`` applied.
        preset: the name of the preset ``params`` is ("" when not given).
        size: the bounds of the draw (length [mm], angle [mrad]).
    """

    params: ParameterSet
    values: np.ndarray
    actual: Mechanism
    preset: str = ""
    size: tuple[float, float] = (0.0, 0.0)

    def settings(self, errors: str) -> dict[str, Any]:
        """The draw's settings as a ``<data>.truth.json`` records them, for :func:`other_machine`.

        ``errors``: the ``--errors`` text (``seed:N`` or ``none``).
        """
        return {"model": self.actual.name, "preset": self.preset, "errors": errors,
                "error_size_mm_mrad": list(self.size)}  # fmt: skip


def acceptance_machine(
    nominal: Mechanism,
    preset: str | None,
    seed: int | None,
    size_mm: float,
    size_mrad: float,
) -> AcceptanceMachine:
    """The nominal model with uniform errors, as ``pincal simulate`` draws them.

    Args:
        nominal: the nominal model.
        preset: the preset of the errors; None: the model's first preset (else ``full``).
        seed: seed of the draw; None: no errors.
        size_mm: bound of the length errors [mm].
        size_mrad: bound of the angle errors [mrad].
    """
    name = preset or next(iter(nominal.presets), "full")
    params = parameters(nominal, name)
    values = np.zeros(len(params))
    if seed is not None:
        er = np.random.default_rng(seed)
        bound = np.array([size_mm * 1e-3 if u == "m" else size_mrad * 1e-3 for u in params.units])
        values = er.uniform(-bound, bound)
    return AcceptanceMachine(
        params, values, params.apply(nominal, values), name, (size_mm, size_mrad)
    )


def other_machine(
    cal: str,
    params: ParameterSet,
    values: np.ndarray,
    settings: dict[str, Any] | None = None,
) -> list[str]:
    """Warnings when the simulated machine is not the one the calibration was fitted on.

    A calibration of simulated data records its data file; ``pincal simulate`` wrote the
    truth beside it (``<data>.truth.json``). When the errors simulated here differ from
    that truth, the "after" figures test the calibration on another machine: one line
    per truth file, saying which settings differ (there → here) and what to pass.

    Args:
        cal: the calibration (a directory; anything else: no warning).
        params: the parameter set of the errors simulated here.
        values: (len(params),) those errors [m, rad].
        settings: the settings simulated here, as the truth file records them (keys
            ``model``, ``preset``, ``errors``, ``error_size_mm_mrad``); None: not said.
    """
    if not (Path(cal) / MANIFEST).is_file():
        return []
    here = dict(zip(params.names, np.asarray(values, dtype=float), strict=True))
    out = []
    for truth_path, truth in fitted_truths(read_calibration(cal)):
        if not _same_errors(_true_values(truth), here):
            out.append(f"the machine simulated here is not the one the calibration was fitted "
                       f"on ({truth_path}: {_differences(truth, settings or {})}): the 'after' "
                       f"figures test the calibration on another machine; to test it on its "
                       f"own, pass {_options(truth)}")  # fmt: skip
    return out


def fitted_truths(directory: CalibrationDirectory) -> list[tuple[Path, dict[str, Any]]]:
    """The ``<data>.truth.json`` of ``pincal simulate`` beside the calibration's data files.

    Each data file is found by its hash, wherever calibrate ran; a file not found, without
    a truth beside it or with an unreadable one is left out. Returns (path, document) pairs.
    """
    out = []
    for k in range(len(directory.manifest.get("data_files") or [])):
        try:
            truth_path = directory.data_file(k).with_suffix(".truth.json")
        except CalibrationDirectoryError:
            continue
        truth = _read_truth(truth_path)
        if truth is not None:
            out.append((truth_path, truth))
    return out


def held_out_machine(directory: CalibrationDirectory, data: Path) -> list[str]:
    """Warnings when a held-out file was simulated on another machine than the fit's data.

    Both ``<data>.truth.json`` (the held-out file's and the calibration's data files') are
    compared: true errors [m, rad] and thermal coefficients [1/K]. One line per differing
    truth, saying which ``simulate`` settings differ and what to pass.
    """
    held = _read_truth(Path(data).with_suffix(".truth.json"))
    if held is None:
        return []
    out = []
    for fit_path, fit in fitted_truths(directory):
        warm = _same_errors(_thermal(fit), _thermal(held))
        if not (warm and _same_errors(_true_values(fit), _true_values(held))):
            differs = _differences(fit, held, warm).replace(" here", " for the held-out file")
            differs = differs.replace(" there,", " for the calibration's data,")
            out.append(f"{data} was simulated on another machine than the calibration's data "
                       f"({fit_path}: {differs}): the figures test the calibration on another "
                       f"machine; simulate the held-out file with {_options(fit)}")  # fmt: skip
    return out


def _read_truth(path: Path) -> dict[str, Any] | None:
    """A truth document ``pincal simulate`` wrote, or None (no file, not JSON, not one).

    Read as every input is: a regular file under the size cap.
    """
    if not path.is_file():
        return None
    try:
        truth = json.loads(read_text(path, "truth file"))
    except (PincalError, ValueError):
        return None
    entries = truth.get("parameters") if isinstance(truth, dict) else None
    if not isinstance(entries, list) or not all(
        isinstance(p, dict)
        and isinstance(p.get("name"), str)
        and isinstance(p.get("value"), int | float)
        for p in entries
    ):
        return None
    return truth


def _true_values(truth: dict[str, Any]) -> dict[str, float]:
    """The truth's parameter values by name [m, rad]."""
    return {p["name"]: float(p["value"]) for p in truth.get("parameters", [])}


def _same_errors(a: dict[str, float], b: dict[str, float]) -> bool:
    """One machine: every value equal (to 1e-12), a name missing on one side counts as 0."""
    return all(abs(a.get(n, 0.0) - b.get(n, 0.0)) <= 1e-12 for n in set(a) | set(b))


def _thermal(truth: dict[str, Any]) -> dict[str, float]:
    """The truth's thermal coefficients by name [1/K] (empty: no thermal expansion)."""
    return {str(k): float(v) for k, v in (truth.get("thermal_1_per_K") or {}).items()}


def _alpha(truth: dict[str, Any]) -> str:
    """The truth's ``--thermal`` coefficient in words [1/K] ("none" without expansion)."""
    alphas = sorted(set(_thermal(truth).values()))
    return "none" if not alphas else " / ".join(f"{a:g}" for a in alphas)


def _options(truth: dict[str, Any]) -> str:
    """The ``simulate`` options (errors, preset, size, thermal) that draw the truth's machine."""
    size = truth.get("error_size_mm_mrad")
    hint = f"--errors {truth.get('errors')} --params {truth.get('preset')}"
    hint += f" --error-size {size[0]:g},{size[1]:g}" if size else ""
    return hint + (f" --thermal {_alpha(truth)}" if _thermal(truth) else "")


def _differences(truth: dict[str, Any], here: dict[str, Any], warm: bool = True) -> str:
    """Which of the truth's settings differ from ``here``'s, in words (there → here).

    ``warm``: False when both are truths whose thermal coefficients differ (said too).
    """

    def shown(key: str, value: Any) -> str:
        if key == "error_size_mm_mrad" and isinstance(value, list | tuple) and len(value) == 2:
            return f"{value[0]:g},{value[1]:g}"
        return str(value)

    words = {"model": "model", "preset": "--params", "errors": "--errors",
             "error_size_mm_mrad": "--error-size"}  # fmt: skip
    said = []
    for key, word in words.items():
        if key in here and key in truth:
            there, now = shown(key, truth[key]), shown(key, here[key])
            if there != now:
                said.append(f"{word} {there} there, {now} here")
    if not warm:
        said.append(f"--thermal {_alpha(truth)} there, {_alpha(here)} here")
    return "; ".join(said) or "the same settings, other error values"


def _grouped(
    meas: Measurements, controller: Mechanism
) -> tuple[list[pin.SE3], np.ndarray, np.ndarray | None]:
    """Commands (forward kinematics of the distinct actuator rows) and the poses per row."""
    keys, first, inverse = np.unique(meas.q_act, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)
    counts = np.bincount(inverse.reshape(-1))
    if len(set(counts.tolist())) != 1 or counts[0] < 2:
        raise MeasurementError(
            f"every commanded pose must be measured the same number (≥ 2) of times; got "
            f"counts {counts[order].tolist()}"
        )
    if meas.rotations is None and any(c.startswith("r") for c in meas.components):
        raise MeasurementError(
            f"the file declares components {' '.join(meas.components)} but holds no "
            "orientation; measure the orientation or declare position components only"
        )
    poses, pos, rot = [], [], []
    for g in order:
        rows = np.flatnonzero(inverse.reshape(-1) == g)
        poses.append(controller.forward(keys[g]))
        pos.append(meas.positions[rows])
        if meas.rotations is not None:
            rot.append(meas.rotations[rows])
    return poses, np.array(pos), (np.array(rot) if rot else None)


def measured_characteristics(
    data_file: str, nominal: Mechanism, controller: Mechanism
) -> PoseCharacteristics:
    """AP / RP of measured repeated poses (a pincal measurements file).

    Args:
        data_file: the measurements; rows with equal actuator values are one commanded
            pose, each measured the same number (≥ 2) of times; its components are judged.
        nominal: the model the file is read with.
        controller: the model whose forward kinematics gives the commanded poses.

    Raises:
        MeasurementError: unequal repetitions, or orientation declared but not held.
    """
    meas = read_measurements(data_file, nominal)
    poses, pos, rot = _grouped(meas, controller)
    return pose_characteristics(poses, pos, rot, tuple(meas.components))


def cube_doc(cube: TestCube) -> dict[str, Any]:
    """The ``cube`` entry of the acceptance JSON (lengths in m)."""
    return {
        "shape": cube.shape,
        "axes": list(cube.axes),
        "components": list(cube.components),
        "workspace": cube.workspace,
        "bounds": np.asarray(cube.bounds).tolist(),
        "centre": cube.centre.tolist(),
        "edge": cube.edge,
        "points": cube.points.tolist(),
    }


def cycle_characteristics(
    actual: Mechanism,
    controller: Mechanism,
    cube: TestCube,
    cycles: int,
    actuator_std: float,
    seed: int,
    progress: Callable[[int, int], None] | None = None,
) -> PoseCharacteristics:
    """AP / RP of ``actual`` commanded by ``controller`` through the cube's five poses.

    Args:
        actual: the simulated machine.
        controller: the model whose inverse kinematics gives the commands.
        cube: the test cube (:func:`pincal.validation.iso_test_cube`).
        cycles: cycles of the five poses.
        actuator_std: actuator repeatability 1σ [m or rad].
        seed: seed of the actuators' errors.
        progress: called with (cycles done, cycles).
    """
    _, pos, rot = simulate_cycles(
        actual, controller, cube.poses, cycles, actuator_std, seed, progress
    )
    return pose_characteristics(cube.poses, pos, rot, cube.components)

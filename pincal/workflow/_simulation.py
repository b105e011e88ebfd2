"""A measurement campaign of a simulated "actual" machine, as ``pincal simulate`` runs it.

:func:`simulate_campaign` draws random geometric errors on a preset's parameters (none
on those a built machine cannot have, :func:`buildable_mask`), keeps the poses the
erroneous machine reaches and measures it there: noisy poses (optionally at drawn
temperatures), a scalar instrument's readings, or a ball seated in two sockets 50 mm
apart. It returns the data and the truth (:class:`SimulatedCampaign`); nothing is
written.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from pincal.errors import ConvergenceError
from pincal.identification import default_instrument
from pincal.io import read_pose_rows
from pincal.measure import (
    InstrumentData,
    KnownDistance,
    Measurements,
    NoiseModel,
    SocketData,
    SocketPlate,
    simulate_instrument,
    simulate_measurements,
    simulate_sockets,
)
from pincal.model import (
    Mechanism,
    actual_joint_values,
    actual_shift,
    sample_actuators,
    with_joint_terms,
)
from pincal.sensitivity import parameters
from pincal.workflow._buildable import buildable_mask

__all__ = [
    "SOCKET_SPACING",
    "SimulatedCampaign",
    "ThermalDraw",
    "default_sockets",
    "reachable_rows",
    "simulate_campaign",
    "thermal_machine",
]

#: the known distance between the two simulated sockets [m]
SOCKET_SPACING = 0.05

Say = Callable[[str], None]

@dataclass(frozen=True)
class ThermalDraw:
    """A machine expanding with temperature (``simulate --temperature``).

    Attributes:
        span: (low, high) temperatures [°C]; each pose's is drawn uniformly in it.
        alpha: the true expansion coefficient of every actuated joint's length [1/K].
    """

    span: tuple[float, float]
    alpha: float


def thermal_machine(
    nominal: Mechanism, q_act: np.ndarray, draw: ThermalDraw, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray, np.ndarray, dict[str, float]]:
    """The joint values and shifts of a machine expanding with temperature.

    Args:
        nominal: the nominal mechanism.
        q_act: (m, n_act) commands [rad, m].
        draw: the temperature span and the true coefficient.
        rng: the random generator (draws each pose's temperature).

    Returns:
        (joint values (m, n_act) the machine takes, world position change (m, 3) of the
        measured frame [m], temperatures (m,) [°C], {parameter name: α [1/K]}).
    """
    terms = with_joint_terms(nominal, parameters(nominal, [f"{nominal.actuated[0]}.offset"]),
                             ("temperature",))  # fmt: skip
    values = np.zeros(len(terms))
    values[terms.joint_terms] = draw.alpha
    T = rng.uniform(draw.span[0], draw.span[1], len(q_act))
    cond = {"temperature": T}
    q = actual_joint_values(nominal, terms, values, q_act, cond)
    shift = actual_shift(nominal, terms, values, q_act, cond)
    return q, shift, T, {terms.names[k]: draw.alpha for k in terms.joint_terms}


@dataclass(frozen=True)
class SimulatedCampaign:
    """A simulated campaign as :func:`simulate_campaign` returns it.

    Attributes:
        data: the measurements: poses, a scalar instrument's readings or socket poses.
        components: what each row holds (the measured components, the instrument kind,
            or ``socket``).
        model: the nominal model's name.
        preset: the preset the errors are drawn on.
        error_size: the error bounds (length [mm], angle [mrad]).
        names: the preset's parameter names, (n,).
        units: their units (``m`` or ``rad``), (n,).
        values: the true errors (n,) [m, rad] (0 where none was drawn).
        extra: further truth: the instrument's or sockets' true parameters [m, rad], or
            the true thermal coefficients [1/K].
        skipped: 1-based rows the actual machine did not reach (left out).
    """

    data: Measurements | InstrumentData | SocketData
    components: tuple[str, ...]
    model: str
    preset: str
    error_size: tuple[float, float]
    names: tuple[str, ...]
    units: tuple[str, ...]
    values: np.ndarray
    extra: dict[str, Any]
    skipped: list[int]

    def truth(self, written_by: str, errors: str) -> dict[str, Any]:
        """The ``<out>.truth.json`` document; ``errors``: the ``--errors`` text."""
        return {
            "written_by": written_by,
            "model": self.model,
            "preset": self.preset,
            "errors": errors,
            "error_size_mm_mrad": list(self.error_size),
            "parameters": [
                {"name": n, "unit": u, "value": float(v)}
                for n, u, v in zip(self.names, self.units, self.values, strict=True)
            ],
            **self.extra,
            "skipped_rows": self.skipped,
        }


def simulate_campaign(
    nominal: Mechanism,
    preset: str,
    poses_file: str | Path | None,
    n_random: int | None,
    *,
    error_seed: int | None,
    error_size: tuple[float, float],
    noise: tuple[float, float],
    seed: int,
    instrument: str | None = None,
    sockets: bool = False,
    thermal: ThermalDraw | None = None,
    say: Say | None = None,
) -> SimulatedCampaign:
    """Measure an "actual" machine: ``nominal`` with random errors on ``preset``.

    Args:
        nominal: the nominal mechanism.
        preset: the preset whose parameters get the errors.
        poses_file: a poses (or commands, measurements) file of the commands measured;
            None: ``n_random`` random workspace poses.
        n_random: number of random poses (with ``poses_file`` None, and with ``sockets``:
            half seat the ball in each socket).
        error_seed: seed of the uniform error draw; None: no errors.
        error_size: uniform error bounds ± (lengths [mm], angles [mrad]).
        noise: measurement noise 1σ (position [mm], orientation [mrad]); a scalar
            instrument's and the sockets' 1σ is the position noise.
        seed: seed of the random poses and the noise.
        instrument: a registered scalar instrument kind measured instead of poses.
        sockets: seat a ball in two sockets :data:`SOCKET_SPACING` apart instead.
        thermal: the machine expands with temperature (``--temperature``; poses only).
        say: given the progress and notes, one line each (stderr on the command line).

    Raises:
        ConvergenceError: the actual machine reaches none of the poses.
    """
    tell = say or (lambda _line: None)
    params = parameters(nominal, preset)
    values = np.zeros(len(params))
    rng = np.random.default_rng(seed)
    if poses_file is not None:
        q_act = read_pose_rows(poses_file, nominal)
    else:
        assert n_random is not None  # exactly one of poses_file / n_random
        tell(f"… sampling {n_random} random poses")
        q_act = sample_actuators(nominal, n_random, rng)
    size_mm, size_mrad = error_size
    if error_seed is not None:
        er = np.random.default_rng(error_seed)
        bound = np.array([size_mm * 1e-3 if u == "m" else size_mrad * 1e-3 for u in params.units])
        values = er.uniform(-bound, bound) * buildable_mask(nominal, params, q_act, say=tell)
    actual = params.apply(nominal, values)
    skipped: list[int] = []
    if not sockets:
        q_act, skipped = reachable_rows(actual, q_act, tell)
    tell(f"… measuring {len(q_act)} poses of the actual machine")
    pos_mm, ori_mrad = noise
    extra: dict[str, Any] = {}
    data: Measurements | InstrumentData | SocketData
    if sockets:
        assert n_random is not None  # sockets seat the ball at random poses
        centres = default_sockets(nominal)
        std = pos_mm * 1e-3
        plate = SocketPlate("plate", std, (KnownDistance("A", "B", SOCKET_SPACING, std),))
        per = max(n_random // 2, 1)
        tell(f"… seating the ball {per} times in each of 2 sockets 50 mm apart")
        data = simulate_sockets(actual, plate, centres, per, rng)
        components: tuple[str, ...] = ("socket",)
        extra["instrument"] = {
            f"plate.{s}_{a}": float(c[i]) for s, c in centres.items() for i, a in enumerate("xyz")
        }
    elif instrument is not None:
        inst, theta, ids = default_instrument(nominal, instrument, q_act, std=pos_mm * 1e-3)
        data = simulate_instrument(actual, inst, theta, q_act, rng, ids=ids)
        components = (data.kind,)
        extra["instrument"] = dict(zip(inst.parameter_names, map(float, theta), strict=True))
    elif thermal is not None:
        q_true, shift, T, alphas = thermal_machine(nominal, q_act, thermal, rng)
        poses = simulate_measurements(actual, q_true, NoiseModel(pos_mm, ori_mrad), rng)
        data = dataclasses.replace(
            poses, q_act=np.array(q_act, dtype=float), positions=poses.positions + shift,
            temperature=T,
        )  # fmt: skip
        components = tuple(data.components)
        extra["thermal_1_per_K"] = alphas
    else:
        data = simulate_measurements(actual, q_act, NoiseModel(pos_mm, ori_mrad), rng)
        components = tuple(data.components)
    return SimulatedCampaign(
        data, components, nominal.name, preset, (size_mm, size_mrad), tuple(params.names),
        tuple(params.units), values, extra, skipped,
    )  # fmt: skip


def reachable_rows(
    actual: Mechanism, q_act: np.ndarray, say: Say | None = None
) -> tuple[np.ndarray, list[int]]:
    """The rows (m, n_act) the actual machine reaches and the others' 1-based numbers.

    Tells ``say`` how many were skipped, which and why.

    A pose the erroneous machine cannot close on its home assembly branch (its loops
    open near the workspace's edge) is left out of the campaign, as a measurement
    campaign skips a pose the machine refuses.

    Raises:
        ConvergenceError: the actual machine reaches none of the rows.
    """
    ok = actual.closable_batch(q_act)
    skipped = [int(i) + 1 for i in np.flatnonzero(~ok)]
    if not ok.any():
        raise ConvergenceError(
            f"the actual machine (the model with the simulated errors) reaches none of the "
            f"{len(q_act)} poses: its loops do not close on home's assembly branch there; "
            "choose poses away from the workspace's edges or smaller --error-size"
        )
    if skipped and say is not None:
        shown = ", ".join(map(str, skipped[:20])) + (", …" if len(skipped) > 20 else "")
        say(
            f"skipped {len(skipped)} of {len(q_act)} poses the actual machine cannot reach "
            f"(its loops do not close on home's assembly branch with the simulated errors, "
            f"at the workspace's edge): rows {shown}; the file lists the {int(ok.sum())} "
            "reached"
        )
    return np.asarray(q_act)[ok], skipped


def default_sockets(mech: Mechanism) -> dict[str, np.ndarray]:
    """Two socket centres (3,) [m], 50 mm apart, inside the reach of ``mech``.

    Socket A lies at 60 % of the home tool point's horizontal reach (its height kept),
    B 50 mm from A, horizontal and across the reach.
    """
    p = mech.frame_placement(mech.q_home).translation
    a = np.array([0.6 * p[0], 0.6 * p[1], p[2]])
    across = np.array([-p[1], p[0], 0.0])
    norm = float(np.linalg.norm(across))
    across = across / norm if norm > 1e-9 else np.array([1.0, 0.0, 0.0])
    return {"A": a, "B": a + SOCKET_SPACING * across}

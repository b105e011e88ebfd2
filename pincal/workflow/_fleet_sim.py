"""A simulated fleet as ``pincal fleet simulate`` makes it, without the CLI.

:func:`plan_fleet` loads the model, draws the fleet (:func:`draw_fleet`) and returns a
:class:`FleetPlan`: each unit's measurements are simulated on demand
(:meth:`FleetPlan.measurements`, one unit at a time, so a large fleet is never held in
memory) and :meth:`FleetPlan.truth` is the ``truth.json`` document. Nothing is written.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from pincal.measure import Measurements, NoiseModel
from pincal.model import Mechanism, ParameterSet, load_mechanism
from pincal.sensitivity import parameters
from pincal.workflow._buildable import buildable_mask
from pincal.workflow._fleet_draw import FleetDraw, draw_fleet, simulate_unit

__all__ = ["SESSION_DATES", "FleetPlan", "plan_fleet"]

#: the dates of a recalibrated unit's two sessions in a simulated fleet file
SESSION_DATES = ("2026-01-15", "2026-07-15")


@dataclass(frozen=True)
class FleetPlan:
    """A drawn fleet, ready to be measured unit by unit.

    Attributes:
        model: the model as given; nominal: its mechanism.
        preset: the parameter preset (the model's first when none was given).
        params: the parameter set drawn.
        draw: the fleet's true geometry (:class:`FleetDraw`).
        ids: the units' ids ``SN-0001``… (N,).
        seed: the fleet's seed; n_poses: random poses per unit.
        spread: 1σ production spread (lengths [mm], angles [mrad]).
        shift: a faulty part's shift [production σ].
        noise: the instrument noise (mm, mrad).
    """

    model: str
    nominal: Mechanism
    preset: str
    params: ParameterSet
    draw: FleetDraw
    ids: tuple[str, ...]
    seed: int
    n_poses: int
    spread: tuple[float, float]
    shift: float
    noise: NoiseModel

    def measurements(self, i: int, second: bool = False) -> Measurements:
        """Unit ``i``'s simulated measurements (``n_poses`` random poses, its own seed).

        ``second``: its second session (a recalibrated unit: ``i in draw.second``).
        """
        draw = self.draw
        values, seed = (draw.second[i], draw.second_seeds[i]) if second else (
            draw.values[i], draw.seeds[i])  # fmt: skip
        return simulate_unit(self.nominal, self.params, values, self.n_poses, self.noise, seed)

    def sessions(self, i: int) -> list[tuple[dict[str, str], bool]]:
        """Unit ``i``'s fleet-file entries ``{id, data[, date]}`` and whether each is its second.

        Data paths are relative to the fleet file; a recalibrated unit has two entries,
        dated :data:`SESSION_DATES`.
        """
        uid = self.ids[i]
        first = {"id": uid, "data": f"{uid}/measurements.csv"}
        if i not in self.draw.second:
            return [(first, False)]
        second = {"id": uid, "data": f"{uid}/recalibration.csv", "date": SESSION_DATES[1]}
        return [(first | {"date": SESSION_DATES[0]}, False), (second, True)]

    def truth(self) -> dict[str, Any]:
        """``truth.json`` (JSON-ready): the settings, offset, planted units, true values.

        Values are parameter errors [m, rad] in the order of ``names``;
        ``recalibrated`` lists the second sessions' values and drifts.
        """
        draw, ids = self.draw, self.ids
        return {
            "model": self.model,
            "preset": self.preset,
            "seed": self.seed,
            "poses_per_unit": self.n_poses,
            "spread_mm_mrad": list(self.spread),
            "shift_sigma": self.shift,
            "noise_mm_mrad": [self.noise.position, self.noise.orientation],
            "names": list(draw.names),
            "offset": draw.offset.tolist(),
            "planted": [{"id": ids[i], "parameters": p} for i, p in sorted(draw.planted.items())],
            "units": [{"id": ids[i], "values": draw.values[i].tolist()} for i in range(len(ids))],
            "recalibrated": [
                {"id": ids[i], "values": v.tolist(), "drift": draw.drifts.get(i, {})}
                for i, v in draw.second.items()
            ],
        }


def plan_fleet(
    model: str,
    n_units: int,
    seed: int = 0,
    *,
    preset: str | None = None,
    n_poses: int = 40,
    planted: int | None = None,
    spread: tuple[float, float] = (0.1, 0.5),
    shift: float = 8.0,
    noise: tuple[float, float] = (0.01, 0.02),
    recalibrated: int = 0,
    drifted: int = 0,
) -> FleetPlan:
    """Load ``model`` and draw a fleet of ``n_units`` of it (see :func:`draw_fleet`).

    Args:
        model: model name or file.
        n_units: N ≥ 2 units.
        seed: the fleet's seed (geometry, planted units, poses, noise).
        preset: parameter preset (None: the model's first, or ``full``).
        n_poses: random poses measured per unit.
        planted: out-of-family units (None: max(1, 3 % of N)).
        spread: 1σ production spread (lengths [mm], angles [mrad]).
        shift: a faulty part's shift, in production σ.
        noise: instrument noise 1σ (position [mm], orientation [mrad]).
        recalibrated: units measured again in a second session.
        drifted: of those, units with a part moved between the sessions.

    Raises:
        PincalError subclasses of loading the model, of the preset and of the draw.
    """
    nominal = load_mechanism(model)
    preset = preset or next(iter(nominal.presets), "full")
    params = parameters(nominal, preset)
    free = buildable_mask(nominal, params, nominal.actuators_of(nominal.q_home)[None])
    draw = draw_fleet(params, n_units, seed, spread_mm=spread[0], spread_mrad=spread[1],
                      planted=planted, shift=shift, free=free, recalibrated=recalibrated,
                      drifted=drifted)  # fmt: skip
    ids = tuple(f"SN-{i + 1:04d}" for i in range(n_units))
    return FleetPlan(model, nominal, preset, params, draw, ids, seed, n_poses, spread, shift,
                     NoiseModel(*noise))  # fmt: skip

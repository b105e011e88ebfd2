"""The executable-pose screens of `pincal poses`: options and the compensation test.

The screens themselves are :func:`pincal.design.screen_candidates`; this module turns
the options into :class:`pincal.design.ScreenSettings` and supplies the compensation
test, which needs stage 6 (compensation) and so cannot live in the design stage: every
surviving candidate's nominal pose is compensated on the nominal model displaced by
random errors of the preset's parameters (uniform within ±``--reach-errors`` mm / mrad,
as ``pincal simulate --error-size`` draws them; :data:`DRAWS` draws seeded by
``--seed``), from the candidate's own command, limits checked, branch changes refused
— what ``pincal compensate`` does with a calibration of that size, imposing the
components the machine controls (:func:`controlled_components`). A candidate is kept
when it compensates on every draw.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, TypeVar

import click
import numpy as np
import pinocchio as pin

from pincal.errors import OptionValueError

if TYPE_CHECKING:  # imported in the calls: the CLI starts without the design stack
    from pincal.design import CandidateSet, ScreenSettings
    from pincal.model import Mechanism, ParameterSet

_F = TypeVar("_F", bound=Callable[..., object])

__all__ = [
    "DRAWS",
    "compensation_test",
    "controlled_components",
    "parse_reach_errors",
    "screen_options",
    "screen_settings",
]

#: error draws each candidate must compensate on
DRAWS = 3


def screen_options(func: _F) -> _F:
    """The screen options of `pincal poses` (see docs/cli.md, "Executable poses")."""
    options = [
        click.option("--joint-margin", type=float, default=0.05, show_default=True,
                     help="Share of each actuator range kept free at both ends."),
        click.option("--singular-margin", type=float, default=0.1, show_default=True,
                     help="Least σ_min of the actuator → pose Jacobian, relative to its "
                     "median over the candidates (0: off)."),
        click.option("--obstacle", "obstacles", multiple=True, metavar="'X Y Z DX DY DZ'",
                     help="A box of the surroundings [mm]: centre and edge lengths in the "
                     "world frame (repeatable); poses touching it are removed."),
        click.option("--no-collisions", is_flag=True,
                     help="Do not screen self-collisions and obstacles."),
        click.option("--reach-errors", default="1,10", show_default=True,
                     help="MM,MRAD: parameter errors of the model each pose must compensate "
                     "on (no branch change, within limits); 'none': not screened."),
    ]  # fmt: skip
    for option in reversed(options):
        func = option(func)
    return func


def parse_reach_errors(text: str) -> tuple[float, float] | None:
    """``"1,10"`` → (1.0, 10.0) [mm, mrad]; ``"none"`` → None."""
    if text.strip().lower() == "none":
        return None
    parts = text.replace(" ", "").split(",")
    try:
        pair = tuple(float(p) for p in parts)
    except ValueError:
        pair = ()
    if len(pair) != 2 or not all(np.isfinite(pair)) or min(pair) < 0:
        raise OptionValueError(
            f"--reach-errors {text!r} must be MM,MRAD (two numbers >= 0, e.g. 1,10) or none"
        )
    return pair[0], pair[1]


def screen_settings(
    joint_margin: float, singular_margin: float, obstacles: tuple[str, ...], no_collisions: bool
) -> ScreenSettings:
    """:class:`pincal.design.ScreenSettings` from the options (errors name the option)."""
    from pincal.cli._limits import naming_option
    from pincal.design import ScreenSettings, parse_box

    with naming_option("--obstacle"):
        boxes = tuple(parse_box(t) for t in obstacles)
    return ScreenSettings(joint_margin, singular_margin, not no_collisions, boxes)


def compensation_test(
    mech: Mechanism, params: ParameterSet, errors: tuple[float, float], seed: int
) -> Callable[[CandidateSet], np.ndarray]:
    """The ``compensable`` test of :func:`pincal.design.screen_candidates`.

    Args:
        mech: the nominal mechanism.
        params: the preset's parameter set (the errors are drawn on it, before any
            reduction to a base set, as ``pincal simulate`` draws them: none on
            parameters a built machine cannot have, :func:`buildable_mask`).
        errors: uniform error bounds (mm for lengths, mrad for angles).
        seed: random seed of the errors.
    """
    from pincal.cli._buildable import buildable_mask
    from pincal.compensation import compensate
    from pincal.errors import PincalError
    from pincal.model import sample_actuators

    rng = np.random.default_rng([seed, 37])
    bound = np.array([errors[0] * 1e-3 if u == "m" else errors[1] * 1e-3 for u in params.units])
    bound *= buildable_mask(mech, params, sample_actuators(mech, 10, np.random.default_rng(seed)))
    comps = controlled_components(mech)
    displaced, failed = [], []
    for _ in range(DRAWS):
        try:
            displaced.append(params.apply(mech, rng.uniform(-bound, bound)))
        except PincalError as exc:  # the displaced geometry does not assemble
            failed.append(str(exc).split(":")[0])
    if failed:
        click.echo(
            f"  reach screen: {len(failed)} of {DRAWS} error draws of ±{errors[0]:g} mm / "
            f"±{errors[1]:g} mrad do not assemble ({failed[0]}); "
            + ("screened on the others" if displaced else "not screened")
            + " (smaller --reach-errors, or none)",
            err=True,
        )

    def test(cands: CandidateSet) -> np.ndarray:
        ok = np.ones(len(cands), dtype=bool)
        targets = [pin.SE3(R, p) for R, p in zip(cands.rotations, cands.positions, strict=True)]
        for model in displaced:
            if not ok.any():
                break
            idx = np.flatnonzero(ok)
            result = compensate(
                model, [targets[i] for i in idx], starts=cands.q_act[idx], components=comps
            )
            ok[idx] = np.asarray(result.reachable, dtype=bool)
        return ok

    return test


def controlled_components(mech: Mechanism) -> tuple[str, ...]:
    """The measured components a target of the reach screen imposes.

    All of them when the machine moves as many; else, positions first, each component
    whose row of the actuator Jacobian at home [m or rad per m or rad] adds to the rank
    of those kept, up to the mobility (a planar five-bar measuring x y rz is screened on
    x y). Returns component names in x y z rx ry rz order.
    """
    from pincal.model import actuator_jacobian

    comps = tuple(mech.measured_components)
    if len(comps) <= mech.mobility:
        return comps
    G = actuator_jacobian(mech, mech.q_home)  # (components, actuators)
    order = sorted(range(len(comps)), key=lambda k: comps[k].startswith("r"))
    keep: list[int] = []
    for k in order:
        if len(keep) < mech.mobility and np.linalg.matrix_rank(G[[*keep, k]]) > len(keep):
            keep.append(k)
    return tuple(comps[k] for k in sorted(keep))

"""Every machine written here in other people's habits, and what pincal does with each.

:func:`machines` writes them (with the habit each shows); :func:`recover` is the
noise-free recovery every loadable one must pass for the ``base`` and ``full`` presets;
:func:`table` runs both and gives the README's open-world table (``python
scripts/studies/open_world_table.py``). Refused ones must be refused with their own message.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin
import yaml

from pincal.errors import (
    MobilityError,
    ModelFileError,
    PincalError,
    SingularConfigurationError,
)
from pincal.identification import GaussNewtonOptions, identify
from pincal.measure import simulate_measurements
from pincal.model import Mechanism, load_mechanism, sample_actuators
from pincal.sensitivity import identifiability, parameters
from tests.open_world import linkage_machines as lm
from tests.open_world import machines as m
from tests.open_world import paper_machines as pm

MODEL_MACHINES = Path(__file__).parents[1] / "model" / "machines"


@dataclass(frozen=True)
class Machine:
    """A machine of the roster: its name, the habits it is written in, the writer of its
    model (``write(folder) -> path``), and — for one that must be refused — the error
    class and a fragment of the message. ``unresolved``: (preset, reason) pairs whose
    noise-free recovery misses 1e-9 for a reason of the machine's own (a strict xfail)."""

    name: str
    habits: str
    write: Callable[[Path], Path]
    refused: tuple[type[PincalError], str] | None = None
    unresolved: tuple[tuple[str, str], ...] = ()


def mjcf_toe_leg() -> str:
    """MJCF text: the keyed four-bar of :func:`machines.mjcf_fourbar_straight` with a toe
    body on a spring hinge (``stiffness="5"``, ±30°) at the coupler's site; the site
    ``tool`` 3 cm along the toe. The keyframe gains the toe's value 0 (qpos order:
    crank, coupler, toe, rocker)."""
    text = m.mjcf_fourbar_straight()
    site = '<site name="tool" pos="0.06 0.03 0"/>'
    toe = (
        '<body name="toe" pos="0.06 0.03 0"><joint name="toe_joint" range="-30 30" '
        'stiffness="5"/><site name="tool" pos="0.03 0 0"/></body>'
    )
    assert site in text and "1.059932 -0.390232" in text
    return text.replace(site, toe).replace("1.059932 -0.390232", "1.059932 0 -0.390232")


_TIP = {"measured_frame": "tool", "measured": "position"}


def _mjcf(name: str, text: str, sidecar: dict) -> Callable[[Path], Path]:
    def write(folder: Path) -> Path:
        path = folder / f"{name}.xml"
        path.write_text(text, encoding="utf-8")
        path.with_suffix(".yaml").write_text(yaml.safe_dump(sidecar), encoding="utf-8")
        return path

    return write


def _urdf(name: str, urdf: str, sidecar: dict) -> Callable[[Path], Path]:
    return lambda folder: m.write_machine(folder, name, urdf, sidecar)


def _at(path: Path) -> Callable[[Path], Path]:
    return lambda folder: path


def _roster() -> list[Machine]:
    out = [
        Machine(f"MJCF {n}", "MJCF `connect`/ball cuts", _at(m.MJCF / f"{n}.xml"))
        for n in ("fourbar", "fivebar", "delta")
    ]
    out += [
        Machine(
            "MJCF four-bar leg, `qpos0` at its dead point",
            "singular `qpos0`, `<keyframe>`, spring",
            _mjcf("fourbar_straight", m.mjcf_fourbar_straight(), _TIP),
        ),
        Machine(
            "MJCF four-bar leg with a spring toe, locked",
            "spring joint, sidecar `lock:`",
            _mjcf("toe_locked", mjcf_toe_leg(), {**_TIP, "lock": {"toe_joint": 0}}),
        ),
    ]
    for fn, habits in (
        (m.rssr_emulated_ball, "ball joint as three revolutes"),
        (m.rusr_universal, "`universal` joint"),
        (m.rusr_ujoint, "robot.yaml `UJOINT_ZY`, `FIXED`"),
        (m.delta_4r, "parallelograms closed by `6d` welds"),
    ):
        out.append(Machine(fn.__name__, habits, _urdf(fn.__name__, *fn())))
    urdf, sidecar = m.ankle_2rsu()
    out += [
        Machine(
            "2-RSU ankle", "two loops, emulated ball and U joints", _urdf("ankle", urdf, sidecar)
        ),
        Machine(
            "2-RSU ankle, limits `0 0`",
            "zero-width URDF limits, no workspace",
            _urdf("ankle_zero", *m.ankle_2rsu(zero_limits=True)),
        ),
    ]
    out += [
        Machine(
            "Agile Eye (Gosselin & Hamel 1994)",
            "`robot.urdf` + `robot.yaml`, closures named by joints, orientation only",
            pm.write_agile_eye,
        ),
        Machine(
            "6-RSS Stewart head",
            "MJCF freejoint, `connect site1 site2`, `<default>` classes, keyframe",
            pm.write_stewart,
        ),
        Machine(
            "Clavel delta, IRB 360 dimensions (Williams 2016)",
            "every ball end three revolutes, platform on a rod",
            _urdf("clavel_delta", *pm.clavel_delta()),
        ),
    ]
    for n, habits in (
        ("fivebar", "planar `x y` cut"),
        ("rssr", "crank through its range"),
        ("prs3", "3-PRS"),
        ("rpr3", "planar 3-RPR, rpy"),
        ("rrr3", "planar 3-RRR, measures x y rz"),
    ):
        out.append(Machine(n, habits, _at(MODEL_MACHINES / n)))
    out += [
        Machine(
            "MJCF robot neck, two linear actuators, U-joint head",
            "`zaxis` slide legs, `connect site1 site2`, `<position>` actuators, measures rx ry",
            _mjcf("neck", lm.mjcf_neck(), lm.NECK_SIDECAR),
        ),
        Machine(
            "URDF excavator-style arm, three cylinders, four planar loops",
            "CAD-exporter `<inertial>` everywhere, `[x, z]` cuts, measures x z ry",
            _urdf("excavator", *lm.urdf_excavator()),
        ),
        Machine(
            "MJCF gripper finger, two four-bars",
            '`<compiler angle="degree">`, `euler` palm, joint `<default>` class, `connect`',
            _mjcf("finger", lm.mjcf_finger(), lm.FINGER_SIDECAR),
        ),
    ]
    # refused, with the message a user can act on
    bad = m.mjcf_fourbar_straight(False, crank_range="0 10", coupler_range="20 120")
    out += [
        Machine(
            "MJCF four-bar leg with a spring toe, not locked",
            "spring joint moving the measured site",
            _mjcf("toe_free", mjcf_toe_leg(), _TIP),
            (MobilityError, "'lock: {toe_joint: home}'"),
        ),
        Machine(
            "MJCF four-bar leg, singular `qpos0`, no keyframe, no regular home in range",
            "singular `qpos0`, narrow ranges",
            _mjcf("fourbar_stuck", bad, _TIP),
            (SingularConfigurationError, "Give a regular home"),
        ),
        Machine(
            "2-RSU ankle with one motor declared",
            "motors that do not fix the output",
            _urdf("ankle_one", urdf, {**sidecar, "name_mot": ["mot_l"]}),
            (MobilityError, "not fixed by the 1 actuated joints"),
        ),
        Machine(
            "MJCF gripper finger, distal joint coupled by `polycoef`",
            "`<equality><joint polycoef>`",
            _mjcf("finger_polycoef", lm.mjcf_finger(coupler=False), lm.FINGER_SIDECAR),
            (ModelFileError, "model the linkage that makes the coupling"),
        ),
    ]
    return out


ROSTER: tuple[Machine, ...] = tuple(_roster())
"""Every machine of the roster (models written on demand by ``Machine.write``)."""


@dataclass(frozen=True)
class Recovery:
    """Noise-free recovery of a random error on a preset's identifiable set.

    ``k`` of ``n`` parameters identified; ``parameter_error`` max |found − true| [m or
    rad] over them; ``prediction_error`` max over 5 fresh poses of the measured
    components' difference between the calibrated and the actual model [m or rad];
    ``iterations`` the solver's (Levenberg–Marquardt's evaluations included);
    ``floor`` [m or rad] what Gauss–Newton's stopping rule may leave: it stops once a
    step promises below 1e-24 of the starting cost (a residual 1e12 times smaller), so
    along a direction κ times weaker than the strongest (κ the column-scaled condition
    number of the identifiable set) up to 1e-12·κ of the error's size remains. (Round-off
    in the data can leave more: the finger measured in [x, z] only, ``full``, 1.9e-9
    against 6.0e-10; tests/open_world/test_curved_valley.py.)
    """

    n: int
    k: int
    success: bool
    message: str
    parameter_error: float
    prediction_error: float
    iterations: int = 0
    floor: float = 0.0


def _measured_error(mech: Mechanism, a: pin.SE3, b: pin.SE3) -> float:
    d = np.r_[a.translation - b.translation, pin.log3(a.rotation.T @ b.rotation)]
    idx = ["x", "y", "z", "rx", "ry", "rz"]
    return float(np.max(np.abs(d[[idx.index(c) for c in mech.measured_components]])))


def recover(
    mech: Mechanism,
    preset: str,
    n_poses: int = 30,
    size: float = 2e-4,
    options: GaussNewtonOptions | None = None,
) -> Recovery:
    """Simulate a random error (σ = ``size`` [m, rad]) on the identifiable set of
    ``preset`` (its base parameters at the poses), measure it exactly at ``n_poses``
    random rows the actual machine reaches, and identify from the nominal model (the
    default solver, with ``options`` when given)."""
    params = parameters(mech, preset)
    rows = sample_actuators(mech, n_poses, np.random.default_rng(11))
    ident = identifiability(mech, params, rows)
    truth = np.zeros(len(params))
    base = [params.index(n) for n in ident.base_names]
    truth[base] = np.random.default_rng(1).normal(0, size, len(base))
    actual = params.apply(mech, truth)
    rows = rows[actual.closable_batch(rows)]  # a campaign measures the poses it reaches
    res = identify(mech, params, simulate_measurements(actual, rows), options=options)
    err = float(np.max(np.abs(res.full_values - truth)[res.identified]))
    s = ident.singular_values  # column-scaled, descending
    bound = 1e-12 * float(s[0] / s[ident.rank - 1]) * float(np.max(np.abs(truth)))
    fresh = sample_actuators(mech, 5, np.random.default_rng(12))
    pred = max(_measured_error(mech, actual.forward(r), res.calibrated.forward(r)) for r in fresh)
    k = int(res.identified.sum())
    return Recovery(len(params), k, res.success, res.message, err, pred, res.iterations, bound)


def row(machine: Machine, folder: Path) -> str:
    """The machine's line of the README table (loads and calibrates, or refused)."""
    head = f"| {machine.name} | {machine.habits} |"
    try:
        mech = load_mechanism(machine.write(folder))
    except PincalError as exc:
        return f"{head} refused: `{type(exc).__name__}`: {exc} | | |"
    cells = []
    for preset in ("base", "full"):
        r = recover(mech, preset)
        ok = "✓" if r.success else "✗"
        cells.append(f"{ok} {r.k}/{r.n}, {r.parameter_error:.0e} / {r.prediction_error:.0e}")
    return f"{head} loads, calibrates | {cells[0]} | {cells[1]} |"


def table(folder: Path) -> list[str]:
    """The README's open-world table, one line per roster machine (written in ``folder``)."""
    return [
        "| machine | written with | result | `base`: fitted/params, max error "
        "parameters / predictions [m, rad] | `full`: same |",
        "|---|---|---|---|---|",
        *(row(mc, folder) for mc in ROSTER),
    ]

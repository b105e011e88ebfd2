"""Recovery of joint compliance, gain, harmonic and thermal terms at the Cramér–Rao bound.

A UR5 (example-robot-data, by name) — or, with ``--machine stewart``, the 6-UPS
Stewart platform of ``models/stewart_6ups`` carrying a 20 kg payload (centre of mass
(50, −20, 100) mm in the tool frame; its legs' axial compliance under the static load
from the loop-closure equilibrium) — measured in full pose (noise 0.01 mm / 0.01 mrad
per component, declared) at N random poses; its parameters are the geometric ``base``
(arm) or ``stewart42`` (Stewart) preset plus, on every actuated joint, the error-model
terms asked for (``--terms``, default ``compliance,gain,harmonics`` on the arm,
``compliance`` on the Stewart platform). Per draw: fresh poses, a fresh
true error on the identifiable set (geometric ~ N(0, 0.2 mm / 0.2 mrad), joint terms
~ N(0, their default prior σ)), fresh noise; the machine is simulated with the
joint terms moving its joints (``pincal.model.actual_joint_values``) and identified
by Gauss–Newton from nominal. Recorded: the Mahalanobis error
``(x̂ − x)ᵀ Σ⁻¹ (x̂ − x) / n`` of the identified parameters (Σ the covariance the
result reports): ≈ 1 when the estimate is efficient and its covariance honest
(χ²_n / n for a known σ), and the same restricted to the joint terms
(``Σ_jt`` the sub-block).

With the ``temperature`` term (thermal expansion: the arm's link lengths, the Stewart
platform's leg strokes; truth ~ N(0, 2e-5 /K)) each pose also gets a temperature drawn
uniformly in ``--span`` (default 18–28 °C), and the identifiable set is found at those
temperatures.

With ``--machine hexaslide``: the 6-PUS hexaslide of ``models/hexaslide_6pus`` with
the same 20 kg payload, its ``pus54`` preset plus the axial compliance of its six
fixed-length struts (``strut-compliance``: ``δL_j = c_j·F_j``, the strut forces from the
loop-closure equilibrium, true ``c ~ N(0, 1e-7 m/N)``, the default prior). The machine
is simulated with the physical model — each pose measured on the true geometry with every
strut lengthened by its ``c_j·F_j``. ``F`` is the nominal machine's at the command (as the
Stewart study's leg forces are); ``--true-forces`` takes the true (geometrically
erroneous) machine's at the command instead. Neither is the lengthened machine's own,
which the identification solves for (:mod:`pincal.model.params._term_strut`); the exact
truth is scripts/studies/hexaslide_deflection.py's.

    PYTHONPATH=. python scripts/studies/nongeometric_recovery.py [--draws 100] [--poses 60]
    PYTHONPATH=. python scripts/studies/nongeometric_recovery.py --machine stewart
    PYTHONPATH=. python scripts/studies/nongeometric_recovery.py --terms temperature
    PYTHONPATH=. python scripts/studies/nongeometric_recovery.py --machine hexaslide
    PYTHONPATH=. python scripts/studies/nongeometric_recovery.py --machine hexaslide --true-forces
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pincal.identification import identify
from pincal.measure import NoiseModel, simulate_measurements
from pincal.model import (
    Mechanism,
    ParameterSet,
    Payload,
    actual_joint_values,
    actual_shift,
    joint_term_prior,
    load_mechanism,
    sample_actuators,
    strut_loads,
    with_joint_terms,
    with_payload,
)
from pincal.sensitivity import identifiability, parameters

NOISE = NoiseModel(position=0.01, orientation=0.01)  # [mm], [mrad]
GEOMETRIC_SIGMA = 2e-4  # [m] or [rad]
STEWART = Path(__file__).parents[2] / "models" / "stewart_6ups"
HEXASLIDE = Path(__file__).parents[2] / "models" / "hexaslide_6pus"
SPINDLE = Payload(20.0, (0.05, -0.02, 0.10))  # [kg], [m] in the tool frame
SPAN = (18.0, 28.0)  # [°C] temperatures of the poses with a thermal term


@dataclass(frozen=True)
class Draw:
    """One simulated calibration: Mahalanobis errors / n (all, joint terms) and sizes."""

    maha: float
    maha_terms: float
    n: int
    n_terms: int


def setup(terms: tuple[str, ...], robot: str = "ur5") -> tuple[Mechanism, ParameterSet]:
    """The machine and its parameters: an arm by name, or ``"stewart"`` with its payload."""
    if robot == "stewart":
        mech = with_payload(load_mechanism(STEWART), SPINDLE)
        return mech, with_joint_terms(mech, parameters(mech, "stewart42"), terms)
    if robot == "hexaslide":
        mech = with_payload(load_mechanism(HEXASLIDE), SPINDLE)
        return mech, with_joint_terms(mech, parameters(mech, "pus54"), terms)
    mech = load_mechanism(robot)
    return mech, with_joint_terms(mech, parameters(mech, "base"), terms)


def draw(
    mech: Mechanism,
    params: ParameterSet,
    n_poses: int,
    rng: np.random.Generator,
    span: tuple[float, float] = SPAN,
    true_forces: bool = False,
) -> Draw:
    """One seeded calibration of a simulated machine with geometric and joint errors."""
    rows = sample_actuators(mech, n_poses, rng)
    cond = None
    if "1/K" in params.units:  # a thermal term: one temperature per pose
        cond = {"temperature": rng.uniform(*span, n_poses)}
    base = np.asarray(identifiability(mech, params, rows, conditions=cond).base)
    sigma = np.where(np.isnan(joint_term_prior(params)), GEOMETRIC_SIGMA, joint_term_prior(params))
    truth = np.zeros(len(params))
    truth[base] = rng.normal(0.0, sigma[base])
    actual = params.apply(mech, truth)
    joints = _true_joints(mech, params, truth, rows, cond, true_forces)
    meas = simulate_measurements(actual, joints, NOISE, rng)
    meas = dataclasses.replace(meas, q_act=rows.copy())
    if cond is not None:
        shift = actual_shift(mech, params, truth, rows, cond)
        meas = dataclasses.replace(
            meas, positions=meas.positions + shift, temperature=cond["temperature"]
        )
    res = identify(mech, params, meas, "gauss-newton")
    e = res.values - truth[res.identified]
    jt = np.isin(np.flatnonzero(res.identified), params.joint_terms)
    e_t, C_t = e[jt], res.covariance[np.ix_(jt, jt)]
    return Draw(
        float(e @ np.linalg.solve(res.covariance, e)) / e.size,
        float(e_t @ np.linalg.solve(C_t, e_t)) / max(e_t.size, 1),
        int(e.size),
        int(e_t.size),
    )


def _true_joints(
    mech: Mechanism,
    params: ParameterSet,
    truth: np.ndarray,
    rows: np.ndarray,
    cond: dict[str, np.ndarray] | None = None,
    true_forces: bool = False,
) -> np.ndarray:
    """The joint values at which the rigid true geometry is where the true machine is.

    Joint terms on actuated joints: ``q + B θ``. Struts: each pose measured on the true
    geometry with its struts lengthened by ``c·F`` (``F`` of the nominal machine, or of
    the true one with ``true_forces``), then the joint values that bring the rigid true
    geometry there (inverse kinematics).
    """
    k = [i for i in params.joint_terms if params.parameters[i].dof == "strut_compliance"]
    if not k:
        return actual_joint_values(mech, params, truth, rows, cond)
    on_joints = np.setdiff1d(np.arange(len(params)), k)
    rest = np.where(np.isin(np.arange(len(params)), on_joints), truth, 0.0)
    joints = actual_joint_values(mech, params, rest, rows, cond)
    actual = params.apply(mech, truth)
    names = tuple(params.parameters[i].joint for i in k)
    lengths = parameters(actual, [f"{j}.tz" for j in names])  # the hexaslide's struts lie on z
    forces, _ = strut_loads(actual if true_forces else mech, joints, names)
    out = np.empty_like(joints)
    for i, (q, f) in enumerate(zip(joints, forces, strict=True)):
        pose = lengths.apply(actual, truth[k] * f).forward(q)
        out[i] = actual.inverse(pose, actual.configurations(q[None])[0], check_limits=False)
    return out


def study(
    draws: int,
    n_poses: int,
    seed: int,
    terms: tuple[str, ...],
    robot: str = "ur5",
    span: tuple[float, float] = SPAN,
    true_forces: bool = False,
) -> list[Draw]:
    mech, params = setup(terms, robot)
    rng = np.random.default_rng(seed)
    return [draw(mech, params, n_poses, rng, span, true_forces) for _ in range(draws)]


def mean_se(values: list[float]) -> tuple[float, float]:
    v = np.asarray(values, dtype=float)
    return float(v.mean()), float(v.std(ddof=1) / np.sqrt(v.size))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--draws", type=int, default=100, help="independent seeded draws")
    ap.add_argument("--poses", type=int, default=60, help="poses per calibration")
    ap.add_argument("--seed", type=int, default=1, help="seed of poses, errors and noise")
    ap.add_argument("--robot", default="ur5", help="a serial arm by name (default ur5)")
    ap.add_argument(
        "--machine", choices=("arm", "stewart", "hexaslide"), default="arm",
        help="arm (--robot), or the Stewart platform or hexaslide with a 20 kg payload",
    )  # fmt: skip
    ap.add_argument("--terms", default=None, help="comma list (default: see above)")
    ap.add_argument("--span", default="18,28", help="temperatures of the poses [°C] LOW,HIGH")
    ap.add_argument(
        "--true-forces", action="store_true",
        help="struts lengthened under the true machine's forces (default: the nominal's)",
    )  # fmt: skip
    args = ap.parse_args()
    lo, hi = (float(v) for v in args.span.split(","))
    robot = args.robot if args.machine == "arm" else args.machine
    default = {"stewart": "compliance", "hexaslide": "strut-compliance"}.get(
        robot, "compliance,gain,harmonics"
    )
    terms = tuple(t for t in (args.terms or default).split(",") if t)
    t0 = time.perf_counter()
    out = study(args.draws, args.poses, args.seed, terms, robot, (lo, hi), args.true_forces)
    seconds = time.perf_counter() - t0
    m, s = mean_se([d.maha for d in out])
    mt, st = mean_se([d.maha_terms for d in out])
    print(f"{len(out)} draws, {robot}, {args.poses} full poses, noise 0.01 mm / 0.01 mrad, "
          f"terms {'+'.join(terms)}{', true forces' if args.true_forces else ''} "
          f"({seconds:.0f} s)"
          + (f", temperatures {lo:g}–{hi:g} °C" if "temperature" in terms else ""))  # fmt: skip
    print(f"identified parameters: {out[0].n} ({out[0].n_terms} joint terms)")
    print(f"Mahalanobis error / n, all identified   mean {m:.4f} ± {s:.4f} (s.e.)")
    print(f"Mahalanobis error / n, joint terms only mean {mt:.4f} ± {st:.4f} (s.e.)")


if __name__ == "__main__":
    main()

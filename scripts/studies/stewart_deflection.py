"""Leg compliance of a Stewart platform against an independent statics: recovery by sag.

The truth is not pincal's compliance term. The study's own statics of the 6-UPS
platform of ``models/stewart_6ups`` (20 kg payload at (50, −20, 100) mm in the tool
frame, the 2 kg platform, 0.1 kg rods whose centres are the spherical joints — masses
read from the URDF): the true geometry (anchors of the legs on the base and on the
platform, the legs' zero offsets) is read once per draw from the true rigid machine;
then, per pose,

* forward kinematics: the platform pose (t, R) whose leg lengths ``|t + R p_i − b_i|``
  are the given ones (Newton on the six lengths);
* statics by virtual work: the leg forces τ with ``J_Lᵀ τ = ∇V``, ``V`` the potential
  energy of the masses, ``J_L`` the legs' rates per platform twist — τ_i the force
  the leg holds (> 0 compressed by the weight), as the model's sign convention;
* deflection: the fixed point ``L = L_cmd + c·τ(L)`` of the legs' lengths under the
  forces of the true machine at its deflected pose (``c = −1/k`` per leg).

The measured pose is that deflected platform pose with noise 0.01 mm / 0.01 mrad
(declared). Per draw: 60 random poses, geometric errors ~ N(0, 0.2 mm) on the
``stewart42`` set, compliances ``c_i = −s/τ_rms · U(0.5, 1.5)`` for a sag ``s`` (τ_rms the
nominal RMS leg force at home), identified by Gauss–Newton from nominal with
``stewart42+compliance``. Recorded: the Mahalanobis error ``(x̂ − x)ᵀ Σ⁻¹ (x̂ − x) / n``
over the 48 parameters (≈ 1 when the model matches the physics), and over the 6
compliances alone.

With ``--cells`` the sag of each draw is drawn log-uniformly in a range per cell (e.g.
``stiff:0.01:0.15,soft:0.2:2`` [mm]) and each draw also compensates 10 random targets:
the commands of ``pincal.compensation.compensate`` with the calibration's joint terms
(and, for comparison, of a geometric-only calibration on the same data) are played on
the independent statics, and the RMS position miss [µm] of the deflected platform is
recorded. ``--out FILE`` appends one JSON line per draw (partial runs keep their draws).

    PYTHONPATH=. python scripts/studies/stewart_deflection.py --draws 40
    PYTHONPATH=. python scripts/studies/stewart_deflection.py --sags 0.01,0.1 --draws 10
    PYTHONPATH=. python scripts/studies/stewart_deflection.py \
        --cells stiff:0.01:0.15,soft:0.2:2 --draws 20

Running it with another pincal on ``PYTHONPATH`` (e.g. one extracted with
``git archive``) measures that version against the same truths.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin

from pincal.compensation import JointTermCorrection, compensate
from pincal.identification import identify
from pincal.measure import NoiseModel, simulate_measurements
from pincal.model import Payload, load_mechanism, sample_actuators, with_joint_terms, with_payload
from pincal.sensitivity import parameters

STEWART = Path(__file__).parents[2] / "models" / "stewart_6ups"
PAYLOAD = (20.0, np.array([0.05, -0.02, 0.10]))  # [kg], [m] in the platform (tool) frame
NOISE = NoiseModel(position=0.01, orientation=0.01)  # [mm], [mrad]
GEOMETRIC_SIGMA = 2e-4  # [m]
G = 9.81  # [m/s²] along −z of the base
LEGS = range(1, 7)


def masses() -> tuple[float, float]:
    """(platform mass, one rod's mass) [kg] from the URDF's <inertial> (origins at 0)."""
    root = ET.parse(STEWART / "stewart_6ups.urdf").getroot()
    mass = {
        link.get("name"): float(link.find("inertial/mass").get("value"))  # type: ignore[union-attr]
        for link in root.iter("link")
        if link.find("inertial") is not None
    }
    return mass["platform"], mass["leg1_rod"]


@dataclasses.dataclass(frozen=True)
class Platform:
    """The true rigid geometry: base anchors b (6, 3), platform anchors p (6, 3) [m],
    leg offsets (6,) [m] (length = joint value + offset)."""

    b: np.ndarray
    p: np.ndarray
    offset: np.ndarray

    @classmethod
    def of(cls, mech) -> Platform:
        """Read from a pincal mechanism's frames at its home configuration."""
        model, data = mech.model, mech.model.createData()
        q = mech.configurations(mech.actuators_of(mech.q_home)[None])[0]
        pin.framesForwardKinematics(model, data, q)
        world = {f.name: data.oMf[i] for i, f in enumerate(model.frames)}
        T = world["platform"]
        b = np.array([world[f"leg{i}_u1"].translation for i in LEGS])
        s = np.array([world[f"platform_p{i}"].translation for i in LEGS])
        p = (s - T.translation) @ T.rotation
        q_act = mech.actuators_of(q)
        return cls(b, p, np.linalg.norm(s - b, axis=1) - q_act)

    def lengths(self, t: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Leg lengths (6,) [m] and their rates per platform twist (6, 6) [(δt, δφ)]."""
        r = self.p @ R.T
        d = t + r - self.b
        L = np.linalg.norm(d, axis=1)
        u = d / L[:, None]
        return L, np.hstack([u, np.cross(r, u)])

    def pose(self, L: np.ndarray, t: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Forward kinematics: the pose with leg lengths L, Newton from (t, R)."""
        for _ in range(50):
            Lk, J = self.lengths(t, R)
            xi = np.linalg.solve(J, L - Lk)
            t, R = t + xi[:3], pin.exp3(xi[3:]) @ R
            if np.max(np.abs(xi)) < 1e-15:
                break
        return t, R

    def forces(self, t: np.ndarray, R: np.ndarray, m_plat: float, m_rod: float) -> np.ndarray:
        """Leg forces (6,) [N] by virtual work, ``J_Lᵀ τ = ∇V``."""
        ez = np.array([0.0, 0.0, 1.0])
        points = [(m_plat, np.zeros(3)), (PAYLOAD[0], R @ PAYLOAD[1])]
        points += [(m_rod, R @ p) for p in self.p]
        grad = sum(G * m * np.concatenate([ez, np.cross(r, ez)]) for m, r in points)
        _, J = self.lengths(t, R)
        return np.linalg.solve(J.T, grad)

    def deflected(self, L_cmd, c, t, R, m_plat, m_rod):
        """The pose of the fixed point ``L = L_cmd + c·τ(L)`` and its forces."""
        L = L_cmd.copy()
        for _ in range(100):
            t, R = self.pose(L, t, R)
            tau = self.forces(t, R, m_plat, m_rod)
            new = L_cmd + c * tau
            if np.max(np.abs(new - L)) < 1e-14:
                break
            L = new
        return self.pose(new, t, R), tau


def draw(
    mech,
    params,
    sag: float,
    rng: np.random.Generator,
    n_poses: int,
    tau_rms: float,
    targets: int = 0,
) -> dict:
    """One calibration against the independent statics.

    Returns ``{"maha": Mahalanobis/n over all, "maha_c": over the compliances}`` and, with
    ``targets``, the RMS position misses [µm] of compensated commands: ``"comp"`` with the
    compliance calibration, ``"geom"`` with a geometric-only one, ``"none"`` the nominal
    machine's inverse kinematics.
    """
    m_plat, m_rod = masses()
    rows = sample_actuators(mech, n_poses, rng)
    truth = np.zeros(len(params))
    truth[:42] = rng.normal(0.0, GEOMETRIC_SIGMA, 42)
    truth[42:] = -sag / tau_rms * rng.uniform(0.5, 1.5, 6)
    plat = Platform.of(params.apply(mech, truth))

    def play(commands: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Deflected platform positions (m, 3) and rotations of the true machine [m]."""
        pos, rot = np.empty((len(commands), 3)), np.empty((len(commands), 3, 3))
        t, R = np.array([0.0, 0.0, 0.45]), np.eye(3)
        for i, q in enumerate(commands):
            (t, R), _ = plat.deflected(q + plat.offset, truth[42:], t, R, m_plat, m_rod)
            pos[i], rot[i] = t, R
        return pos, rot

    meas = simulate_measurements(mech, rows, NOISE, rng)  # layout; poses replaced below
    pos, rot = play(rows)
    pos = pos + rng.normal(0.0, 1e-5, pos.shape)
    rot = np.array([R @ pin.exp3(rng.normal(0.0, 1e-5, 3)) for R in rot])
    meas = dataclasses.replace(meas, positions=pos, rotations=rot, q_act=rows.copy())
    res = identify(mech, params, meas, "gauss-newton")
    e = res.values - truth[res.identified]
    out = {"sag_mm": sag * 1e3, "maha": float(e @ np.linalg.solve(res.covariance, e)) / e.size}
    c = np.isin(np.flatnonzero(res.identified), params.joint_terms)
    e_c = e[c]
    out["maha_c"] = float(e_c @ np.linalg.solve(res.covariance[np.ix_(c, c)], e_c)) / e_c.size
    if targets:
        goal = [mech.forward(q) for q in sample_actuators(mech, targets, rng)]
        want = np.array([T.translation for T in goal])
        terms = JointTermCorrection.of(mech, res.parameter_set, res.full_values)
        geo = identify(mech, parameters(mech, "stewart42"), meas, "gauss-newton")
        for key, cal, jt in (("comp", res.calibrated, terms), ("geom", geo.calibrated, None),
                             ("none", mech, None)):  # fmt: skip
            sol = compensate(cal, goal, check_limits=False, joint_terms=jt)
            ok = sol.reachable
            miss = play(sol.q_act[ok])[0] - want[ok]
            out[key] = float(np.sqrt(np.mean(np.sum(miss**2, axis=1)))) * 1e6
    return out


def nominal_force_rms(mech) -> float:
    """RMS leg force [N] of the nominal machine at home (the study's statics)."""
    plat = Platform.of(mech)
    L, _ = plat.lengths(np.array([0.0, 0.0, 0.45]), np.eye(3))
    t, R = plat.pose(L, np.array([0.0, 0.0, 0.45]), np.eye(3))
    return float(np.sqrt(np.mean(plat.forces(t, R, *masses()) ** 2)))


def _mean_se(v) -> str:
    v = np.asarray(v, dtype=float)
    se = v.std(ddof=1) / np.sqrt(v.size) if v.size > 1 else float("nan")
    return f"{v.mean():.3f} ± {se:.3f}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--draws", type=int, default=40, help="independent draws per sag")
    ap.add_argument("--poses", type=int, default=60)
    ap.add_argument("--sags", default="0.01,0.1,0.5,2", help="leg sags s [mm], comma list")
    ap.add_argument("--cells", default=None,
                    help="NAME:LOW:HIGH,... sag ranges [mm] (log-uniform per draw), with "
                         "compensation; replaces --sags")  # fmt: skip
    ap.add_argument("--targets", type=int, default=10, help="compensated targets (--cells)")
    ap.add_argument("--out", default=None, help="append one JSON line per draw")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--only", default=None,
                    help="NAME,... run only these cells, each with the draws it has in the "
                         "full list (to run the cells in parallel processes)")  # fmt: skip
    args = ap.parse_args()
    mech = with_payload(load_mechanism(STEWART), Payload(PAYLOAD[0], tuple(PAYLOAD[1])))
    params = with_joint_terms(mech, parameters(mech, "stewart42"), ("compliance",))
    tau_rms = nominal_force_rms(mech)
    print(f"nominal RMS leg force at home {tau_rms:.2f} N; {args.poses} full poses, "
          f"noise 0.01 mm / 0.01 mrad, {args.draws} draws per cell")  # fmt: skip
    if args.cells:
        cells = [(n, float(lo), float(hi)) for n, lo, hi in
                 (c.split(":") for c in args.cells.split(","))]  # fmt: skip
    else:
        cells = [(s, float(s), float(s)) for s in args.sags.split(",")]
    n_targets = args.targets if args.cells else 0
    print("cell (sag [mm])   Mahalanobis/n all | compliances   "
          + ("| RMS miss [µm] compliance cal | geometric cal | nominal   " if n_targets else "")
          + "(draws, seconds)")  # fmt: skip
    only = None if args.only is None else set(args.only.split(","))
    for k, (name, lo, hi) in enumerate(cells):
        if only is not None and name not in only:
            continue
        rng = np.random.default_rng([args.seed, k])
        t0 = time.perf_counter()
        rows = []
        for _ in range(args.draws):
            sag = float(np.exp(rng.uniform(np.log(lo), np.log(hi))))
            row = draw(mech, params, 1e-3 * sag, rng, args.poses, tau_rms, n_targets)
            rows.append(row)
            if args.out:
                with open(args.out, "a") as f:
                    f.write(json.dumps({"cell": name, **row}) + "\n")
        line = f"{name} ({lo:g}–{hi:g})   {_mean_se([r['maha'] for r in rows])} | "
        line += _mean_se([r["maha_c"] for r in rows])
        if n_targets:
            line += "   | " + " | ".join(
                _mean_se([r[k] for r in rows]) for k in ("comp", "geom", "none")
            )
        print(f"{line}   ({len(rows)}, {time.perf_counter() - t0:.0f} s)", flush=True)


if __name__ == "__main__":
    main()

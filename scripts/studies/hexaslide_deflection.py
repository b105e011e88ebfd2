"""Strut compliance of the hexaslide against an independent statics: recovery by sag.

The truth is not pincal's strut-compliance term. The study's own statics of the 6-PUS
hexaslide of ``models/hexaslide_6pus`` (20 kg payload at (50, −20, 100) mm in the tool
frame, the 0.1 kg platform; the struts' and carriages' masses sit at the universal
joints' centres in the URDF, which the held actuators fix, so they do no work): the true
geometry is read once per draw from the true rigid machine — each rail's origin ``a_i``
and direction ``d_i`` (the carriage's universal-joint centre is ``a_i + q_i d_i``), the
strut lengths ``ℓ_i``, the platform's ball centres ``p_i`` (platform frame) — then, per pose,

* forward kinematics: the platform pose (t, R) whose strut lengths
  ``|t + R p_i − a_i − q_i d_i|`` are ``ℓ_i + δ_i`` (Newton);
* statics by virtual work: the strut forces ``F`` with ``J_Lᵀ F = ∇V`` (``J_L`` the
  struts' length rates per platform twist, carriages held): ``F_i = ∂V/∂ℓ_i``, > 0
  compressed by the weight, as the model's sign convention;
* deflection: the fixed point ``δ = c·F(ℓ + δ)`` of the struts' elongations under the
  forces of the true machine at its deflected pose (``c = −1/k`` per strut).

The measured pose is that deflected platform pose with noise 0.01 mm / 0.01 mrad
(declared). Per draw: 60 random poses, geometric errors ~ N(0, 0.2 mm / 0.2 mrad) on the
identifiable part of ``pus54``, strut compliances ``c_i = −s/F_rms · U(0.5, 1.5)`` for a
sag ``s`` drawn log-uniformly in the cell (``F_rms`` the nominal RMS strut force at home),
identified by Gauss–Newton from nominal with ``pus54+strut-compliance``. Recorded per
draw: the Mahalanobis error over all identified parameters and over the compliances,
and the RMS position miss [µm] at 10 random targets of ``compensate``'s commands played
on the independent statics (compliance calibration, geometric-only, nominal).

    PYTHONPATH=. python scripts/studies/hexaslide_deflection.py \\
        --cells stiff:0.01:0.15,soft:0.2:2 --draws 40
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
from pincal.sensitivity import identifiability, parameters

HEXASLIDE = Path(__file__).parents[2] / "models" / "hexaslide_6pus"
PAYLOAD = Payload(20.0, (0.05, -0.02, 0.10))  # [kg], [m] in the platform (tool) frame
NOISE = NoiseModel(position=0.01, orientation=0.01)  # [mm], [mrad]
GEOMETRIC_SIGMA = 2e-4  # [m] or [rad]
G = 9.81  # [m/s²] along −z
LEGS = range(1, 7)
HOME = (np.array([0.0, 0.0, 0.46]), np.eye(3))


def platform_mass() -> float:
    """The platform's mass [kg] from the URDF's <inertial> (origin at the platform's)."""
    root = ET.parse(HEXASLIDE / "hexaslide_6pus.urdf").getroot()
    link = next(k for k in root.iter("link") if k.get("name") == "platform")
    return float(link.find("inertial/mass").get("value"))  # type: ignore[union-attr]


@dataclasses.dataclass(frozen=True)
class Hexaslide:
    """True rigid geometry: rail origins a, directions d (6, 3), strut lengths ℓ (6,),
    platform ball centres p (6, 3) in the platform frame [m], platform mass [kg]."""

    a: np.ndarray
    d: np.ndarray
    ell: np.ndarray
    p: np.ndarray
    m_plat: float

    @classmethod
    def of(cls, mech) -> Hexaslide:
        """Read from a pincal mechanism's frames (two carriage positions per rail)."""
        model, data = mech.model, mech.model.createData()
        q = mech.configurations(mech.actuators_of(mech.q_home)[None])[0]

        def world(qq):
            pin.framesForwardKinematics(model, data, qq)
            return {f.name: data.oMf[i].copy() for i, f in enumerate(model.frames)}

        w0 = world(q)
        a, d, ell, s = [], [], [], []
        for i in LEGS:
            j = model.getJointId(f"leg{i}_slide")
            qq = q.copy()
            qq[model.joints[j].idx_q] += 0.1
            c0, c1 = w0[f"leg{i}_u1"].translation, world(qq)[f"leg{i}_u1"].translation
            d.append((c1 - c0) / 0.1)
            a.append(c0 - q[model.joints[j].idx_q] * d[-1])
            ell.append(np.linalg.norm(w0[f"leg{i}_tip"].translation - c0))
            s.append(w0[f"platform_p{i}"].translation)
        T = w0["platform"]
        p = (np.array(s) - T.translation) @ T.rotation
        return cls(np.array(a), np.array(d), np.array(ell), p, platform_mass())

    def lengths(self, q, t, R) -> tuple[np.ndarray, np.ndarray]:
        """Strut lengths (6,) [m] at carriages q and platform (t, R); rates per twist (6, 6)."""
        r = self.p @ R.T
        v = t + r - self.a - q[:, None] * self.d
        L = np.linalg.norm(v, axis=1)
        u = v / L[:, None]
        return L, np.hstack([u, np.cross(r, u)])

    def pose(self, q, ell, t, R):
        """Forward kinematics: the platform pose with strut lengths ``ell``, from (t, R)."""
        for _ in range(50):
            L, J = self.lengths(q, t, R)
            xi = np.linalg.solve(J, ell - L)
            t, R = t + xi[:3], pin.exp3(xi[3:]) @ R
            if np.max(np.abs(xi)) < 1e-15:
                break
        return t, R

    def forces(self, q, t, R) -> np.ndarray:
        """Strut forces (6,) [N] by virtual work, ``J_Lᵀ F = ∇V`` (platform + payload)."""
        ez = np.array([0.0, 0.0, 1.0])
        points = [(self.m_plat, np.zeros(3)), (PAYLOAD.mass, R @ np.asarray(PAYLOAD.com))]
        grad = sum(G * m * np.concatenate([ez, np.cross(r, ez)]) for m, r in points)
        return np.linalg.solve(self.lengths(q, t, R)[1].T, grad)

    def deflected(self, q, c, t, R):
        """The pose of the fixed point ``ℓ' = ℓ + c·F(ℓ')`` at carriages ``q``."""
        ell = self.ell.copy()
        for _ in range(100):
            t, R = self.pose(q, ell, t, R)
            new = self.ell + c * self.forces(q, t, R)
            if np.max(np.abs(new - ell)) < 1e-14:
                break
            ell = new
        return self.pose(q, new, t, R)


def draw(mech, params, comp, sag, rng, n_poses, f_rms, targets) -> dict:
    """One calibration against the independent statics (see the module docstring)."""
    rows = sample_actuators(mech, n_poses, rng)
    base = np.asarray(identifiability(mech, params, rows).base)
    truth = np.zeros(len(params))
    geo = np.setdiff1d(base, comp)
    truth[geo] = rng.normal(0.0, GEOMETRIC_SIGMA, geo.size)
    truth[comp] = -sag / f_rms * rng.uniform(0.5, 1.5, comp.size)
    hexa = Hexaslide.of(params.apply(mech, truth))

    def play(commands):
        pos, rot = np.empty((len(commands), 3)), np.empty((len(commands), 3, 3))
        t, R = HOME
        for i, q in enumerate(commands):
            t, R = hexa.deflected(q, truth[comp], t, R)
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
    k = np.isin(np.flatnonzero(res.identified), comp)
    e_c = e[k]
    out["maha_c"] = float(e_c @ np.linalg.solve(res.covariance[np.ix_(k, k)], e_c)) / e_c.size
    starts = sample_actuators(mech, targets, rng)
    goal = [mech.forward(u) for u in starts]
    want = np.array([T.translation for T in goal])
    terms = JointTermCorrection.of(mech, res.parameter_set, res.full_values)
    g_fit = identify(mech, parameters(mech, "pus54"), meas, "gauss-newton")
    for key, cal, jt in (
        ("comp", res.calibrated, terms),
        ("geom", g_fit.calibrated, None),
        ("none", mech, None),
    ):
        sol = compensate(cal, goal, check_limits=False, joint_terms=jt, starts=starts)
        ok = sol.reachable
        miss = play(sol.q_act[ok])[0] - want[ok]
        out[key] = float(np.sqrt(np.mean(np.sum(miss**2, axis=1)))) * 1e6
        out[f"{key}_reached"] = int(ok.sum())
    return out


def _mean_se(v) -> str:
    v = np.asarray(v, dtype=float)
    se = v.std(ddof=1) / np.sqrt(v.size) if v.size > 1 else float("nan")
    return f"{v.mean():.3f} ± {se:.3f}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--draws", type=int, default=40, help="independent draws per cell")
    ap.add_argument("--poses", type=int, default=60)
    ap.add_argument("--cells", default="stiff:0.01:0.15,soft:0.2:2",
                    help="NAME:LOW:HIGH,... sag ranges [mm], log-uniform per draw")  # fmt: skip
    ap.add_argument("--targets", type=int, default=10, help="compensated targets per draw")
    ap.add_argument("--out", default=None, help="append one JSON line per draw")
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    mech = with_payload(load_mechanism(HEXASLIDE), PAYLOAD)
    params = with_joint_terms(mech, parameters(mech, "pus54"), ("strut-compliance",))
    comp = np.asarray(params.joint_terms)
    hexa = Hexaslide.of(mech)
    q0 = mech.actuators_of(mech.q_home)
    t, R = hexa.pose(q0, hexa.ell, *HOME)
    f_rms = float(np.sqrt(np.mean(hexa.forces(q0, t, R) ** 2)))
    print(f"hexaslide + {PAYLOAD.mass:g} kg; nominal RMS strut force at home {f_rms:.2f} N; "
          f"{args.poses} poses, noise 0.01 mm / 0.01 mrad, {args.draws} draws/cell")  # fmt: skip
    print("cell (sag [mm])   Mahalanobis/n all | compliances | RMS miss [µm] compliance cal "
          "| geometric cal | nominal   (draws, seconds)")  # fmt: skip
    for n, cell in enumerate(args.cells.split(",")):
        name, lo, hi = cell.split(":")
        rng = np.random.default_rng([args.seed, n])
        t0 = time.perf_counter()
        out = []
        for _ in range(args.draws):
            sag = float(np.exp(rng.uniform(np.log(float(lo)), np.log(float(hi)))))
            row = draw(mech, params, comp, 1e-3 * sag, rng, args.poses, f_rms, args.targets)
            out.append(row)
            if args.out:
                with open(args.out, "a") as f:
                    f.write(json.dumps({"cell": name, **row}) + "\n")
        cols = ("maha", "maha_c", "comp", "geom", "none")
        print(f"{name} ({lo}–{hi})   " + " | ".join(_mean_se([r[k] for r in out]) for k in cols)
              + f"   ({len(out)}, {time.perf_counter() - t0:.0f} s)", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()

"""Batched vs pose-by-pose kinematics + identification Jacobian on machines written by others.

Run: python scripts/bench_open_world.py [--poses 500] [--repeats 5]

The machines are the test suite's open-world models (tests/open_world/machines.py,
tests/model/mjcf/*.xml, tests/model/machines/*): MJCF files (one with a singular
``qpos0`` and a keyframe), emulated ball joints, universal joints (pincal's and the
robot.yaml ``UJOINT_ZY``), a two-loop 2-RSU ankle, ``6d`` parallelogram cuts, idle
passive spins, planar loops with redundant rows. For each, ``--poses`` random
workspace rows are closed and differentiated (``base`` preset) two ways, timed in
turns (repeat by repeat, after an untimed warm-up call):

* pose by pose: ``mech.configuration(row)`` then ``pose_sensitivity`` per row (the
  path every non-square or universal-joint machine took before they were batched);
* batched: ``mech.configurations_batch(rows)`` then ``sensitivities_batch``.

Times are CPU time per pose (``time.process_time``), median of ``--repeats``, one BLAS
thread (threadpoolctl). "in batch" is the share of rows the batched Newton closes
from home; the others are redone pose by pose inside ``configurations_batch``
(continuation onto the home branch).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # the test suite's machine writers

import pincal  # noqa: E402
from pincal.sensitivity import pose_sensitivity  # noqa: E402
from pincal.sensitivity.batch import sensitivities_batch  # noqa: E402
from tests.open_world import machines  # noqa: E402
from tests.open_world.roster import ROSTER  # noqa: E402


def _machines(folder: Path) -> dict[str, Path]:
    out = {f"mjcf {n}": machines.MJCF / f"{n}.xml" for n in ("fourbar", "fivebar", "delta")}
    for fn in (
        machines.rssr_emulated_ball,
        machines.rusr_universal,
        machines.rusr_ujoint,
        machines.delta_4r,
        machines.ankle_2rsu,
    ):
        urdf, sidecar = fn()
        out[fn.__name__] = machines.write_machine(folder, fn.__name__, urdf, sidecar)
    straight = folder / "fourbar_straight.xml"  # singular qpos0, keyframe home
    straight.write_text(machines.mjcf_fourbar_straight(), encoding="utf-8")
    straight.with_suffix(".yaml").write_text(
        "measured_frame: tool\nmeasured: position\n", encoding="utf-8"
    )
    out["mjcf fourbar_straight"] = straight
    for n in ("fivebar", "rssr", "prs3", "rpr3"):
        out[n] = ROOT / "tests" / "model" / "machines" / n
    later = {  # roster machines (tests/open_world/roster.py) added after the rows above
        "2-RSU ankle, limits `0 0`": "ankle, 0/0 limits",
        "MJCF four-bar leg with a spring toe, locked": "mjcf toe leg, locked",
        "rrr3": "rrr3",
    }
    for mc in ROSTER:
        if mc.name in later:
            out[later[mc.name]] = mc.write(folder)
    return out


def _time(fn) -> float:
    t0 = time.process_time()
    fn()
    return time.process_time() - t0


def bench(path: Path, n: int, repeats: int) -> dict:
    mech = pincal.load_mechanism(path)
    params = pincal.parameters(mech, "base")
    rows = pincal.sample_actuators(mech, n, np.random.default_rng(0))

    def pose_by_pose():
        for row in rows:
            pose_sensitivity(mech, params, mech.configuration(row))

    def batched():
        Q, bk = mech.configurations_batch(rows)
        sensitivities_batch(mech, params, Q, bk)

    times: dict[str, list[float]] = {"pose": [], "batch": []}
    for _ in range(repeats):
        for key, fn in (("pose", pose_by_pose), ("batch", batched)):
            fn()  # untimed: caches warm
            times[key].append(_time(fn))
    ok = mech.try_configurations_batch(rows)[1]
    return {
        "shape": f"{mech.n_closure_rows}×{mech.free_dofs.size}",
        "rank": mech.closure_rank,
        "in_batch": float(np.mean(ok)),
        "pose": statistics.median(times["pose"]) / n,
        "batch": statistics.median(times["batch"]) / n,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--poses", type=int, default=500)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    print(f"CPU time per pose, median of {args.repeats} repeats over {args.poses} random rows; ")
    print("one BLAS thread; pose by pose and batched timed in turns\n")
    head = f"{'machine':20s} {'closure rows×passive':>20s} {'rank':>5s} {'in batch':>9s}"
    print(head + f" {'pose by pose':>13s} {'batched':>9s} {'speed-up':>9s}")
    with tempfile.TemporaryDirectory() as tmp, threadpool_limits(1):
        for name, path in _machines(Path(tmp)).items():
            r = bench(path, args.poses, args.repeats)
            print(
                f"{name:20s} {r['shape']:>20s} {r['rank']:>5d} {r['in_batch']:>9.0%}"
                f" {r['pose'] * 1e6:>10.0f} µs {r['batch'] * 1e6:>6.0f} µs"
                f" {r['pose'] / r['batch']:>8.1f}×"
            )


if __name__ == "__main__":
    main()

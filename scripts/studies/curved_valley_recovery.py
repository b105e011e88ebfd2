"""Exact-data recovery with the default solver, and with straight Gauss–Newton steps.

Run: python scripts/studies/curved_valley_recovery.py [--straight] [SPEC ...]

A SPEC is ``MACHINE@PRESET``; MACHINE is ``finger_xz`` (the roster's gripper finger
measured in [x, z] only), a fragment of a roster machine's name (``excavator``,
``finger``), ``robot:NAME`` (a bundled robot, e.g. ``robot:ur5``) or ``file:PATH`` (a
model file). Each line: parameters fitted / in the preset, success, max |found − true|
over them [m, rad], the bound the stopping rule allows (``floor``), max prediction error
of the measured components at 5 fresh poses [m, rad], solver iterations (evaluations for
Levenberg–Marquardt), wall time and the solver's message. The errors are the roster's
(tests/open_world/roster.py, ``recover``): σ 0.2 mm / 0.2 mrad on the identifiable set,
30 random poses, exact data. A parameter error far above the floor with exact
predictions is another choice among exactly aliased parameters, not a failed fit
(wedge3 ``full``: 2.9e-5 because q2.tz is fitted for q2.offset, which moves the platform
5 times as much; predictions 2e-16).
``--straight`` adds a line per SPEC with ``GaussNewtonOptions(acceleration=False)``
(the solver before the bent steps, its Levenberg–Marquardt fallback included).
"""

from __future__ import annotations

import argparse
import logging
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))  # the test suite's machine writers

from pincal.identification import GaussNewtonOptions  # noqa: E402
from pincal.model import Mechanism, load_mechanism  # noqa: E402
from tests.open_world import linkage_machines as lm  # noqa: E402
from tests.open_world.roster import ROSTER, _mjcf, recover  # noqa: E402

DEFAULT = [
    f"file:{ROOT / 'models/stewart_6ups/stewart_6ups.urdf'}@base",
    f"file:{ROOT / 'models/wedge3/wedge3.urdf'}@base",
    "robot:ur5@base",
    f"file:{ROOT / 'tests/model/mjcf/delta.xml'}@base",
    "finger_xz@base",
    "finger_xz@full",
    "excavator@base",
    "excavator@full",
    "finger@base",
    "finger@full",
]


def load(name: str, folder: Path) -> Mechanism:
    """The mechanism a SPEC's MACHINE names (module docstring)."""
    if name == "finger_xz":
        sidecar = {**lm.FINGER_SIDECAR, "measured": ["x", "z"]}
        return load_mechanism(_mjcf("finger_xz", lm.mjcf_finger(), sidecar)(folder))
    if name.startswith("file:"):
        return load_mechanism(Path(name[5:]))
    if name.startswith("robot:"):
        return load_mechanism(name[6:])
    machine = next(mc for mc in ROSTER if name.lower() in mc.name.lower())
    return load_mechanism(machine.write(folder))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("specs", nargs="*", default=DEFAULT, help="MACHINE@PRESET")
    ap.add_argument("--straight", action="store_true", help="also without bent steps")
    args = ap.parse_args()
    logging.disable(logging.WARNING)
    runs = [("default", None)]
    if args.straight:
        runs.append(("straight", GaussNewtonOptions(acceleration=False)))
    for spec in args.specs:
        name, preset = spec.rsplit("@", 1)
        with tempfile.TemporaryDirectory() as folder:
            mech = load(name, Path(folder))
            for label, options in runs:
                t = time.perf_counter()
                rec = recover(mech, preset, options=options)
                dt = time.perf_counter() - t
                print(
                    f"{Path(name).name}@{preset} {label}: {rec.k}/{rec.n} success={rec.success}"
                    f" error={rec.parameter_error:.2e} floor={rec.floor:.1e}"
                    f" prediction={rec.prediction_error:.1e} iterations={rec.iterations}"
                    f" t={dt:.2f}s"
                    f" | {rec.message}",
                    flush=True,
                )


if __name__ == "__main__":
    main()

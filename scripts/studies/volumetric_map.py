"""How much of a calibration a volumetric map keeps (docs/cli.md, "Export to a controller").

Run: python scripts/studies/volumetric_map.py

Two machines with known changes, exported as ``volumetric-map`` over 200 random workspace
poses (seed 0): the rotary Delta of ``tests/export/test_rotary_delta.py`` (an upper arm
+0.5 mm, its shoulder +0.3 mm, a zero +2 mrad, an arm's rods +0.4 mm; positions only)
and the bundled Stewart with ``stewart42`` errors drawn U(±0.2 mm / mrad), seed 0 (its
error depends on the platform's orientation, which the map holds at home only). Printed:
the projection's position RMS / max and orientation RMS, and the error with no map.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))  # the test suite's machine writers

from pincal.export import CalibratedMachine, export_calibration  # noqa: E402
from pincal.model import Mechanism, load_mechanism, parameters  # noqa: E402
from tests.export.test_rotary_delta import _moved  # noqa: E402
from tests.open_world.first_machines import delta_elbows  # noqa: E402


def _report(label: str, nominal: Mechanism, calibrated: Mechanism) -> None:
    machine = CalibratedMachine.from_mechanisms(calibrated, nominal)
    proj = export_calibration(machine, "volumetric-map", poses=200).projection
    ref = machine.reference(proj.q_act)[:, :3, 3]
    plain = np.array([nominal.frame_placement(c).translation
                      for c in nominal.configurations(proj.q_act)])  # fmt: skip
    e = np.linalg.norm(plain - ref, axis=1)
    print(f"{label}: map {proj.position_rms * 1e6:.4g} / {proj.position_max * 1e6:.4g} um "
          f"RMS/max, orientation {proj.orientation_rms * 1e6:.4g} urad RMS; no map "
          f"{np.sqrt(np.mean(e**2)) * 1e6:.4g} um RMS")  # fmt: skip
    nodes = [s.split(" (")[0] for s in proj.not_expressed if "nodes" in s]
    print("  " + (nodes[0] if nodes else "every node reachable"))


def main() -> None:
    urdf, sidecar = delta_elbows("spherical")
    delta = Mechanism(urdf, sidecar, name="delta")
    _report("rotary Delta", delta, _moved(delta))
    stewart = load_mechanism("stewart_6ups")
    params = parameters(stewart, "stewart42")
    errors = np.random.default_rng(0).uniform(-2e-4, 2e-4, len(params))
    _report("Stewart", stewart, params.apply(stewart, errors))


if __name__ == "__main__":
    main()

"""`pincal poses` never sums lengths and angles into one σ figure (issue 39, item 4).

Its summary read "RMS parameter std … mm (max 2.387)" over a set mixing metres and
radians (the 2.387 was mrad); its ``--json`` summary kept one ``predicted_rms_std``
adding m² and rad². Both are now per unit class: lengths in mm, angles in mrad.
"""

from __future__ import annotations

import json
import re

import numpy as np
from click.testing import CliRunner

from pincal.cli import main
from pincal.model import load_mechanism, parameters


def test_poses_states_the_predicted_sigma_per_unit_class(tmp_path):
    out = tmp_path / "p.csv"
    args = ["poses", "ur5", "--count", "20", "--candidates", "random:150", "--out", str(out)]
    runner = CliRunner()
    text = runner.invoke(main, args)
    assert text.exit_code == 0, text.output
    doc = runner.invoke(main, [*args, "--overwrite", "--json"])
    assert doc.exit_code == 0, doc.output
    summary = json.loads(doc.stdout.strip().splitlines()[-1])
    assert "predicted_rms_std" not in summary  # the mixed figure
    # the per-parameter σ the design file records [SI], split by each parameter's unit
    design = json.loads(out.with_suffix(".json").read_text())
    sigma = design["predicted_std"]
    units = np.array(parameters(load_mechanism("ur5"), list(sigma)).units)
    values = np.array(list(sigma.values())) * 1e3
    assert {"m", "rad"} <= set(units.tolist())
    by_unit = summary["predicted_std_by_unit"]
    line = next(s for s in text.stdout.splitlines() if "RMS parameter std" in s)
    for kind, unit, shown in (("lengths", "m", "mm"), ("angles", "rad", "mrad")):
        s = values[units == unit]
        entry = by_unit[kind]
        assert entry["unit"] == shown and entry["count"] == s.size
        assert np.isclose(entry["rms"], np.sqrt(np.mean(s**2)), rtol=1e-12)
        assert np.isclose(entry["max"], s.max(), rtol=1e-12)
        found = re.search(rf"{kind} ([0-9.e+-]+) {shown} \(max ([0-9.e+-]+)\)", line)
        assert found, line
        assert np.isclose(float(found[1]), entry["rms"], rtol=1e-3)
        assert np.isclose(float(found[2]), entry["max"], rtol=1e-3)

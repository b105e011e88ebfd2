"""docs/sidecar.md: its minimal URDF + sidecar example loads as the page says."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

import pincal

PAGE = Path(__file__).resolve().parent.parent / "docs" / "sidecar.md"


def _block(lang: str) -> str:
    """The page's first fenced block of ``lang``."""
    found = re.search(rf"```{lang}\n(.*?)```", PAGE.read_text(encoding="utf-8"), flags=re.S)
    assert found, f"docs/sidecar.md has no {lang} block"
    return found.group(1)


def test_the_minimal_example_loads_as_documented(tmp_path):
    model = tmp_path / "fivebar"
    model.mkdir()
    (model / "fivebar.urdf").write_text(_block("xml"), encoding="utf-8")
    (model / "fivebar.yaml").write_text(_block("yaml"), encoding="utf-8")

    mech = pincal.load_mechanism(model)

    side = mech.sidecar
    assert side.closed_loop == (("tip_l", "tip_r"),)
    assert side.type == (("x", "y"),)
    assert side.name_mot == ("mot_l", "mot_r")
    assert side.measured_frame == "tip_r"
    assert side.readings.columns == {"m1": "mot_l", "m2": "mot_r"}
    assert side.readings.units == {"angle": "deg"}
    params = pincal.parameters(mech, "lengths")
    assert len(params) == 6
    assert pincal.identifiability(mech, params).rank == 6  # "6 parameters, 6 identifiable"
    # every corner of the declared workspace assembles
    lo, hi = side.workspace.joints["mot_l"], side.workspace.joints["mot_r"]
    for q in ([lo[0], hi[0]], [lo[1], hi[1]], [lo[0], hi[1]], [lo[1], hi[0]]):
        assert np.all(np.isfinite(mech.forward(np.array(q)).translation))

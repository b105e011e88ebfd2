"""models/aacmm: the committed URDF is the builder's output and reproduces Table 2."""

from __future__ import annotations

import importlib.util
import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml

from pincal.model import (
    dh_apply_errors,
    dh_fk,
    dh_urdf,
)

ROOT = Path(__file__).resolve().parents[2]
MODEL = ROOT / "models" / "aacmm"


def _script():
    spec = importlib.util.spec_from_file_location(
        "build_aacmm", ROOT / "scripts" / "models" / "build_aacmm.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def probe_tip_mm(urdf_text, joints_deg):
    model = pin.buildModelFromXML(urdf_text)
    data = model.createData()
    q = pin.neutral(model)
    for i, angle in enumerate(joints_deg, start=1):
        q[model.joints[model.getJointId(f"joint{i}")].idx_q] = math.radians(angle)
    pin.framesForwardKinematics(model, data, q)
    return data.oMf[model.getFrameId("probe_tip")].translation * 1e3


def test_committed_files_are_up_to_date():
    for name, text in _script().build().items():
        stale = f"{name} is stale: run scripts/models/build_aacmm.py"
        assert (MODEL / name).read_text() == text, stale


def test_sidecar_and_presets_name_urdf_joints():
    sidecar = yaml.safe_load((MODEL / "aacmm.yaml").read_text())
    assert sidecar["measured_frame"] == "probe_tip" and sidecar["measured"] == "position"
    joints = {j.get("name") for j in ET.parse(MODEL / "aacmm.urdf").getroot().iter("joint")}
    counts = {}
    for preset, entries in sidecar["presets"].items():
        assert {e["joints"] for e in entries} <= joints
        counts[preset] = sum(len(e["dofs"]) for e in entries)
    assert counts == {"dh": 28, "dh25": 25}
    assert pin.buildModelFromXML((MODEL / "aacmm.urdf").read_text()).nq == 6


@pytest.mark.parametrize("row_no", [1, 4, 5, 15, 20])
def test_urdf_reproduces_table2_nominal_and_error(row_no):
    table = yaml.safe_load((ROOT / "scripts" / "data" / "seed004.yaml").read_text())
    row = next(r for r in table["table2"] if r["row"] == row_no)
    urdf = (MODEL / "aacmm.urdf").read_text()
    nominal = probe_tip_mm(urdf, row["joints"])
    np.testing.assert_allclose(nominal, row["P"], atol=1e-3)
    # Table 1 errors applied as the parameters of table1_errors.yaml, via the builder
    script = _script()
    rows, errors = script.table1()
    names = {"joint_names": script.JOINT_NAMES, "link_names": script.LINK_NAMES}
    actual = probe_tip_mm(dh_urdf(dh_apply_errors(rows, errors), "x", **names), row["joints"])
    expected = dh_fk(rows, np.radians(row["joints"]), errors=errors)[:3, 3] * 1e3
    np.testing.assert_allclose(actual, expected, atol=1e-9)
    assert np.linalg.norm(actual - nominal) == pytest.approx(row["E"], abs=0.1)

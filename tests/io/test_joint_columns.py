"""Joint columns of measurement files: other names, units and a reference, declared once."""

from __future__ import annotations

import numpy as np
import pytest

from pincal.errors import (
    ActuatorRangeError,
    BadValueError,
    ColumnError,
    MeasurementFormatError,
    ModelFileError,
)
from pincal.io import read_measurements, write_measurements
from pincal.measure import simulate_measurements
from pincal.model import Mechanism, Sidecar, load_mechanism, sample_actuators


@pytest.fixture(scope="module")
def hexa():
    return load_mechanism("hexaslide_6pus")


@pytest.fixture(scope="module")
def meas(hexa):
    rng = np.random.default_rng(5)
    return simulate_measurements(hexa, sample_actuators(hexa, 6, rng), None, rng)


def _with(mech: Mechanism, **keys) -> Mechanism:
    side = mech.sidecar.to_dict() | keys
    return Mechanism(mech.urdf_xml, side, name=mech.name, source=mech.source)


def _rewrite(path, mech, offsets, factor, names):
    """The file with the joint columns renamed, scaled by ``factor``, minus ``offsets``."""
    lines = path.read_text().splitlines()
    k = next(i for i, line in enumerate(lines) if not line.startswith("#"))
    cols = lines[k].split(",")
    n = len(mech.actuated)
    out = [*lines[:k], ",".join([*names, *cols[n:]])]
    for line in lines[k + 1 :]:
        v = line.split(",")
        joints = [(float(x) - float(o)) * factor for x, o in zip(v[:n], offsets, strict=True)]
        out.append(",".join([repr(x) for x in joints] + v[n:]))
    return out


def test_renamed_mm_relative_columns_read_back_the_same_joints(tmp_path, hexa, meas):
    src = write_measurements(tmp_path / "a.csv", meas)
    names = [f"axis{i}" for i in range(1, 7)]
    offsets = np.linspace(0.1, 0.2, 6)
    (tmp_path / "b.csv").write_text("\n".join(_rewrite(src, hexa, offsets, 1e3, names)) + "\n")
    mech = _with(
        hexa,
        columns=dict(zip(names, hexa.actuated, strict=True)),
        joint_units={"length": "mm"},
        joint_reference=dict(zip(hexa.actuated, offsets.tolist(), strict=True)),
    )
    back = read_measurements(tmp_path / "b.csv", mech)
    assert np.allclose(back.q_act, meas.q_act, rtol=0, atol=1e-12)
    assert np.array_equal(back.positions, meas.positions)
    # the same in the header; the header wins over the sidecar key by key
    lines = _rewrite(src, hexa, offsets, 1e3, names)
    pairs = " ".join(f"{c}={j}" for c, j in zip(names, hexa.actuated, strict=True))
    refs = " ".join(f"{j}={float(o)!r}" for j, o in zip(hexa.actuated, offsets, strict=True))
    header = [f"# columns: {pairs}", "# joint_units: length=mm", f"# joint_reference: {refs}"]
    (tmp_path / "c.csv").write_text("\n".join(lines[:1] + header + lines[1:]) + "\n")
    wrong_unit = _with(hexa, joint_units={"length": "um"})
    back = read_measurements(tmp_path / "c.csv", wrong_unit)
    assert np.allclose(back.q_act, meas.q_act, rtol=0, atol=1e-12)


def test_missing_and_wrongly_mapped_columns_are_named(tmp_path, hexa, meas):
    src = write_measurements(tmp_path / "a.csv", meas)
    names = [f"axis{i}" for i in range(1, 7)]
    (tmp_path / "b.csv").write_text("\n".join(_rewrite(src, hexa, [0] * 6, 1.0, names)) + "\n")
    with pytest.raises(ColumnError, match="missing actuator columns") as info:
        read_measurements(tmp_path / "b.csv", hexa)
    assert "'columns'" in str(info.value)
    mapped = dict(zip(names, hexa.actuated, strict=True)) | {"axis6": "no_such_joint"}
    with pytest.raises(ColumnError, match="'axis6' is mapped to joint 'no_such_joint'"):
        read_measurements(tmp_path / "b.csv", _with(hexa, columns=mapped))


def test_values_outside_the_range_or_implausible_name_column_and_row(tmp_path, hexa, meas):
    src = write_measurements(tmp_path / "a.csv", meas)
    names = [f"axis{i}" for i in range(1, 7)]
    mech = _with(hexa, columns=dict(zip(names, hexa.actuated, strict=True)))
    lines = _rewrite(src, hexa, [0] * 6, 1e3, names)  # mm, declared as nothing (m)
    (tmp_path / "c.csv").write_text("\n".join(lines) + "\n")
    with pytest.raises(ActuatorRangeError, match=r"data row 1, column 'axis1': joint 'leg1_slide'"):
        read_measurements(tmp_path / "c.csv", mech)
    back = read_measurements(tmp_path / "c.csv", _with(mech, joint_units={"length": "mm"}))
    assert np.allclose(back.q_act, meas.q_act, rtol=0, atol=1e-12)
    # joints without a URDF range (continuous): a reading over two turns is refused
    pend = load_mechanism("double_pendulum_continuous")
    rng = np.random.default_rng(2)
    q = rng.uniform(-3, 3, (4, 2))
    src = write_measurements(tmp_path / "p.csv", simulate_measurements(pend, q, None, rng))
    lines = _rewrite(src, pend, [0, 0], 180 / np.pi, ["a1", "a2"])  # degrees
    (tmp_path / "d.csv").write_text("\n".join(lines) + "\n")
    cols = {"columns": {"a1": "joint1", "a2": "joint2"}}
    row = 1 + int(np.argmax(np.abs(np.degrees(q[:, 0])) > 4 * np.pi))
    with pytest.raises(BadValueError, match=rf"data row {row}, column 'a1'.*radians\?"):
        read_measurements(tmp_path / "d.csv", _with(pend, **cols))
    back = read_measurements(tmp_path / "d.csv", _with(pend, **cols, joint_units="deg"))
    assert np.allclose(back.q_act, q, rtol=0, atol=1e-12)
    # one unit in the header, as in the sidecar: every angle column in it
    (tmp_path / "e.csv").write_text("\n".join([*lines[:1], "# joint_units: deg", *lines[1:]]))
    back = read_measurements(tmp_path / "e.csv", _with(pend, **cols))
    assert np.allclose(back.q_act, q, rtol=0, atol=1e-12)


def test_bad_declarations_are_refused():
    with pytest.raises(ModelFileError, match="maps several columns"):
        Sidecar.from_dict({"columns": {"a": "j1", "b": "j1"}})
    with pytest.raises(ModelFileError, match="'home' or map joints"):
        Sidecar.from_dict({"joint_reference": "zero"})
    side = Sidecar.from_dict({"columns": {"a": "j1"}, "joint_units": "deg"})
    assert side.to_dict() == {"columns": {"a": "j1"}, "joint_units": {"angle": "deg"}}


def test_malformed_header_entry(tmp_path, hexa, meas):
    src = write_measurements(tmp_path / "a.csv", meas)
    lines = src.read_text().splitlines()
    (tmp_path / "b.csv").write_text("\n".join([lines[0], "# columns: axis1", *lines[1:]]))
    with pytest.raises(MeasurementFormatError, match="NAME=VALUE"):
        read_measurements(tmp_path / "b.csv", hexa)

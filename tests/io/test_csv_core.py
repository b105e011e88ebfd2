"""Tests of the CSV core shared by all file kinds (pincal.io._csv, pincal.io._units)."""

from __future__ import annotations

import numpy as np
import pytest

from pincal.errors import (
    BadValueError,
    MeasurementError,
    MeasurementFormatError,
    NonFiniteValueError,
)
from pincal.io import write_commands
from pincal.io._csv import (
    header_value,
    parse_column,
    parse_numbers,
    positive_value,
    split_file,
    write_csv,
)
from pincal.io._units import ANGLE_UNITS, LENGTH_UNITS, actuator_write_factors, unit_factor


def test_write_then_split_round_trips_header_columns_and_values(tmp_path):
    values = [0.1, -2.5e-7, 1 / 3]
    path = write_csv(
        tmp_path / "f.csv",
        "poses",
        ["length_unit: mm", "target: A 1 2 3", "target: B 4 5 6"],
        ["a [mm]", "b", "c"],
        [[repr(v) for v in values]],
    )
    header, columns, rows = split_file(path, "poses")
    assert header == {"length_unit": ["mm"], "target": ["A 1 2 3", "B 4 5 6"]}
    assert columns == ["a [mm]", "b", "c"]
    assert parse_numbers(rows, columns, "f.csv")[0].tolist() == values  # bit-exact
    assert parse_column(columns[0]) == ("a", "mm")
    assert parse_column("b") == ("b", None)


def test_split_rejects_another_kind_and_a_missing_magic_line(tmp_path):
    path = write_csv(tmp_path / "c.csv", "commands", [], ["pose"], [["0"]])
    with pytest.raises(MeasurementFormatError, match="expected 'pincal poses'"):
        split_file(path, "poses")
    bare = tmp_path / "bare.csv"
    bare.write_text("x,y\n1,2\n", encoding="utf-8")
    with pytest.raises(MeasurementFormatError, match="missing the first header line"):
        split_file(bare, "poses")


def test_numbers_name_the_data_row_and_column():
    cols = ["a", "b"]
    with pytest.raises(BadValueError, match="data row 2, column 'b'") as exc:
        parse_numbers([["1", "2"], ["3", "x"]], cols, "f.csv")
    assert (exc.value.row, exc.value.column) == (2, "b")
    with pytest.raises(NonFiniteValueError, match="data row 1, column 'a'"):
        parse_numbers([["nan", "2"]], cols, "f.csv")
    with pytest.raises(MeasurementFormatError, match="data row 1: 1 fields"):
        parse_numbers([["1"]], cols, "f.csv")


def test_header_values_are_single_and_positive_where_required():
    header = {"kind": ["pose", "targets"], "frame": ["tool"]}
    assert header_value(header, "frame", None, "f") == "tool"
    assert header_value(header, "absent", "dflt", "f") == "dflt"
    with pytest.raises(MeasurementFormatError, match="given 2 times"):
        header_value(header, "kind", None, "f")
    with pytest.raises(MeasurementFormatError, match="is required"):
        header_value(header, "absent", None, "f")
    assert positive_value("0.5", "point_std", "f") == 0.5
    for bad in ("-1", "0", "inf", "abc"):
        with pytest.raises(MeasurementFormatError, match="point_std"):
            positive_value(bad, "point_std", "f")


def test_units_convert_from_si_and_reject_unknown_names():
    assert unit_factor(LENGTH_UNITS, "mm", "length", "w") == 1e3
    assert unit_factor(ANGLE_UNITS, "deg", "angle", "w") == pytest.approx(180 / np.pi)
    with pytest.raises(MeasurementFormatError, match="unknown length unit 'inch'"):
        unit_factor(LENGTH_UNITS, "inch", "length", "w")
    assert actuator_write_factors(["mm", "deg"], 2).tolist() == [1e3, 180 / np.pi]
    assert actuator_write_factors(None, 3).tolist() == [1.0, 1.0, 1.0]


def test_unknown_actuator_unit_on_write_is_a_measurement_error_and_writes_nothing(tmp_path):
    target = tmp_path / "c.csv"
    with pytest.raises(MeasurementError, match="actuator units \\['inch'\\] unknown"):
        write_commands(target, ["a", "b"], np.zeros((1, 2)), actuator_units=["mm", "inch"])
    assert not target.exists()

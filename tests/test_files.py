"""Bounded reading of inputs and clipped values in messages."""

from __future__ import annotations

import os
import threading

import pytest

from pincal._files import read_bytes, read_text
from pincal._limits import Limits
from pincal.errors import InputFileError, InputLimitError, ModelFileError, clip


def test_clip_bounds_every_kind_of_value():
    assert len(clip("a" * 10**6)) <= 80
    assert clip(list(range(10**6))) == "<list of 1000000 items>"
    assert "digits" in clip(10**400)
    assert clip("x\ny") == "x\\ny"
    assert clip(3.5) == "3.5"


def test_device_fifo_and_directory_are_refused(tmp_path):
    with pytest.raises(InputFileError, match="not a regular file"):
        read_bytes("/dev/zero", "measurement CSV")
    fifo = tmp_path / "pipe.csv"
    os.mkfifo(fifo)
    done = threading.Event()

    def attempt():
        with pytest.raises(InputFileError, match="pipe.csv is not a regular file"):
            read_text(fifo, "poses CSV")
        done.set()

    t = threading.Thread(target=attempt, daemon=True)
    t.start()
    t.join(10)
    assert done.is_set(), "reading a FIFO with no writer blocked"
    with pytest.raises(InputFileError, match="is a directory"):
        read_text(tmp_path, "URDF")


def test_size_cap_per_call_and_from_the_limits_in_force(tmp_path, monkeypatch):
    big = tmp_path / "big.csv"
    big.write_bytes(b"x" * 3000)
    with pytest.raises(InputLimitError, match="PINCAL_MAX_FILE_MB"):
        read_bytes(big, "CSV", limit=1000)
    with Limits(file_bytes=1048).applied(), pytest.raises(InputLimitError, match="big.csv"):
        read_bytes(big, "CSV")
    with Limits(file_bytes=1048).applied():
        assert len(read_bytes(big, "CSV", limit=5000)) == 3000  # the argument wins
    monkeypatch.setenv("PINCAL_MAX_FILE_MB", "0.001")  # the library reads no environment
    assert len(read_bytes(big, "CSV")) == 3000


def test_text_names_the_file_and_offset_and_drops_bom(tmp_path):
    bad = tmp_path / "robot.urdf"
    bad.write_bytes(b"<robot>\xff</robot>")
    with pytest.raises(ModelFileError, match=r"robot.urdf is not UTF-8 .*offset 7"):
        read_text(bad, "URDF", error=ModelFileError)
    bom = tmp_path / "m.csv"
    bom.write_bytes("\ufeffa,b\n".encode())
    assert read_text(bom) == "a,b\n"
    with pytest.raises(ModelFileError, match="does not exist"):
        read_text(tmp_path / "missing.urdf", "URDF", error=ModelFileError)


def test_a_file_deep_in_a_long_path_is_named(tmp_path):
    """Messages show a path whole up to 300 characters: the file name is what users need."""
    deep = tmp_path.joinpath(*["campaign-2026-11-measurements"] * 5)
    deep.mkdir(parents=True)
    (deep / "robot.urdf").write_bytes(b"<robot \xff/>")
    assert len(str(deep / "robot.urdf")) > 160
    with pytest.raises(InputFileError, match=r"poses.csv does not exist"):
        read_text(deep / "poses.csv", "poses file")
    with pytest.raises(InputFileError, match=r"robot.urdf is not UTF-8"):
        read_text(deep / "robot.urdf", "URDF")

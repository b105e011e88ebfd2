"""A new instrument kind is one class plus one registry line (issue 24).

The toy "line" gauge below (the distance from the tool point to a fixed line, e.g. a
taut wire) lives only in this file: registered, it is simulated by `pincal simulate
--instrument line`, written and read as an instrument file, and identified by `pincal
calibrate` and `identify_instruments`, with no change to pincal's code.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import pytest
from click.testing import CliRunner

from pincal.cli import main
from pincal.identification import identify_instruments
from pincal.io import read_instrument_file, write_instrument_data
from pincal.measure import Instrument, add_instrument_kind, simulate_instrument
from pincal.model import sample_actuators


def _basis(u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    a = np.eye(3)[int(np.argmin(np.abs(u)))]
    t1 = np.cross(u, a)
    t1 /= np.linalg.norm(t1)
    return t1, np.cross(u, t1)


@dataclass(frozen=True)
class Line(Instrument):
    """Distance from the tool point to a line along ``axis`` through ``a t1 + b t2``."""

    kind: ClassVar[str] = "line"
    description: ClassVar[str] = "distance to a fixed line (a wire gauge)"
    std: float = 1e-6
    axis: tuple[float, float, float] = (1.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        self._check_std()
        u = np.asarray(self.axis, dtype=float)
        object.__setattr__(self, "axis", tuple(u / np.linalg.norm(u)))

    @property
    def parameter_names(self) -> tuple[str, ...]:
        return ("line_a", "line_b")

    def _w(self, P, theta):
        u = np.asarray(self.axis)
        t1, t2 = _basis(u)
        return P - np.outer(P @ u, u) - (theta[0] * t1 + theta[1] * t2), t1, t2

    def _predict(self, P, theta, ids):
        w, t1, t2 = self._w(P, theta)
        v = np.linalg.norm(w, axis=1)
        n = w / v[:, None]
        return v, n, -np.column_stack([n @ t1, n @ t2])

    def start(self, P, v, ids):
        u = np.asarray(self.axis)
        t1, t2 = _basis(u)
        Q = P - np.outer(P @ u, u)  # v² = |Q|² − 2 Q·c + |c|², linear in (a, b, |c|²)
        A = np.column_stack([2 * Q @ t1, 2 * Q @ t2, -np.ones(len(P))])
        return self, np.linalg.lstsq(A, np.sum(Q**2, axis=1) - v**2, rcond=None)[0][:2]

    @classmethod
    def from_header(cls, std, header):
        return cls(std, tuple(header.vector("axis", 3, "1 0 0")))

    def header(self, length, number):
        return ["axis: " + ", ".join(number(x) for x in self.axis)]

    @classmethod
    def typical(cls, P, std=None):
        c = np.asarray(P).mean(axis=0) - np.array([0.0, 0.0, 0.1])
        inst = cls(cls.default_std if std is None else std, (1.0, 0.2, 0.0))
        t1, t2 = _basis(np.asarray(inst.axis))
        return inst, np.array([c @ t1, c @ t2]), None


@pytest.fixture(scope="module")
def line_kind():
    return add_instrument_kind(Line)  # the one registry line


def _fd(f, x, h=1e-7):
    cols = []
    for i in range(x.size):
        e = np.zeros_like(x)
        e[i] = h
        cols.append((f(x + e) - f(x - e)) / (2 * h))
    return np.stack(cols, axis=-1)


def test_line_derivatives_are_exact(line_kind):
    rng = np.random.default_rng(0)
    P, theta = rng.normal(size=(5, 3)), np.array([0.3, -0.2])
    inst = Line(axis=(1.0, 0.2, 0.0))
    _, dv_dp, dv_dth = inst.predict(P, theta)
    for i in range(5):
        num = _fd(lambda p, i=i: inst.predict(p[None], theta)[0][0], P[i])
        np.testing.assert_allclose(dv_dp[i], num, atol=1e-7)
    np.testing.assert_allclose(dv_dth, _fd(lambda t: inst.predict(P, t)[0], theta), atol=1e-7)


def test_line_kind_goes_through_file_and_identification(line_kind, stewart, stewart42, tmp_path):
    rng = np.random.default_rng(4)
    rows = sample_actuators(stewart, 60, rng)
    truth = rng.uniform(-3e-4, 3e-4, len(stewart42))
    actual = stewart42.apply(stewart, truth)
    inst, theta = Line(1e-6, (1.0, 0.2, 0.0)), np.array([0.05, -0.3])
    data = simulate_instrument(actual, inst, theta, rows, rng)
    path = write_instrument_data(tmp_path / "line.csv", data, length_unit="mm")
    assert "# kind: line" in path.read_text() and "# axis: " in path.read_text()
    back = read_instrument_file(path, stewart)
    assert isinstance(back.instrument, Line)
    np.testing.assert_allclose(back.instrument.axis, inst.axis, atol=1e-15)
    np.testing.assert_allclose(back.values, data.values, atol=1e-12)
    out = identify_instruments(stewart, stewart42, [back], labels=["wire"])
    assert out.result.success
    assert 0.3 < out.result.reduced_chi2 < 3.0
    # the fitted readings explain the data to the noise (the line's offsets trade with
    # a translation of the machine across it: a gauge, so they are not compared)
    assert out.result.after.rms_position < 3e-6 < out.result.before.rms_position
    assert sorted(out.instrument_values()) == ["wire.line_a", "wire.line_b"]


def test_cli_simulates_and_calibrates_a_registered_kind(line_kind, tmp_path):
    data = tmp_path / "w.csv"
    args = ["simulate", "stewart_6ups", "--random", "60", "--instrument", "line", "--seed", "3",
            "--error-size", "0.3,1", "--out", str(data)]  # fmt: skip
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    truth = json.loads(data.with_suffix(".truth.json").read_text())
    assert sorted(truth["instrument"]) == ["line_a", "line_b"]
    res = CliRunner().invoke(main, ["calibrate", "stewart_6ups", "--data", str(data),
                                    "--out", str(tmp_path / "cal"), "--json"])  # fmt: skip
    assert res.exit_code == 0, res.output
    doc = json.loads(res.stdout)
    assert sorted(k.split(".")[-1] for k in doc["instruments"]) == ["line_a", "line_b"]

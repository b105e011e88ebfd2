"""The ``base`` preset (identifiable base set without degenerate translations), and
`pincal info` / `poses` / `calibrate` agreeing on how they treat a rank-deficient preset."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

import pincal
from pincal.cli import main
from pincal.errors import UnknownNameError
from pincal.model import Mechanism, degenerate_translations, load_mechanism
from pincal.sensitivity import BASE_POSES, BASE_RTOL, base_parameters, identifiability, parameters
from tests.open_world.machines import MJCF, rssr_emulated_ball, write_machine
from tests.sensitivity.five_bar import FIVE_BAR_SIDECAR, FIVE_BAR_URDF


def test_base_is_the_seeded_identifiable_base_set_without_degenerate_translations(stewart):
    assert set(degenerate_translations(stewart)) == {
        f"leg{i}_u2.t{d}" for i in range(1, 7) for d in "xyz"
    }  # the universal joints of the Stewart platform are two revolutes each
    mech = Mechanism(*rssr_emulated_ball())
    full = parameters(mech, "full")
    skip = set(degenerate_translations(mech))
    candidates = full.subset([k for k, n in enumerate(full.names) if n not in skip])
    rows = pincal.sample_actuators(mech, BASE_POSES, np.random.default_rng(0))
    expected = candidates.subset(identifiability(mech, candidates, rows, rtol=BASE_RTOL).base)
    base = parameters(mech, "base")
    assert base == expected and base.label == "base"
    assert parameters(Mechanism(*rssr_emulated_ball()), "base") == base  # a fresh mechanism
    fresh = pincal.sample_actuators(mech, 40, np.random.default_rng(9))
    assert identifiability(mech, base, fresh).full_rank


def test_degenerate_needs_zero_length_between_two_passive_revolutes():
    urdf, sidecar = rssr_emulated_ball()
    mech = Mechanism(urdf, sidecar)
    assert set(degenerate_translations(mech)) == {f"ball_{a}.t{d}" for a in "yz" for d in "xyz"}
    # ball_x hangs from the actuated crank: its translation is a real crank length
    assert not any(n.startswith(("ball_x.", "crank_mot.")) for n in degenerate_translations(mech))
    # a link of non-zero length between the axes: no longer one physical joint
    moved = urdf.replace(
        '<joint name="ball_y" type="revolute"><parent link="gimbal1"/><child link="gimbal2"/>'
        '<origin xyz="0 0 0"',
        '<joint name="ball_y" type="revolute"><parent link="gimbal1"/><child link="gimbal2"/>'
        '<origin xyz="0.01 0 0"',
    )
    assert moved != urdf
    sidecar = dict(sidecar, home={"crank_mot": 0.0, "ball_y": -0.55})
    assert set(degenerate_translations(Mechanism(moved, sidecar))) == {
        f"ball_z.t{d}" for d in "xyz"
    }


def test_sidecar_preset_named_base_wins_and_unknown_presets_list_base(tmp_path):
    sidecar = dict(FIVE_BAR_SIDECAR, presets={"base": ["act_a.offset", "act_b.offset"]})
    mech = Mechanism(FIVE_BAR_URDF, sidecar)
    assert parameters(mech, "base").names == ("act_a.offset", "act_b.offset")
    with pytest.raises(UnknownNameError, match="'base'"):
        parameters(mech, "bsae")


def test_base_of_a_custom_set_is_labelled_after_it(stewart, stewart42):
    assert base_parameters(stewart, stewart42).label == "stewart42 base"


def _run(*args):
    res = CliRunner().invoke(main, [str(a) for a in args])
    assert res.exit_code == 0, res.output
    return res


@pytest.mark.slow
def test_info_offers_the_base_preset():
    out = _run("info", MJCF / "delta.xml").output
    n = len(parameters(load_mechanism(MJCF / "delta.xml"), "base"))
    assert f"preset 'base': {n} parameters, all identifiable" in out
    assert "36 translations between coincident passive axes left out" in out
    assert "--params base" in out and "--preset base" in out


@pytest.fixture(scope="module")
def five_bar_model(tmp_path_factory):
    return write_machine(tmp_path_factory.mktemp("m"), "five_bar", FIVE_BAR_URDF, FIVE_BAR_SIDECAR)


def test_poses_and_calibrate_reduce_full_alike(five_bar_model, tmp_path):
    """`poses` used to refuse `full` with a wall of unidentifiable names; both commands
    now reduce it to its identifiable base set and say so in the same line."""
    line = (
        "pincal: preset 'full': 13 of 42 parameters identifiable; using its identifiable base "
        "set (`pincal info MODEL` offers it as the 'base' preset)"
    )
    res = _run(
        "poses",
        five_bar_model,
        "--preset",
        "full",
        "--candidates",
        "random:40",
        "--count",
        "8",
        "--restarts",
        "1",
        "--out",
        tmp_path / "p.csv",
    )
    assert line in res.stderr
    data = tmp_path / "m.csv"
    _run(
        "simulate",
        five_bar_model,
        "--random",
        "20",
        "--params",
        "base",
        "--noise",
        "0,0",
        "--out",
        data,
    )
    res = _run(
        "calibrate", five_bar_model, "--data", data, "--params", "full", "--out", tmp_path / "cal"
    )
    assert line in res.stderr
    assert "break loop closure" in res.stdout

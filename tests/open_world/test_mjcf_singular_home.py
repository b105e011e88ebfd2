"""Machine style: an MJCF leg linkage whose rest pose (``qpos0``) is singular — a planar
four-bar at its extended dead point (machines.mjcf_fourbar_straight), closed by an
``<equality><connect>``, with a spring on the rocker (issue 28, cause 6)."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from pincal.errors import SingularConfigurationError
from pincal.model import load_mechanism, load_mjcf
from tests.open_world import acceptance
from tests.open_world.machines import FOURBAR_KEYFRAME, mjcf_fourbar_straight

SPRING = "joint 'rocker_joint' has a spring (MJCF stiffness 2): a passive joint here"


def _write(folder: Path, text: str, sidecar: dict | None = None) -> Path:
    path = folder / "leg.xml"
    path.write_text(text, encoding="utf-8")
    if sidecar is not None:
        path.with_suffix(".yaml").write_text(yaml.safe_dump(sidecar), encoding="utf-8")
    return path


@pytest.fixture(scope="module")
def keyed(tmp_path_factory) -> Path:
    """The file with its keyframe, and a sidecar measuring the coupler site's position."""
    sidecar = {"measured_frame": "tool", "measured": "position"}
    return _write(tmp_path_factory.mktemp("m"), mjcf_fourbar_straight(), sidecar)


@pytest.fixture(scope="module")
def mech(keyed):
    return load_mjcf(keyed)


def test_the_keyframe_is_home_and_the_spring_is_reported(mech):
    assert mech.actuators_of(mech.q_home) == pytest.approx([FOURBAR_KEYFRAME[0]], abs=1e-12)
    assert any(SPRING in n for n in mech.notes)


def test_round_trip(mech):
    acceptance.check_round_trip(mech)


def test_jacobian_matches_central_differences(mech):
    acceptance.check_jacobian(mech)


def test_noise_free_recovery(mech):
    acceptance.check_recovery(mech)


def test_simulate_calibrate_compensate(keyed, tmp_path):
    acceptance.check_cli(keyed, tmp_path)


def test_qpos0_is_singular_so_a_regular_home_nearby_is_chosen(tmp_path):
    """Without a keyframe, qpos0 is the dead point: the nearest regular configuration
    (crank −0.02 rad: the crank cannot turn positive) is home, and the note says so;
    with the crank range [−60°, −10°] (qpos0 outside it) the nearest inside: −0.2 rad."""
    mech = load_mjcf(_write(tmp_path, mjcf_fourbar_straight(False, crank_range="-60 5")))
    assert mech.actuators_of(mech.q_home) == pytest.approx([-0.02], abs=1e-12)
    note = next(n for n in mech.notes if n.startswith("qpos0 is singular"))
    assert "'crank_joint' = -0.02 (qpos0 -0.02)" in note
    assert load_mechanism(tmp_path / "leg.xml").actuators_of(mech.q_home) == pytest.approx([-0.02])


def test_a_sidecar_home_beside_the_file_is_used(tmp_path):
    home = {"crank_joint": -0.3, "coupler_joint": 1.0, "rocker_joint": -0.35}
    mech = load_mjcf(_write(tmp_path, mjcf_fourbar_straight(keyframe=False), {"home": home}))
    assert mech.actuators_of(mech.q_home) == pytest.approx([-0.3], abs=1e-12)
    assert not any(n.startswith("qpos0 is singular") for n in mech.notes)


def test_a_home_outside_a_range_names_the_joint(tmp_path):
    text = mjcf_fourbar_straight(False, crank_range="-60 5", coupler_range="20 120")
    mech = load_mjcf(_write(tmp_path, text))
    assert any(
        "joint 'coupler_joint' = " in n and "is outside its range [0.349066, 2.0944]" in n
        for n in mech.notes
    )


def test_no_regular_home_nearby_says_why(tmp_path):
    """The crank range [0°, 10°] leaves only the side where the loop cannot close."""
    text = mjcf_fourbar_straight(False, crank_range="0 10", coupler_range="20 120")
    with pytest.raises(SingularConfigurationError) as info:
        load_mjcf(_write(tmp_path, text))
    msg = str(info.value)
    assert "home configuration is singular" in msg
    assert "at the home (qpos0), joint 'coupler_joint' = 0 is outside its range" in msg
    assert "<keyframe>" in msg and "'home:' in a sidecar" in msg

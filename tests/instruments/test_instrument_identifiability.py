"""What a ballbar (and the other instruments) can identify of the Stewart platform."""

from __future__ import annotations

import numpy as np
from click.testing import CliRunner

from pincal.cli import main
from pincal.identification import (
    default_instrument,
    instrument_blocks,
    instrument_identifiability,
)
from pincal.model import sample_actuators
from pincal.sensitivity import identification_jacobian


def _rigid_motion(stewart, stewart42, omega, v, centre):
    """Parameter change moving every base joint by v + ω × (b − centre)."""
    dx = np.zeros(len(stewart42))
    for leg in range(1, 7):
        jid = stewart.model.getJointId(f"leg{leg}_u1")
        b = stewart.model.jointPlacements[jid].translation
        d = v + np.cross(omega, b - centre)
        for k, axis in enumerate(("tx", "ty", "tz")):
            dx[stewart42.index(f"leg{leg}_u1.{axis}")] = d[k]
    return dx


def test_ballbar_on_the_stewart_rank_and_absorbed_combinations(stewart, stewart42):
    rep = instrument_identifiability(stewart, stewart42, "distance", n_poses=60, rng=0)
    ident = rep.identifiability
    # 42 + 4 unknowns; 9 unseen: 3 rotations of the machine about the pivot, 3
    # translations absorbed by the pivot, 3 rotations of the tool about the tool point
    assert (ident.rank, len(rep.names)) == (37, 46)
    assert len(ident.unidentifiable) == 9
    assert {"pivot_x", "pivot_y", "pivot_z", "length_offset"} <= set(ident.base_names)
    # every unidentifiable parameter is absorbed by base parameters; the base-joint
    # positions are absorbed together with the pivot (rigid translation)
    assert set(ident.combinations) == set(ident.unidentifiable.tolist())
    pivot_terms = [
        k
        for k, combo in ident.combinations.items()
        if any(ident.names[i].startswith("pivot_") for i in combo)
    ]
    assert pivot_terms and all(
        ident.names[k].endswith(("u1.tx", "u1.ty", "u1.tz")) for k in pivot_terms
    )
    q = sample_actuators(stewart, 60, np.random.default_rng(0))
    _, theta, _ = default_instrument(stewart, "distance", q)
    text = "\n".join(rep.lines())
    assert "rank 37 (9 not identifiable)" in text
    assert len(rep.invisible) == 1 and rep.invisible[0].startswith("3 rotation(s)")
    centre = np.array(
        [float(t) for t in rep.invisible[0].split("point (")[1].split(")")[0].split(",")]
    )
    np.testing.assert_allclose(centre, theta[:3], atol=1e-3)  # about the pivot
    assert rep.absorbed == (
        "the absolute tool position: 3 translations of every tool point "
        "(pivot_x, pivot_y, pivot_z)",
    )
    assert rep.n_still == 3


def test_rigid_motions_of_the_machine_are_null_directions_of_the_ballbar(stewart, stewart42):
    """Independent of the analysis: build the motions and apply the Jacobian."""
    q = sample_actuators(stewart, 30, np.random.default_rng(5))
    inst, theta, _ = default_instrument(stewart, "distance", q)
    J = instrument_blocks(stewart, stewart42, inst, theta, q)[0][:, 0, :]
    n = len(stewart42)
    scale = np.abs(J).max()
    J_pose = identification_jacobian(stewart, stewart42, q)
    # a rotation of the whole machine about the pivot: the ballbar reads nothing
    for omega in np.eye(3):
        dx = _rigid_motion(stewart, stewart42, omega, np.zeros(3), theta[:3])
        assert np.abs(J[:, :n] @ dx).max() < 1e-9 * scale
        # …which a full-pose tracker sees
        assert np.abs(J_pose @ dx).max() > 1e-3
    # a translation of the machine is seen, unless the pivot moves with it
    v = np.array([1.0, -2.0, 0.5])
    dx = _rigid_motion(stewart, stewart42, np.zeros(3), v, np.zeros(3))
    assert np.abs(J[:, :n] @ dx).max() > 0.1 * scale
    assert np.abs(J[:, :n] @ dx + J[:, n : n + 3] @ v).max() < 1e-9 * scale
    # a rotation about another point is seen
    dx = _rigid_motion(stewart, stewart42, np.array([0, 0, 1.0]), np.zeros(3), theta[:3] + 0.3)
    assert np.abs(J[:, :n] @ dx).max() > 1e-3 * scale


def test_every_kind_states_what_it_cannot_see(stewart, stewart42):
    ranks = {}
    for kind in ("sphere", "plane", "point"):
        rep = instrument_identifiability(stewart, stewart42, kind, n_poses=50, rng=1)
        ranks[kind] = rep.rank
        assert rep.n_still == 3  # no scalar instrument sees the tool orientation
        assert rep.invisible or rep.absorbed
    assert ranks == {"sphere": 36, "plane": 39, "point": 36}
    gauge = instrument_identifiability(stewart, stewart42, "point", n_poses=50, rng=1)
    assert any("2 translation(s)" in w for w in gauge.invisible)  # across the gauge axis
    assert any(
        "along (+0.000, -0.000, +1.000)" in w
        or "along (-0.000, +0.000, +1.000)" in w
        or "+1.000)" in w
        for w in gauge.absorbed
    )


def test_cli_info_instrument_prints_the_statement():
    res = CliRunner().invoke(main, ["info", "stewart_6ups", "--instrument", "distance"])
    assert res.exit_code == 0, res.output
    assert "instrument 'distance': 42 machine + 4 instrument parameters, rank 37" in res.output
    assert "cannot see: 3 rotation(s)" in res.output
    absorbed = "absorbed by the instrument parameters: the absolute tool position: 3 translations"
    assert absorbed in res.output
    assert "is not identifiable (absorbed by" in res.output

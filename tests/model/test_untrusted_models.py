"""Untrusted models (issue 16): bounded reading, named URDF errors, size limits, absurd
numbers and a pose workspace off home's assembly branch. Library and CLI for each."""

from __future__ import annotations

import json
import os
import threading
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import yaml
from click.testing import CliRunner

from pincal.cli import main
from pincal.errors import InputLimitError, ModelFileError, UnreachablePoseError
from pincal.model import (
    Limits,
    Mechanism,
    UrdfTree,
    load_mechanism,
    parameters,
    read_sidecar,
    sample_actuators,
    sample_pose,
)
from pincal.model.files import _urdf as urdf_module
from pincal.model.files._urdf_check import captured_stderr
from pincal.sensitivity import identifiability

ROOT = Path(__file__).resolve().parents[2]
MACHINES = Path(__file__).parent / "machines"
LIMIT = '<limit lower="-1" upper="1" effort="1" velocity="1"/>'


def chain(n: int, jtype: str = "revolute", limit: str = LIMIT, origin: str = "0 0 0.1") -> str:
    """A serial chain of ``n`` joints (generated: the big models are not stored)."""
    parts = ['<robot name="big">', '<link name="l0"/>']
    for i in range(1, n + 1):
        parts.append(
            f'<link name="l{i}"/><joint name="j{i}" type="{jtype}"><parent link="l{i - 1}"/>'
            f'<child link="l{i}"/><origin xyz="{origin}"/><axis xyz="0 0 1"/>{limit}</joint>'
        )
    return "\n".join([*parts, "</robot>"])


def star(n: int) -> str:
    """One revolute joint and ``n`` fixed links hung on the base."""
    parts = ['<robot name="star">', '<link name="base"/>', '<link name="tool"/>']
    parts.append(
        '<joint name="j" type="revolute"><parent link="base"/><child link="tool"/>'
        f'<axis xyz="0 0 1"/>{LIMIT}</joint>'
    )
    for i in range(n):
        parts.append(
            f'<link name="s{i}"/><joint name="f{i}" type="fixed"><parent link="base"/>'
            f'<child link="s{i}"/></joint>'
        )
    return "\n".join([*parts, "</robot>"])


def one_joint(joint_body: str, jtype: str = "revolute") -> str:
    return (
        '<robot name="r"><link name="base"/><link name="tool"/>'
        f'<joint name="arm" type="{jtype}"><parent link="base"/><child link="tool"/>'
        f"{joint_body}</joint></robot>"
    )


def cli_error(args: list[str], kind: str) -> str:
    """Run the CLI, expect exit 1 with one line ``pincal: error: <kind>: ...``; the line."""
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 1, res.output
    lines = res.output.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in res.output, res.output
    assert lines[0].startswith(f"pincal: error: {kind}:"), lines[0]
    return lines[0]


def write_model(folder: Path, urdf: str, sidecar: dict | None = None) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    (folder / f"{folder.name}.urdf").write_text(urdf)
    if sidecar is not None:
        (folder / f"{folder.name}.yaml").write_text(yaml.safe_dump(sidecar))
    return folder


# ---------------------------------------------------------------- 1. reading, named errors
def test_non_utf8_urdf_names_the_file(tmp_path):
    urdf = tmp_path / "robot.urdf"
    urdf.write_bytes(one_joint(LIMIT).encode().replace(b'name="r"', b'name="r\xff"'))
    with pytest.raises(ModelFileError, match=r"robot.urdf is not UTF-8 .*offset"):
        load_mechanism(urdf)
    assert "robot.urdf is not UTF-8" in cli_error(["info", str(urdf)], "ModelFileError")


def test_urdf_fifo_is_refused_without_blocking(tmp_path):
    fifo = tmp_path / "pipe.urdf"
    os.mkfifo(fifo)
    caught: list[Exception] = []
    t = threading.Thread(target=lambda: _load_into(fifo, caught), daemon=True)
    t.start()
    t.join(10)
    assert caught and isinstance(caught[0], ModelFileError), "reading a FIFO blocked"
    assert "pipe.urdf is not a regular file" in str(caught[0])


def _load_into(path: Path, caught: list[Exception]) -> None:
    try:
        load_mechanism(path)
    except Exception as exc:  # the test inspects it
        caught.append(exc)


def test_mjcf_is_read_bounded(tmp_path, monkeypatch):
    xml = tmp_path / "arm.xml"
    xml.write_text("<mujoco>" + " " * 3_000_000 + "</mujoco>")
    with (
        Limits(file_bytes=2**20).applied(),
        pytest.raises(InputLimitError, match="MJCF file .*arm.xml .*PINCAL_MAX_FILE_MB"),
    ):
        load_mechanism(xml)


@pytest.mark.parametrize(
    ("body", "jtype", "expected"),
    [
        ("", "revolute", r"joint 'arm' is revolute but has no <limit>"),
        ('<limit lower="0" upper="1"/>', "revolute", r"joint 'arm' <limit> has no effort"),
        ('<limit lower="a" upper="1" effort="1" velocity="1"/>', "prismatic", "<limit lower>"),
        ('<origin xyz="0 0"/>' + LIMIT, "revolute", r"<origin xyz>: expected 3 numbers"),
        (LIMIT, "hinge", r"type 'hinge'; valid types are revolute"),
        ("<mimic/>" + LIMIT, "revolute", r"<mimic> has no joint attribute"),
        ('<dynamics damping="q"/>' + LIMIT, "revolute", r"<dynamics damping>: cannot read"),
        ('<axis xyz="0 0 0"/>' + LIMIT, "revolute", r"<axis xyz> is zero"),
    ],
)
def test_urdf_errors_name_the_joint_and_attribute(tmp_path, body, jtype, expected):
    xml = one_joint(body, jtype)
    with pytest.raises(ModelFileError, match=expected):
        Mechanism(xml)
    folder = write_model(tmp_path / "bad", xml)
    line = cli_error(["info", str(folder)], "ModelFileError")
    assert "bad.urdf" in line and "'arm'" in line


def test_joints_forming_a_loop_are_refused_not_followed_forever():
    xml = (
        '<robot name="r"><link name="base"/><link name="a"/><link name="b"/>'
        '<joint name="ab" type="fixed"><parent link="a"/><child link="b"/></joint>'
        '<joint name="ba" type="fixed"><parent link="b"/><child link="a"/></joint></robot>'
    )
    with pytest.raises(ModelFileError, match=r"links \['a', 'b'\] are not connected .*'base'"):
        UrdfTree(xml)


def test_parser_output_goes_to_the_log_not_the_terminal(capfd, caplog):
    xml = one_joint(LIMIT).replace(
        '<link name="base"/>', '<link name="base"><inertial><mass value="x"/></inertial></link>'
    )
    mech = Mechanism(xml, {"measured_frame": "tool"})
    assert mech.model.nq == 1
    assert capfd.readouterr().err == ""  # urdfdom's "Error:" lines were captured
    assert any("mass [x] is not a float" in r.getMessage() for r in caplog.records)


def test_captured_stderr_collects_fd2_and_the_exception():
    def noisy():
        os.write(2, b"Error: joint [x] broken\n")
        raise ValueError("The XML stream does not contain a valid URDF model.")

    result, text, error = captured_stderr(noisy)
    assert result is None and "joint [x] broken" in text and isinstance(error, ValueError)


# ---------------------------------------------------------------- 2. size limits
def test_deep_chain_is_refused_before_pinocchio_parses_it(tmp_path, monkeypatch):
    xml = chain(5000, "fixed", limit="")  # segfaulted the interpreter in Pinocchio's parser
    assert len(xml) > 500_000
    with pytest.raises(InputLimitError, match=r"5001 links, over the limit of 1000"):
        Mechanism(xml)
    with (  # more links allowed: then the depth limit still holds
        Limits(links=6000).applied(),
        pytest.raises(InputLimitError, match=r"5000 joints in its deepest chain.*limit of 256"),
    ):
        Mechanism(xml)
    monkeypatch.setenv("PINCAL_MAX_LINKS", "6000")  # the same on the command line
    line = cli_error(["info", str(write_model(tmp_path / "deep", xml))], "InputLimitError")
    assert "deep.urdf" in line and "PINCAL_MAX_TREE_DEPTH=5000" in line


def test_deep_mjcf_is_refused_before_the_recursive_conversion(tmp_path, monkeypatch):
    n = 3000  # deeper than Python's recursion limit: was a RecursionError traceback
    bodies = "".join(
        f'<body name="b{i}" pos="0 0 0.1"><joint name="j{i}" type="hinge"/>' for i in range(n)
    )
    path = tmp_path / "deep.xml"
    path.write_text(f"<mujoco><worldbody>{bodies}{'</body>' * n}</worldbody></mujoco>")
    with pytest.raises(InputLimitError, match=r"3000 bodies and sites.*PINCAL_MAX_LINKS"):
        load_mechanism(path)
    with (
        Limits(links=5000).applied(),
        pytest.raises(InputLimitError, match=r"'deep' has 3000 nested bodies.*limit of 256"),
    ):
        load_mechanism(path)
    monkeypatch.setenv("PINCAL_MAX_LINKS", "5000")  # the same on the command line
    assert "PINCAL_MAX_TREE_DEPTH=3000" in cli_error(["info", str(path)], "InputLimitError")


def test_depth_limit_can_be_raised(monkeypatch):
    with pytest.raises(InputLimitError, match=r"PINCAL_MAX_TREE_DEPTH.*Limits\(depth=300\)"):
        UrdfTree(chain(300, "fixed", limit=""))
    with Limits(depth=400).applied():
        assert UrdfTree(chain(300, "fixed", limit="")).depth == 300
    assert UrdfTree(chain(300, "fixed", limit=""), Limits(depth=300)).depth == 300
    monkeypatch.setenv("PINCAL_MAX_TREE_DEPTH", "400")  # the library reads no environment
    with pytest.raises(InputLimitError, match="300 joints in its deepest chain"):
        UrdfTree(chain(300, "fixed", limit=""))


def _never(*args, **kwargs):
    raise AssertionError("called before the limit was checked")


def test_many_joints_are_refused_before_create_data(tmp_path, monkeypatch):
    xml = chain(600)  # 127 KB; Pinocchio's createData reached 6.9 GB (four nv³ tensors)
    with monkeypatch.context() as m:
        m.setattr(pin, "buildModelFromXML", _never)  # refused before Pinocchio builds
        with pytest.raises(InputLimitError, match=r"600 degrees of freedom, over the limit"):
            Mechanism(xml)
    line = cli_error(["info", str(write_model(tmp_path / "wide", xml))], "InputLimitError")
    assert "wide.urdf" in line and "PINCAL_MAX_DOF=600" in line


def test_spherical_joints_from_the_sidecar_count_in_the_dof_limit(monkeypatch):
    xml = (MACHINES / "rssr" / "rssr.urdf").read_text()
    sidecar = read_sidecar(MACHINES / "rssr" / "rssr.yaml")
    nv = Mechanism(xml, sidecar).model.nv
    with (
        Limits(dof=nv - 1).applied(),
        pytest.raises(InputLimitError, match=rf"{nv} degrees of freedom \(with the sidecar"),
    ):
        Mechanism(xml, sidecar)


def test_huge_link_count_is_refused_before_parsing(tmp_path, monkeypatch):
    xml = star(150_000)  # hung the pure-Python tree (quadratic `in` on a list)
    with monkeypatch.context() as m:
        m.setattr(urdf_module.ET, "fromstring", _never)  # refused before the XML is parsed
        with pytest.raises(InputLimitError, match=r"150002 links, over the limit of 1000"):
            Mechanism(xml)
    line = cli_error(["info", str(write_model(tmp_path / "many", xml))], "InputLimitError")
    assert "many.urdf" in line and "PINCAL_MAX_LINKS=150002" in line


def test_identifiability_parameter_count_is_bounded(monkeypatch):
    mech = Mechanism(chain(4), {"measured_frame": "l4"})
    params = parameters(mech, "full")
    with (
        Limits(parameters=len(params) - 1).applied(),
        pytest.raises(InputLimitError, match=rf"{len(params)} parameters in set 'full'"),
    ):
        identifiability(mech, params, rng=np.random.default_rng(0))
    monkeypatch.setenv("PINCAL_MAX_PARAMETERS", str(len(params) - 1))
    identifiability(mech, params, rng=np.random.default_rng(0))  # the library ignores it
    res = CliRunner().invoke(main, ["info", "stewart_6ups", "--json"])  # error as JSON
    assert res.exit_code == 1, res.output
    err = json.loads(res.stdout)["error"]
    assert err["type"] == "InputLimitError"
    assert "PINCAL_MAX_PARAMETERS" in err["message"] and "stewart_6ups" in err["message"]


def test_limit_variables_must_be_positive_integers(monkeypatch):
    monkeypatch.setenv("PINCAL_MAX_DOF", "lots")
    Mechanism(chain(2))  # the library reads no environment; the command line refuses it
    line = cli_error(["info", "wedge3"], "InputLimitError")
    assert "PINCAL_MAX_DOF=lots must be a positive integer (default 200)" in line


# ---------------------------------------------------------------- 3. absurd numbers
@pytest.mark.parametrize("origin", ["1e308 0 0", "nan 0 0", "0 inf 0"])
def test_absurd_joint_origins_are_refused_at_load(tmp_path, origin):
    xml = chain(2, origin=origin)
    with pytest.raises(ModelFileError, match=r"joint 'j1' <origin xyz>: .*within ±1e\+06"):
        Mechanism(xml)
    line = cli_error(["info", str(write_model(tmp_path / "far", xml))], "ModelFileError")
    assert "far.urdf" in line and "'j1'" in line


@pytest.mark.parametrize(
    ("limit", "expected"),
    [
        ('<limit lower="-1e308" upper="1e308" effort="1" velocity="1"/>', r"within ±1e\+16"),
        ('<limit lower="1" upper="0.5" effort="1" velocity="1"/>', r"lower 1 > upper 0.5"),
    ],
)
def test_huge_or_inverted_limits_are_refused_naming_the_joint(tmp_path, limit, expected):
    xml = chain(2, limit=limit)
    with pytest.raises(ModelFileError, match=rf"joint 'j1' <limit.*{expected}"):
        Mechanism(xml)
    line = cli_error(["info", str(write_model(tmp_path / "lim", xml))], "ModelFileError")
    assert "lim.urdf" in line and "'j1'" in line


def test_workspace_range_that_overflows_is_refused_naming_the_joint():
    mech = Mechanism(chain(2), {"workspace": {"joints": {"j1": [-1e308, 1e308]}}})
    with pytest.raises(ModelFileError, match=r"joint 'j1' .*\[-1e\+308, 1e\+308\].*lower <= upper"):
        sample_actuators(mech, 2, np.random.default_rng(0))  # was numpy's OverflowError


def test_gazebo_style_huge_limits_still_load():
    assert Mechanism(chain(2, limit=LIMIT.replace('"-1"', '"-1e16"'))).model.nq == 2


# ---------------------------------------------------------------- 4. pose workspace branch
def _fivebar_mirrored() -> Mechanism:
    folder = MACHINES / "fivebar"
    sidecar = read_sidecar(folder / "fivebar.yaml")
    nominal = Mechanism((folder / "fivebar.urdf").read_text(), sidecar)
    x, y, _ = nominal.frame_placement(nominal.q_home).translation
    # the tip box mirrored through the base line: some poses close only on the other mode
    sidecar["workspace"] = {"pose": {"x": [x - 0.05, x + 0.05], "y": [-y - 0.03, -y + 0.03]}}
    return Mechanism((folder / "fivebar.urdf").read_text(), sidecar)


def test_sampled_poses_are_the_poses_forward_kinematics_gives():
    mech = _fivebar_mirrored()
    box = np.array([mech.workspace.pose["x"], mech.workspace.pose["y"]])  # (2, 2)
    rows = sample_actuators(mech, 30, np.random.default_rng(0))
    for row in rows:  # forward kinematics from home gives the drawn pose, inside the box
        p = mech.forward(row).translation[:2]
        assert np.all(p >= box[:, 0] - 1e-9) and np.all(p <= box[:, 1] + 1e-9), p
    # The box holds poses of another assembly mode (~1 draw in 4): inverse kinematics
    # either refuses them or (before the branch check covered this machine) returned a
    # configuration whose FK is another pose. Either way sampling must not return them.
    rng, other_mode = np.random.default_rng(1), 0
    for _ in range(40):
        target = sample_pose(mech, rng)
        try:
            q_act = mech.inverse(target)
        except UnreachablePoseError:
            other_mode += 1
            continue
        other_mode += np.linalg.norm(mech.forward(q_act).translation - target.translation) > 1e-6
    assert other_mode > 0


def test_pose_workspace_on_the_mirrored_branch_is_refused(tmp_path):
    folder = ROOT / "models" / "stewart_6ups"
    sidecar = read_sidecar(folder / "stewart_6ups.yaml")
    sidecar["workspace"]["pose"]["z"] = [-0.49, -0.41]  # platform mirrored through the base
    mech = Mechanism((folder / "stewart_6ups.urdf").read_text(), sidecar, name="stewart_6ups")
    with pytest.raises(ModelFileError, match=r"another assembly mode than home's.*0\.45"):
        sample_actuators(mech, 3, np.random.default_rng(0), max_tries_per_pose=5)
    model = write_model(tmp_path / "mirror", (folder / "stewart_6ups.urdf").read_text(), sidecar)
    html = tmp_path / "x.html"
    res = CliRunner().invoke(main, ["view", str(model), "--random", "2", "--html", str(html)])
    assert res.exit_code == 1 and "another assembly mode" in res.output, res.output
    assert "Traceback" not in res.output and not html.exists()

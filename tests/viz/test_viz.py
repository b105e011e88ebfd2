"""Tests of pincal.viz: scene contents against independent kinematics, and real renders."""

from __future__ import annotations

import base64
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import umsgpack

from pincal import viz
from pincal.errors import (
    ModelFileError,
    UnknownNameError,
    VisualizationError,
)
from pincal.viz._geometry import stl_with_normals

# A planar two-leg platform drawn with primitives only (the loop leg2_tip ↔ platform
# would be closed by a sidecar; here it only has to look like a parallel machine).
# leg2_tip and platform_tip have no <visual>: they must be drawn as sticks.
PRIMITIVE_URDF = """<?xml version="1.0"?>
<robot name="twoleg">
  <material name="grey"><color rgba="0.6 0.6 0.65 1"/></material>
  <link name="base">
    <visual><origin xyz="0 0 0.01"/><geometry><box size="0.6 0.2 0.02"/></geometry>
      <material name="grey"/></visual>
  </link>
  <joint name="leg1_rot" type="revolute">
    <parent link="base"/><child link="leg1_lower"/>
    <origin xyz="-0.2 0 0.02" rpy="0 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/>
  </joint>
  <link name="leg1_lower">
    <visual><origin xyz="0 0 0.1"/><geometry><cylinder radius="0.02" length="0.2"/></geometry>
    </visual>
  </link>
  <joint name="leg1_slide" type="prismatic">
    <parent link="leg1_lower"/><child link="leg1_upper"/>
    <origin xyz="0 0 0.2"/><axis xyz="0 0 1"/>
    <limit lower="0" upper="0.2" effort="1" velocity="1"/>
  </joint>
  <link name="leg1_upper">
    <visual><origin xyz="0 0 0.05"/><geometry><cylinder radius="0.012" length="0.1"/></geometry>
    </visual>
  </link>
  <joint name="platform_rot" type="revolute">
    <parent link="leg1_upper"/><child link="platform"/>
    <origin xyz="0 0 0.1"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/>
  </joint>
  <link name="platform">
    <visual><origin xyz="0.2 0 0"/><geometry><box size="0.45 0.12 0.03"/></geometry></visual>
    <visual><geometry><sphere radius="0.025"/></geometry></visual>
  </link>
  <joint name="platform_fix" type="fixed">
    <parent link="platform"/><child link="platform_tip"/>
    <origin xyz="0.4 0 0"/>
  </joint>
  <link name="platform_tip"/>
  <joint name="effector_fix" type="fixed">
    <parent link="platform"/><child link="effector"/>
    <origin xyz="0.2 0 0.05" rpy="0 0 0.3"/>
  </joint>
  <link name="effector"/>
  <joint name="leg2_rot" type="revolute">
    <parent link="base"/><child link="leg2_lower"/>
    <origin xyz="0.2 0 0.02"/><axis xyz="0 1 0"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/>
  </joint>
  <link name="leg2_lower"/>
  <joint name="leg2_tipfix" type="fixed">
    <parent link="leg2_lower"/><child link="leg2_tip"/>
    <origin xyz="0 0 0.3"/>
  </joint>
  <link name="leg2_tip"/>
</robot>
"""


def _ur5_path() -> Path:
    from importlib import metadata

    try:
        files = metadata.files("example-robot-data") or []
    except metadata.PackageNotFoundError:
        files = []
    for f in files:
        if str(f).endswith("robots/ur_description/urdf/ur5_robot.urdf"):
            return Path(f.locate()).resolve()
    pytest.skip("example-robot-data's ur5_robot.urdf not found")


@pytest.fixture(scope="module")
def prim(tmp_path_factory):
    path = tmp_path_factory.mktemp("prim") / "twoleg.urdf"
    path.write_text(PRIMITIVE_URDF)
    model = pin.buildModelFromUrdf(str(path))
    qs = [
        np.array([0.0, 0.05, 0.0, 0.0]),
        np.array([0.3, 0.10, -0.4, -0.2]),
        np.array([-0.3, 0.15, 0.4, 0.2]),
        np.array([0.6, 0.20, -0.9, -0.5]),
    ]
    # joint order in the model is not declaration order: build q by name
    order = ["leg1_rot", "leg1_slide", "platform_rot", "leg2_rot"]
    configurations = []
    for q in qs:
        full = pin.neutral(model)
        for name, value in zip(order, q, strict=True):
            full[model.joints[model.getJointId(name)].idx_q] = value
        configurations.append(full)
    return model, path, configurations


@pytest.fixture(scope="module")
def ur5():
    path = _ur5_path()
    model = pin.buildModelFromUrdf(str(path))
    qs = [
        np.array([0.0, -1.2, 1.5, -0.3, 1.2, 0.0]),
        np.array([0.8, -1.0, 1.2, -0.5, 1.0, 0.5]),
        np.array([-0.8, -1.6, 1.8, 0.2, 1.5, 0.0]),
        np.array([1.6, -0.6, 0.9, -0.8, 0.5, 1.0]),
    ]
    return model, path, qs


def _commands(page: str) -> list[dict]:
    block = page.split("var pincalScene = [", 1)[1].split("];", 1)[0]
    return [
        umsgpack.unpackb(base64.b64decode(s)) for s in re.findall(r'"([A-Za-z0-9+/=]+)"', block)
    ]


def _transforms(commands: list[dict] | str) -> dict[str, np.ndarray]:
    if isinstance(commands, str):
        commands = _commands(commands)
    return {
        c["path"]: np.array(c["matrix"]).reshape(4, 4).T
        for c in commands
        if c["type"] == "set_transform"
    }


def _objects(commands: list[dict] | str) -> dict[str, dict]:
    if isinstance(commands, str):
        commands = _commands(commands)
    return {c["path"]: c["object"] for c in commands if c["type"] == "set_object"}


# ----------------------------------------------------------------------------- contents


def test_page_is_self_contained(prim):
    model, path, qs = prim
    page = viz.static_html(model, path, qs, frame="effector", title="two <legs>")
    assert "<script src" not in page and "http://" not in page.split("<script>", 1)[0]
    assert "MeshCat.Viewer" in page and "handle_command_bytearray" in page
    assert "fetch(" not in page.split("var pincalScene", 1)[1]  # commands decoded in order
    assert "two &lt;legs&gt;" in page  # title escaped



@pytest.mark.parametrize("animate", [True, False])
def test_scene_progress_counts_poses_then_animation_segments(prim, animate):
    model, path, qs = prim
    calls: list[tuple[int, int]] = []
    quiet = viz.static_html(model, path, qs, frame="effector", animate=animate)
    page = viz.static_html(
        model, path, qs, frame="effector", animate=animate,
        progress=lambda k, n: calls.append((k, n)),
    )  # fmt: skip
    total = len(qs) * (2 if animate and len(qs) > 1 else 1)
    assert calls == [(k, total) for k in range(1, total + 1)]
    drawn, drawn_quietly = _transforms(page), _transforms(quiet)  # (objects carry UUIDs)
    assert drawn.keys() == drawn_quietly.keys()  # reporting progress changes nothing drawn
    assert all(np.array_equal(drawn[k], drawn_quietly[k]) for k in drawn)

def test_ghost_poses_match_independent_kinematics(prim):
    model, path, qs = prim
    commands = _commands(viz.static_html(model, path, qs, frame="effector", animate=False))
    transforms = _transforms(commands)
    data = model.createData()
    for k, q in enumerate(qs):
        pin.framesForwardKinematics(model, data, q)
        # box visual of the platform sits 0.2 m along the platform's x axis
        T_world_platform = data.oMf[model.getFrameId("platform")].homogeneous
        expected = T_world_platform @ pin.SE3(np.eye(3), np.array([0.2, 0, 0])).homogeneous
        T = transforms[f"/meshcat/pincal/ghosts/pose{k}/platform_0"]
        np.testing.assert_allclose(T, expected, atol=1e-12)
        # measured-frame axes at the effector pose
        T_axes = transforms[f"/meshcat/pincal/frame_axes/pose{k}"]
        np.testing.assert_allclose(
            T_axes, data.oMf[model.getFrameId("effector")].homogeneous, atol=1e-12
        )
    assert len(qs) == 4


def test_primitives_are_drawn_with_urdf_sizes(prim):
    model, path, qs = prim
    objects = _objects(viz.static_html(model, path, qs[:1], animate=False))
    geometry = {p: o["geometries"][0] for p, o in objects.items()}
    box = geometry["/meshcat/pincal/ghosts/pose0/base_0/shape"]
    assert box["type"] == "BoxGeometry"
    assert (box["width"], box["height"], box["depth"]) == pytest.approx((0.6, 0.2, 0.02))
    cyl = geometry["/meshcat/pincal/ghosts/pose0/leg1_lower_0/shape"]
    assert cyl["type"] == "CylinderGeometry"
    assert (cyl["radiusTop"], cyl["height"]) == pytest.approx((0.02, 0.2))
    sphere = geometry["/meshcat/pincal/ghosts/pose0/platform_1/shape"]
    assert sphere["type"] == "SphereGeometry" and sphere["radius"] == pytest.approx(0.025)


def test_links_without_visual_get_sticks_between_joint_origins(prim):
    model, path, qs = prim
    commands = _commands(viz.static_html(model, path, qs[3:4], animate=False))
    transforms = _transforms(commands)
    stick = "/meshcat/pincal/ghosts/pose0/stick_leg2_lower_leg2_tipfix"
    assert stick in transforms
    # the stick runs from the leg2_rot origin to the leg2_tip origin
    data = model.createData()
    pin.framesForwardKinematics(model, data, qs[3])
    a = data.oMf[model.getFrameId("leg2_lower")].translation
    b = data.oMf[model.getFrameId("leg2_tip")].translation
    T = transforms[stick]
    length = transforms[stick + "/shape"][1, 1]
    np.testing.assert_allclose(T[:3, 3], 0.5 * (a + b), atol=1e-12)
    np.testing.assert_allclose(T[:3, 1] * length, b - a, atol=1e-12)
    # the platform has a visual, so its tip gets a stick from the platform origin
    assert "/meshcat/pincal/ghosts/pose0/stick_platform_platform_fix" not in transforms


def test_error_arrows_are_scaled_and_stated(prim):
    model, path, qs = prim
    start = np.array([0.1, 0.0, 0.3])
    error = np.array([0.0012, 0.0, -0.0005])  # [m]
    page = viz.static_html(
        model,
        path,
        qs[:1],
        arrows=[(start, start + error, "#ff8800", "target 1")],
        arrow_scale=100.0,
        animate=False,
    )
    assert "×100" in page and "target 1" in page and f"{1e3 * np.linalg.norm(error):.3f} mm" in page
    commands = _commands(page)
    T = _transforms(commands)["/meshcat/pincal/arrows/arrow0/head"]
    head = _objects(commands)["/meshcat/pincal/arrows/arrow0/head"]["geometries"][0]
    tip = T @ np.array([0.0, head["height"] / 2, 0.0, 1.0])
    np.testing.assert_allclose(tip[:3], start + 100.0 * error, atol=1e-12)
    colour = _objects(commands)["/meshcat/pincal/arrows/arrow0/head"]["materials"][0]["color"]
    assert colour == 0xFF8800


def test_automatic_arrow_scale_is_a_round_number(prim):
    model, path, qs = prim
    start = np.array([0.1, 0.0, 0.3])
    page = viz.static_html(
        model,
        path,
        qs[:1],
        arrows=[(start, start + np.array([0, 0, 1e-4]), (0, 0, 1), "e")],
        animate=False,
    )
    scale = float(re.search(r"magnified ×([0-9.e+]+)", page).group(1))
    mantissa = scale / 10 ** np.floor(np.log10(scale))
    assert mantissa in (1.0, 2.0, 5.0)
    assert 1e2 < scale <= 1e4  # a 0.1 mm error drawn in a scene of about 0.7 m


def test_animation_keyframes_pass_through_every_configuration(prim):
    model, path, qs = prim
    commands = _commands(viz.static_html(model, path, qs, frame="effector", ghosts=False))
    (anim,) = [c for c in commands if c["type"] == "set_animation"]
    assert anim["options"]["play"] and anim["options"]["repetitions"] > 1000
    clips = {a["path"]: a["clip"] for a in anim["animations"]}
    clip = clips["/meshcat/pincal/robot/measured_frame"]
    track = next(t for t in clip["tracks"] if t["name"] == ".position")
    positions = {round(k["time"]): np.array(k["value"]) for k in track["keys"]}
    fps = clip["fps"]
    period = fps // 2 + fps  # hold + move frames per configuration
    data = model.createData()
    for k, q in enumerate(qs):
        pin.framesForwardKinematics(model, data, q)
        expected = data.oMf[model.getFrameId("effector")].translation
        np.testing.assert_allclose(positions[k * period], expected, atol=1e-6)
    np.testing.assert_allclose(positions[len(qs) * period], positions[0], atol=1e-12)


def test_bad_inputs_raise_pincal_errors(prim, tmp_path):
    model, path, qs = prim
    with pytest.raises(VisualizationError, match=r"shape \(3,\); expected \(4,\)"):
        viz.static_html(model, path, [np.zeros(3)])
    with pytest.raises(UnknownNameError, match="effector"):
        viz.static_html(model, path, qs, frame="efector")
    with pytest.raises(ModelFileError):
        viz.static_html(model, tmp_path / "missing.urdf", qs)
    with pytest.raises(VisualizationError, match="colour"):
        viz.static_html(model, path, qs, arrows=[(np.zeros(3), np.ones(3), "reddish", "")])
    with pytest.raises(VisualizationError, match=r"shape \(3,\)"):
        viz.static_html(model, path, qs, arrows=[(np.zeros(2), np.ones(3), "#ff0000", "")])


def test_urdf_xml_string_is_accepted(prim):
    model, _, qs = prim
    objects = _objects(viz.static_html(model, PRIMITIVE_URDF, qs[:1], animate=False))
    assert "/meshcat/pincal/ghosts/pose0/base_0/shape" in objects


def test_ur5_meshes_and_budget_fallback(ur5):
    model, path, qs = ur5
    one = _objects(viz.static_html(model, path, qs[:1], animate=False))
    formats = {o["geometries"][0].get("format") for o in one.values() if o.get("geometries")}
    assert "dae" in formats  # visual meshes when they fit the budget
    many = _objects(viz.static_html(model, path, qs))
    formats = {o["geometries"][0].get("format") for o in many.values() if o.get("geometries")}
    assert "stl" in formats and "dae" not in formats  # collision meshes for 5 copies


def test_stl_normals_are_recomputed():
    header = b"\0" * 80 + np.array([1], "<u4").tobytes()
    tri = np.zeros(1, [("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
    tri["v"] = [[[0, 0, 0], [2, 0, 0], [0, 3, 0]]]
    fixed = stl_with_normals(header + tri.tobytes())
    n = np.frombuffer(fixed, "<f4", 3, 84)
    np.testing.assert_allclose(n, [0, 0, 1])


def test_write_html_is_atomic_and_readable(tmp_path):
    target = tmp_path / "sub" / "view.html"
    viz.write_html(target, "<html>one</html>")
    viz.write_html(target, "<html>two</html>")
    assert target.read_text() == "<html>two</html>"
    assert [p.name for p in target.parent.iterdir()] == ["view.html"]
    assert target.stat().st_mode & 0o444 == 0o444


def test_live_session_binds_to_localhost(prim):
    model, path, qs = prim
    session = viz.live(model, path, qs[:2], frame="effector")
    try:
        assert session.web_url.startswith("http://127.0.0.1:")
        assert session.zmq_url.startswith("tcp://127.0.0.1:")
    finally:
        session.close()
    assert session.visualizer.window.server_proc.poll() is not None


# ----------------------------------------------------------------------------- browser

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
needs_chromium = pytest.mark.skipif(
    CHROMIUM is None, reason="chromium is not installed (apt-get install chromium)"
)


def _screenshot(page: str, tmp_path: Path, name: str) -> np.ndarray:
    import matplotlib.image

    html_path = viz.write_html(tmp_path / f"{name}.html", page)
    png = tmp_path / f"{name}.png"
    subprocess.run(
        [
            CHROMIUM,
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-background-networking",
            "--hide-scrollbars",
            "--window-size=800,600",
            "--virtual-time-budget=2000",
            f"--screenshot={png}",
            html_path.resolve().as_uri(),
        ],
        check=True,
        capture_output=True,
        timeout=120,
    )
    return matplotlib.image.imread(png)[..., :3]


def _foreground(image: np.ndarray) -> np.ndarray:
    """Pixels that differ from their row's background (the gradient is constant per row)."""
    pane = image[80:]  # below the legend and the controls bar
    background = np.median(pane, axis=1, keepdims=True)
    return np.max(np.abs(pane - background), axis=2) > 0.08


@needs_chromium
def test_render_shows_the_mechanism_and_poses_differ(prim, tmp_path):
    model, path, qs = prim
    first = _screenshot(viz.static_html(model, path, qs[:1], frame="effector"), tmp_path, "p0")
    last = _screenshot(viz.static_html(model, path, qs[3:4], frame="effector"), tmp_path, "p3")
    for image in (first, last):
        assert _foreground(image).mean() > 0.01  # the mechanism covers > 1 % of the pane
        assert len(np.unique((image * 31).astype(int).reshape(-1, 3), axis=0)) > 50
    changed = np.max(np.abs(first - last), axis=2) > 0.08
    assert changed.mean() > 0.005


@pytest.mark.slow
@needs_chromium
def test_render_ur5_ghosts_and_animation(ur5, tmp_path):
    model, path, qs = ur5
    page = viz.static_html(model, path, qs, frame="tool0", title="UR5")
    image = _screenshot(page, tmp_path, "ur5")
    assert _foreground(image).mean() > 0.02
    # each ghost colour shows up somewhere (hue of pose 0 is blue, of pose 3 red)
    hsv = __import__("matplotlib.colors").colors.rgb_to_hsv(image[80:])
    saturated = hsv[..., 1] > 0.35
    assert np.any(saturated & (np.abs(hsv[..., 0] - 0.62) < 0.05))

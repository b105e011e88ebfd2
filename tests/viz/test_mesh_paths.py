"""Views read mesh files only from the model's directory unless allowed (issue 16).

A view embeds mesh bytes in its HTML page; a URDF naming a file outside its directory
(absolute path, ``../``, a foreign ``package://``) must not copy it into the page.
"""

from __future__ import annotations

import base64
import re
import struct
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from click.testing import CliRunner

from pincal import viz
from pincal.cli import main
from pincal.errors import VisualizationError

SECRET = b"SECRET-BYTES-4f1c"


def stl(path: Path, tag: bytes = b"") -> None:
    """A one-triangle binary STL whose 80-byte header carries ``tag``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tri = np.array([[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0]], dtype="<f4")
    header = tag.ljust(80, b"\0")
    body = struct.pack("<I", 1) + np.zeros(3, "<f4").tobytes() + tri.tobytes() + b"\0\0"
    path.write_bytes(header + body)


def robot(folder: Path, filename: str) -> Path:
    """Model directory ``folder`` whose link ``base`` draws the mesh ``filename``."""
    folder.mkdir(parents=True, exist_ok=True)
    urdf = folder / f"{folder.name}.urdf"
    urdf.write_text(
        f'<robot name="{folder.name}"><link name="base"><visual><geometry>'
        f'<mesh filename="{filename}"/></geometry></visual></link><link name="tool"/>'
        '<joint name="j" type="revolute"><parent link="base"/><child link="tool"/>'
        '<origin xyz="0 0 0.2"/><axis xyz="0 0 1"/>'
        '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>'
    )
    return urdf


def page(urdf: Path, **kwargs) -> str:
    model = pin.buildModelFromUrdf(str(urdf))
    return viz.static_html(model, urdf, [np.zeros(model.nq)], animate=False, **kwargs)


def cli_view(model: Path, *extra: str) -> tuple[int, str]:
    html = model / "view.html"
    res = CliRunner().invoke(
        main, ["view", str(model), "--random", "1", "--html", str(html), *extra]
    )
    return res.exit_code, res.output


def embedded(html: str) -> bytes:
    """All meshcat commands recorded in a static page, decoded."""
    blobs = re.findall(r'"([A-Za-z0-9+/]{40,}={0,2})"', html)
    return b"".join(base64.b64decode(b) for b in blobs)


def test_meshes_inside_the_model_directory_are_drawn(tmp_path):
    stl(tmp_path / "arm" / "meshes" / "base.stl", b"INSIDE-MESH")
    for name in ("meshes/base.stl", "package://arm/meshes/base.stl"):
        urdf = robot(tmp_path / "arm", name)
        assert b"INSIDE-MESH" in embedded(page(urdf))


@pytest.mark.parametrize("how", ["absolute", "dotdot", "package", "file", "symlink"])
def test_meshes_outside_are_refused_naming_link_and_path(tmp_path, how):
    secret = tmp_path / "private" / "secret.stl"
    stl(secret, SECRET)
    (tmp_path / "arm").mkdir()
    (tmp_path / "arm" / "link.stl").symlink_to(secret)
    filename = {
        "absolute": str(secret),
        "dotdot": "../private/secret.stl",
        "package": "package://private/secret.stl",
        "file": f"file://{secret}",
        "symlink": "link.stl",  # inside by name, outside once the link is followed
    }[how]
    urdf = robot(tmp_path / "arm", filename)
    with pytest.raises(VisualizationError, match=r"link 'base' mesh .*secret.stl.*outside") as e:
        page(urdf)
    assert "--allow-mesh-outside" in str(e.value)
    code, out = cli_view(urdf.parent)
    assert code == 1 and out.startswith("pincal: error: VisualizationError:"), out
    assert len(out.strip().splitlines()) == 1 and "secret.stl" in out and "'base'" in out
    assert not (urdf.parent / "view.html").exists()


def test_allowing_meshes_outside_reads_them(tmp_path):
    secret = tmp_path / "private" / "secret.stl"
    stl(secret, SECRET)
    urdf = robot(tmp_path / "arm", "../private/secret.stl")
    assert SECRET in embedded(page(urdf, allow_mesh_outside=True))
    with viz.allow_mesh_outside():
        assert SECRET in embedded(page(urdf))  # the context manager (for viz.live) too
    code, out = cli_view(urdf.parent, "--allow-mesh-outside")
    assert code == 0, out
    assert (urdf.parent / "view.html").stat().st_size > 0


@pytest.mark.parametrize(
    ("filename", "expected"),
    [
        ("http://example.com/base.stl", r"http:// is not read"),
        ("meshes/missing.stl", r"missing.stl is not an existing file"),
        ("meshes/garbage.stl", r"cannot load link 'base' mesh .*garbage.stl"),
        ("meshes/garbage.dae", r"cannot load link 'base' mesh .*garbage.dae"),
    ],
)
def test_urls_missing_and_unreadable_meshes_are_visualization_errors(tmp_path, filename, expected):
    folder = tmp_path / "arm"
    (folder / "meshes").mkdir(parents=True)
    (folder / "meshes" / "garbage.stl").write_bytes(b"not a mesh " * 4)
    (folder / "meshes" / "garbage.dae").write_bytes(b"<notcollada/>")
    urdf = robot(folder, filename)
    with pytest.raises(VisualizationError, match=expected):
        page(urdf)
    code, out = cli_view(folder)
    assert code == 1 and out.startswith("pincal: error: VisualizationError:"), out
    assert len(out.strip().splitlines()) == 1 and "'base'" in out


def test_urdf_text_without_a_directory_reads_no_mesh(tmp_path):
    stl(tmp_path / "m.stl")
    urdf = robot(tmp_path / "arm", str(tmp_path / "m.stl"))
    model = pin.buildModelFromUrdf(str(urdf))
    with pytest.raises(VisualizationError, match="given as text"):
        viz.static_html(model, urdf.read_text(), [np.zeros(model.nq)])

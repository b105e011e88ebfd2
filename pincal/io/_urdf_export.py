"""Write a (calibrated) mechanism back as URDF + sidecar."""

from __future__ import annotations

from pathlib import Path

import yaml

from pincal.io._atomic import atomic_write_text
from pincal.model import Mechanism

__all__ = ["save_urdf"]


def save_urdf(mech: Mechanism, path: str | Path) -> Path:
    """Write ``mech`` as ``path`` (a ``.urdf`` file) plus its sidecar ``<stem>.yaml``.

    Joint origins carry the identified geometry at full precision, so loading the
    files back reproduces the mechanism's kinematics. Each file is written
    atomically; the source files are never touched.

    Returns:
        The URDF path.
    """
    path = Path(path)
    if path.suffix.lower() != ".urdf":
        path = path / f"{mech.name}.urdf"
    if mech.source is not None and path.resolve() == Path(mech.source).resolve():
        raise FileExistsError(f"refusing to overwrite the source model {str(path)!r}")
    sidecar = mech.sidecar.to_dict()
    if mech.measured_frame != sidecar.get("measured_frame"):
        sidecar["measured_frame"] = mech.measured_frame
    atomic_write_text(path, mech.urdf_xml if mech.urdf_xml.endswith("\n") else mech.urdf_xml + "\n")
    if sidecar:
        header = f"# Sidecar of {mech.name} written by pincal\n"
        text = yaml.safe_dump(sidecar, sort_keys=False, default_flow_style=None, width=100)
        atomic_write_text(path.with_suffix(".yaml"), header + text)
    return path

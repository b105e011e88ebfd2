from __future__ import annotations

import numpy as np
import pytest

from pincal.io import save_urdf
from pincal.model import load_mechanism


def test_saved_urdf_reproduces_forward_kinematics(stewart, stewart42, stewart_poses, tmp_path):
    values = np.random.default_rng(0).normal(0, 1e-3, 42)
    calibrated = stewart42.apply(stewart, values)
    path = save_urdf(calibrated, tmp_path / "out" / "cal.urdf")
    assert path.with_suffix(".yaml").is_file()
    reloaded = load_mechanism(path)
    for row in stewart_poses[:5]:
        a, b = calibrated.forward(row), reloaded.forward(row)
        assert np.max(np.abs(a.homogeneous - b.homogeneous)) <= 1e-9
    assert not list((tmp_path / "out").glob("*.tmp"))


def test_refuses_to_overwrite_source(stewart):
    with pytest.raises(FileExistsError):
        save_urdf(stewart, stewart.source)

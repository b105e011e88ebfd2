"""Computed presets: pincal.model offers ``parameters(mech, name)`` for presets that later
stages register (``base`` by pincal.sensitivity) without importing those stages."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import pincal
from pincal.errors import ParameterError, UnknownNameError
from pincal.model import Mechanism, parameters, register_preset
from pincal.model import _parameters as model_parameters
from pincal.sensitivity import base_parameters
from tests.sensitivity.five_bar import FIVE_BAR_SIDECAR, FIVE_BAR_URDF

MODEL_DIR = Path(pincal.__file__).parent / "model"


def _imported_modules(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    out: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module:
            out.add(node.module)
    return out


def test_model_imports_nothing_from_later_stages():
    later = ("pincal.sensitivity", "pincal.identification", "pincal.design", "pincal.measure")
    bad = {
        f"{p.name}: {m}"
        for p in MODEL_DIR.glob("*.py")
        for m in _imported_modules(p)
        if m.startswith(later)
    }
    assert not bad


def test_base_preset_is_registered_by_sensitivity():
    mech = Mechanism(FIVE_BAR_URDF, FIVE_BAR_SIDECAR)
    assert parameters(mech, "base") == base_parameters(mech)
    with pytest.raises(UnknownNameError, match="'base'"):
        parameters(mech, "no-such-preset")


def test_register_preset_adds_a_computed_preset(monkeypatch):
    monkeypatch.setattr(model_parameters, "_COMPUTED_PRESETS", {})
    mech = Mechanism(FIVE_BAR_URDF, FIVE_BAR_SIDECAR)
    with pytest.raises(UnknownNameError):
        parameters(mech, "offsets")
    register_preset("offsets", lambda m: parameters(m, ["act_a.offset", "act_b.offset"]))
    assert parameters(mech, "offsets").names == ("act_a.offset", "act_b.offset")


@pytest.mark.parametrize("name", ["full", "", 3])
def test_register_preset_refuses_full_and_non_names(name):
    with pytest.raises(ParameterError, match="cannot register"):
        register_preset(name, lambda m: parameters(m, "full"))  # type: ignore[arg-type]

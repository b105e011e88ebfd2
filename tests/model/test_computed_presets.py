"""Computed presets: the model resolves ``parameters(mech, name, computed=...)`` for presets
a later stage computes and passes in (``base`` by pincal.sensitivity), without importing
that stage and without a registry filled at import time."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import pincal
from pincal import model, sensitivity
from pincal.errors import UnknownNameError
from pincal.model import Mechanism
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


def test_base_preset_comes_from_sensitivity():
    mech = Mechanism(FIVE_BAR_URDF, FIVE_BAR_SIDECAR)
    assert pincal.parameters is sensitivity.parameters
    assert sensitivity.parameters(mech, "base") == base_parameters(mech)
    with pytest.raises(UnknownNameError, match="'base'"):  # listed among the valid names
        sensitivity.parameters(mech, "no-such-preset")


def test_model_alone_points_to_where_base_is_computed():
    mech = Mechanism(FIVE_BAR_URDF, FIVE_BAR_SIDECAR)
    with pytest.raises(UnknownNameError, match=r"'base' is computed: use pincal\.parameters"):
        model.parameters(mech, "base")
    with pytest.raises(UnknownNameError, match="base") as info:
        model.parameters(mech, "base+gain")
    assert "base" not in info.value.valid  # the model lists only what it can resolve


def test_computed_presets_are_arguments():
    mech = Mechanism(FIVE_BAR_URDF, FIVE_BAR_SIDECAR)
    offsets = {"offsets": lambda m: model.parameters(m, ["act_a.offset", "act_b.offset"])}
    with pytest.raises(UnknownNameError):
        model.parameters(mech, "offsets")
    assert model.parameters(mech, "offsets", computed=offsets).names == (
        "act_a.offset",
        "act_b.offset",
    )
    # PRESET+TERM passes them on to the preset part
    with_term = model.parameters(mech, "offsets+gain", computed=offsets)
    assert with_term.names == ("act_a.offset", "act_b.offset", "act_a.gain", "act_b.gain")

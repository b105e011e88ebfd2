"""Typed sidecar: unknown keys are refused with a suggestion, round trips are exact."""

from __future__ import annotations

import pytest
import yaml

from pincal.errors import ModelFileError
from pincal.io import save_urdf
from pincal.model import Mechanism, Sidecar, bundled_models, load_mechanism, read_sidecar
from pincal.model.loading._model_files import MODELS_DIR


def test_misspelt_key_is_refused_with_the_nearest_valid_key():
    raw = read_sidecar(MODELS_DIR / "stewart_6ups" / "stewart_6ups.yaml")
    raw["closed_loops"] = raw.pop("closed_loop")
    xml = (MODELS_DIR / "stewart_6ups" / "stewart_6ups.urdf").read_text()
    with pytest.raises(ModelFileError, match="did you mean 'closed_loop'"):
        Mechanism(xml, raw)


def test_misspelt_workspace_key_is_refused():
    with pytest.raises(ModelFileError, match="did you mean 'joints'"):
        Sidecar.from_dict({"workspace": {"joint": {"a": [0, 1]}}})


@pytest.mark.parametrize("name", bundled_models())
def test_bundled_sidecars_round_trip(name):
    raw = read_sidecar(MODELS_DIR / name / f"{name}.yaml")
    sc = Sidecar.from_dict(raw)
    again = Sidecar.from_dict(yaml.safe_load(yaml.safe_dump(sc.to_dict())))
    assert again == sc
    assert load_mechanism(name).sidecar == sc


def test_single_type_applies_to_every_pair_and_upper_case_kinds():
    sc = Sidecar.from_dict({"closed_loop": [["a", "b"], ["c", "d"]], "type": ["3D"]})
    assert sc.type == ("3D", "3D")
    sc = Sidecar.from_dict({"closed_loop": [["a", "b"], ["c", "d"]], "type": ["x", "z"]})
    assert sc.type == (("x", "z"), ("x", "z"))


def test_mechanism_sidecar_is_typed_and_export_writes_it(tmp_path):
    mech = load_mechanism("wedge3")
    assert isinstance(mech.sidecar, Sidecar)
    assert mech.sidecar.name_mot == ("q0", "q1", "q2")
    path = save_urdf(mech, tmp_path / "w.urdf")
    back = load_mechanism(path)
    assert back.sidecar == mech.sidecar


def test_replace_rechecks_values():
    sc = Sidecar.from_dict({"measured": "position"})
    assert sc.replace(measured_frame="tool").measured_frame == "tool"
    with pytest.raises(ModelFileError):
        sc.replace(measured=["q"])

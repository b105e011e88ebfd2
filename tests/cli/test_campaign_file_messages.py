"""Campaign file errors name the file, the key and the fix."""

from __future__ import annotations

import pytest

from pincal.cli._campaign import load_campaign
from pincal.errors import CampaignError


@pytest.mark.parametrize("text, shown, fix", [("1e300", "'1e300'", "write 1.0e+300"),
                                              ("1e-2", "'1e-2'", "write 0.01")])  # fmt: skip
def test_yaml_exponent_read_as_text_gets_a_hint(tmp_path, text, shown, fix):
    f = tmp_path / "camp.yaml"
    f.write_text(f"model: wedge3\nmeasurements:\n  noise: [{text}, 0.05]\n")
    with pytest.raises(CampaignError) as exc:
        load_campaign(f)
    msg = str(exc.value)
    assert msg.startswith(str(f)) and "measurements.noise[0]" in msg
    assert shown in msg and fix in msg


def test_a_campaign_that_is_not_a_mapping_names_its_file(tmp_path):
    f = tmp_path / "list.yaml"
    f.write_text("- a\n- b\n")
    with pytest.raises(CampaignError, match=r"list.yaml: campaign file: expected a mapping"):
        load_campaign(f)

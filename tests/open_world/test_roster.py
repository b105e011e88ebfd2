"""The one acceptance test every machine of the roster passes (tests/open_world/roster.py):
a loadable machine recovers a random error on the identifiable set of its ``base`` and
``full`` presets to 1e-9 (parameters [m, rad] and predictions of the measured
components) from exact measurements, from the nominal model; a machine with a defect
of its own is refused with the message that names it (issue 28, cause 2 and "Done when")."""

from __future__ import annotations

import logging

import pytest

from pincal.model import load_mechanism
from tests.open_world.roster import ROSTER, Machine, recover

LOADS = [mc for mc in ROSTER if mc.refused is None]
REFUSED = [mc for mc in ROSTER if mc.refused is not None]


@pytest.mark.parametrize("preset", ["base", "full"])
@pytest.mark.parametrize("machine", LOADS, ids=[mc.name for mc in LOADS])
def test_noise_free_recovery_on_every_machine(machine: Machine, preset: str, tmp_path):
    logging.disable(logging.WARNING)
    try:
        mech = load_mechanism(machine.write(tmp_path))
    finally:
        logging.disable(logging.NOTSET)
    r = recover(mech, preset)
    assert r.success, r.message
    assert r.k > 0 and r.parameter_error <= 1e-9 and r.prediction_error <= 1e-9, r


@pytest.mark.parametrize("machine", REFUSED, ids=[mc.name for mc in REFUSED])
def test_machines_with_their_own_defects_are_refused_by_name(machine: Machine, tmp_path):
    assert machine.refused is not None
    error, fragment = machine.refused
    with pytest.raises(error) as info:
        load_mechanism(machine.write(tmp_path))
    assert fragment in str(info.value)

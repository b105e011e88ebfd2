"""A mechanism is read-only in fact: no attribute can be set or deleted once it is made.

Every public name of a loaded serial arm and of a closed-loop machine refuses assignment
and deletion with :class:`~pincal.errors.ImmutableError` (an ``AttributeError`` too), as
does a mechanism derived from one (moved joint origins, added notes); the arrays it
shares with its derivations are not writable; values computed later are kept by
:meth:`Mechanism.memo`, per mechanism.
"""

from __future__ import annotations

import numpy as np
import pytest

from pincal.errors import ImmutableError, PincalError
from pincal.model import Mechanism, load_mechanism
from pincal.sensitivity import parameters


@pytest.fixture(scope="module", params=["aacmm", "stewart_6ups"])
def mech(request: pytest.FixtureRequest) -> Mechanism:
    """A serial arm (AACMM, open chain) and a closed-loop machine (Stewart 6-UPS)."""
    return load_mechanism(request.param)


def _derived(mech: Mechanism) -> Mechanism:
    ps = parameters(mech, "full")
    return ps.apply(mech, np.random.default_rng(3).uniform(-1e-3, 1e-3, len(ps)))


def _public_names(mech: Mechanism) -> list[str]:
    return [n for n in dir(mech) if not n.startswith("_")]


def _assert_read_only(mech: Mechanism) -> None:
    names = _public_names(mech)
    # the data attributes are among them (not only methods and properties)
    assert {"model", "q_home", "options", "notes", "queries", "loop_solver"} <= set(names)
    for name in names:
        with pytest.raises(ImmutableError, match=rf"cannot set attribute '{name}'") as err:
            setattr(mech, name, None)
        assert isinstance(err.value, AttributeError) and isinstance(err.value, PincalError)
        assert "with_joint_origins" in str(err.value) and "load_mechanism" in str(err.value)
        with pytest.raises(ImmutableError, match=rf"cannot delete attribute '{name}'"):
            delattr(mech, name)
    with pytest.raises(ImmutableError):  # nor a new attribute
        mech.some_cache = {}  # type: ignore[attr-defined]
    with pytest.raises(ImmutableError):  # nor a private one
        mech._urdf_xml = ""


def test_a_loaded_mechanism_refuses_every_assignment(mech: Mechanism) -> None:
    q_home, notes = mech.q_home.copy(), mech.notes
    _assert_read_only(mech)
    assert np.array_equal(mech.q_home, q_home) and mech.notes == notes


def test_a_derived_mechanism_refuses_every_assignment(mech: Mechanism) -> None:
    derived = _derived(mech)
    assert not np.allclose(derived.frame_placement(derived.q_home).homogeneous,
                           mech.frame_placement(mech.q_home).homogeneous, atol=1e-9)  # fmt: skip
    _assert_read_only(derived)
    assert derived.urdf_xml != mech.urdf_xml  # written on first use, kept by the memo
    _assert_read_only(_derived(derived))


def test_notes_are_added_by_derivation(mech: Mechanism) -> None:
    noted = mech.with_notes(before=["first"], after=["last"])
    assert noted.notes == ("first", *mech.notes, "last")
    assert "first" not in mech.notes and noted.model is mech.model
    _assert_read_only(noted)


def test_shared_arrays_are_not_writable(mech: Mechanism) -> None:
    with pytest.raises(ValueError, match="read-only"):
        mech.q_home[0] = 1.0
    with pytest.raises(ValueError, match="read-only"):
        mech.actuator_limits[0, 0] = 0.0
    q = mech.q_home.copy()  # a copy is the caller's own
    q[0] += 1.0
    assert q[0] != mech.q_home[0]


def test_memo_computes_once_per_mechanism(mech: Mechanism) -> None:
    calls: list[int] = []

    def build() -> int:
        calls.append(1)
        return len(calls)

    assert mech.memo("test_value", build) == 1
    assert mech.memo("test_value", build) == 1 and len(calls) == 1
    derived = mech.with_notes(after=["x"])  # a derivation starts with an empty memo
    assert derived.memo("test_value", build) == 2 and len(calls) == 2

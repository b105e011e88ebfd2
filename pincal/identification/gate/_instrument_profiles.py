"""Typical accuracies of measuring instruments, to judge an estimated noise.

When a file declares no noise, the σ of each block is estimated from the residuals and
the reduced χ² is 1 by construction: a model error then shows only as a σ̂ larger
than the instrument can produce. The profiles below give an order of magnitude of the
1σ noise of common instruments over a machine-sized volume (about 1–2 m), as found in
manufacturers' specifications (maximum permissible errors of a few to some tens of µm
for laser trackers and CMMs, sub-millimetre for optical motion capture). They are
deliberately typical, not best-case: the gate refuses only when σ̂ exceeds
``GateLimits.noise_factor`` (default 3) times the profile's σ. Declare the actual noise
(``--noise``) when it is known; it is then judged by the χ² test instead.
"""

from __future__ import annotations

from dataclasses import dataclass

from pincal.errors import UnknownNameError

__all__ = ["INSTRUMENT_PROFILES", "InstrumentProfile", "instrument_profile"]


@dataclass(frozen=True)
class InstrumentProfile:
    """Typical 1σ noise of an instrument.

    Attributes:
        name: profile name (``laser-tracker``, ``motion-capture``…).
        position: typical 1σ of a measured coordinate [m].
        orientation: typical 1σ of a measured angle [rad] (NaN: does not measure
            orientation).
        description: what the profile stands for, in words.
    """

    name: str
    position: float
    orientation: float
    description: str


#: built-in profiles, by name
INSTRUMENT_PROFILES: dict[str, InstrumentProfile] = {
    p.name: p
    for p in (
        InstrumentProfile("laser-tracker", 20e-6, 50e-6, "laser tracker (6-DoF probe), ~1–2 m"),
        InstrumentProfile("motion-capture", 0.3e-3, 2e-3, "optical motion capture, ~2 m"),
        InstrumentProfile("ballbar", 1e-6, float("nan"), "telescopic ballbar (distance)"),
        InstrumentProfile("touch-probe", 2e-6, float("nan"), "touch probe on an artefact"),
        InstrumentProfile("cmm", 3e-6, 20e-6, "coordinate measuring machine"),
    )
}


def instrument_profile(name: str) -> InstrumentProfile:
    """The profile of that name (case and ``_``/``-`` insensitive).

    Raises:
        UnknownNameError: no such profile; the valid names are listed.
    """
    key = str(name).strip().lower().replace("_", "-").replace(" ", "-")
    if key not in INSTRUMENT_PROFILES:
        raise UnknownNameError("instrument profile", str(name), list(INSTRUMENT_PROFILES))
    return INSTRUMENT_PROFILES[key]

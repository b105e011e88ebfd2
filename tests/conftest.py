from __future__ import annotations

import numpy as np
import pytest

import pincal
from pincal.model import load_mechanism, parameters


@pytest.fixture(scope="session")
def stewart() -> pincal.Mechanism:
    return load_mechanism("stewart_6ups")


@pytest.fixture(scope="session")
def stewart42(stewart) -> pincal.ParameterSet:
    return parameters(stewart, "stewart42")


@pytest.fixture(scope="session")
def stewart_poses(stewart) -> np.ndarray:
    from pincal.model import sample_actuators

    return sample_actuators(stewart, 30, np.random.default_rng(11))


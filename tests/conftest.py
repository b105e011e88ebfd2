from __future__ import annotations

import os

# One BLAS thread per test process (before numpy loads; subprocesses inherit it): the
# suite's matrices are small, where OpenBLAS threads cost more CPU than they save, and
# `-n auto` (pytest-xdist) already gives each core a worker. Set it to override.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

import pincal  # noqa: E402
from pincal.model import load_mechanism, parameters  # noqa: E402


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


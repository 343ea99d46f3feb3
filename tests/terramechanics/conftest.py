"""Shared fixtures for the terramechanics tests: numpy warnings are errors here."""

import numpy as np
import pytest


@pytest.fixture(autouse=True)
def _numpy_raises():
    """Fail on any 0/0, division by zero, overflow or invalid value (underflow is benign)."""
    with np.errstate(divide="raise", over="raise", invalid="raise", under="ignore"):
        yield

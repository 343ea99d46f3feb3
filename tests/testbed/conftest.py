"""Test-bed data sets generated once per session by the virtual bed."""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipenv.terramechanics.models import force_model_by_name
from slipenv.terramechanics.presets import LUNAR_SIMULANT
from slipenv.testbed.bed import REINA_WHEEL, VirtualTestBed, write_trials

SLIPS = (0.05, 0.1, 0.2, 0.3, 0.45, 0.6)
ANGLES_DEG = (0.0, 5.0, 10.0, 15.0, 20.0, 25.0)
NOISE_N = 0.3  # [N] sensor noise added to each trial's mean force


class PeakedLaw:
    """A law none of slipenv's can make: a traction peak at about 15 % combined slip, then a
    fall (Pacejka's magic formula shape, F = mu W sin(1.9 atan(12 sigma))), split by
    direction like Reina Eq. 8-9; no resistance."""

    def scalar_kernel(self, soil):
        mu = float(soil.mu)

        def kernel(slip, tan_beta, load_n):
            sigma = math.hypot(slip, tan_beta)
            if sigma == 0.0 or load_n <= 0.0:
                return 0.0, 0.0, 0.0
            f = mu * load_n * math.sin(1.9 * math.atan(12.0 * sigma)) / sigma
            return slip * f, -tan_beta * f, 0.0
        return kernel

    def __call__(self, slip, tan_beta, load_n, soil):
        k = self.scalar_kernel(soil)
        out = np.array([k(s, t, w)[:2] for s, t, w in np.broadcast(slip, tan_beta, load_n)])
        return out[:, 0], out[:, 1]

    def resistance_n(self, load_n, soil):
        return np.zeros_like(np.asarray(load_n, dtype=float))


def _generate(model, directory):
    with VirtualTestBed(model, LUNAR_SIMULANT) as bed:
        trials = bed.sweep(SLIPS, ANGLES_DEG, convention="simulation")
    return write_trials(directory, trials, REINA_WHEEL, noise_n=NOISE_N, seed=3,
                        slip_angle_definition="simulation")


@pytest.fixture(scope="session")
def reina_bed_dir(tmp_path_factory):
    """Bed data from slipenv's Reina model on the lunar simulant (Reina Table 3)."""
    model = force_model_by_name("reina", REINA_WHEEL.geometry())
    return _generate(model, tmp_path_factory.mktemp("reina_bed"))


@pytest.fixture(scope="session")
def janosi_bed_dir(tmp_path_factory):
    model = force_model_by_name("janosi", REINA_WHEEL.geometry())
    return _generate(model, tmp_path_factory.mktemp("janosi_bed"))


@pytest.fixture(scope="session")
def peaked_bed_dir(tmp_path_factory):
    return _generate(PeakedLaw(), tmp_path_factory.mktemp("peaked_bed"))

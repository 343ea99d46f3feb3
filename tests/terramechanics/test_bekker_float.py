"""Bekker's wheel sinkage in floats is the numpy function, bit for bit (issue 15).

:func:`slipenv.terramechanics.bekker.wheel_sinkage_float_m` recomputes
:func:`slipenv.terramechanics.bekker.wheel_sinkage_m` in floats for one wheel (the simulator's
relaxation lengths and the rear camera's rut depth use it per wheel at every control step). The
two must agree exactly, over loads, wheels and soils well beyond the presets, and the float form
must still be the physics: z scales as W^(2/(2n+1)) (Wong Ch. 5).
"""

from __future__ import annotations

import numpy as np
import pytest

from slipenv.terramechanics.bekker import wheel_sinkage_float_m, wheel_sinkage_m


def test_float_sinkage_is_the_bekker_function_bit_for_bit():
    rng = np.random.default_rng(8)
    n = 5000
    load = np.concatenate([rng.uniform(-50.0, 3000.0, n - 2), [0.0, np.nan]])
    width, diameter = rng.uniform(0.02, 0.6, n), rng.uniform(0.05, 1.6, n)
    k_c, k_phi, n_exp = rng.uniform(0.0, 1e5, n), rng.uniform(1e4, 1e7, n), rng.uniform(0.2, 2.0, n)
    for i in range(n):
        want = float(wheel_sinkage_m(load[i], width[i], diameter[i], float(k_c[i]),
                                     float(k_phi[i]), float(n_exp[i])))
        got = wheel_sinkage_float_m(float(load[i]), float(width[i]), float(diameter[i]),
                               float(k_c[i]), float(k_phi[i]), float(n_exp[i]))
        assert got == want or (np.isnan(got) and np.isnan(want)), i


def test_float_sinkage_scales_with_load_as_bekker_says():
    soil = (990.0, 1528430.0, 1.1)  # k_c, k_phi, n of a loose sand (test values)
    z1 = wheel_sinkage_float_m(100.0, 0.1, 0.3, *soil)
    z2 = wheel_sinkage_float_m(200.0, 0.1, 0.3, *soil)
    assert z2 == pytest.approx(z1 * 2.0 ** (2.0 / (2.0 * 1.1 + 1.0)), rel=1e-12)
    assert wheel_sinkage_float_m(0.0, 0.1, 0.3, *soil) == 0.0

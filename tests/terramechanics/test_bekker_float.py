"""Bekker's wheel sinkage of one wheel in floats (the simulator's relaxation lengths and the
rear camera's rut depth use it per wheel at every control step) is the physics: z scales as
W^(2/(2n+1)) (Wong Ch. 5), and its array form is the same function element by element.
"""

from __future__ import annotations

import numpy as np
import pytest

from slipenv.terramechanics.bekker import wheel_sinkage_float_m, wheel_sinkage_m


def test_float_sinkage_scales_with_load_as_bekker_says():
    soil = (990.0, 1528430.0, 1.1)  # k_c, k_phi, n of a loose sand (test values)
    z1 = wheel_sinkage_float_m(100.0, 0.1, 0.3, *soil)
    z2 = wheel_sinkage_float_m(200.0, 0.1, 0.3, *soil)
    assert z2 == pytest.approx(z1 * 2.0 ** (2.0 / (2.0 * 1.1 + 1.0)), rel=1e-12)
    assert wheel_sinkage_float_m(0.0, 0.1, 0.3, *soil) == 0.0
    assert wheel_sinkage_float_m(-5.0, 0.1, 0.3, *soil) == 0.0  # no contact, no rut


def test_array_sinkage_is_the_float_sinkage_element_by_element():
    soil = (990.0, 1528430.0, 1.1)
    loads = np.array([0.0, 50.0, 400.0])
    z = wheel_sinkage_m(loads, 0.1, 0.3, *soil)
    assert z.tolist() == [wheel_sinkage_float_m(w, 0.1, 0.3, *soil) for w in loads.tolist()]

"""Array versions derived from the scalar laws: broadcasting, keywords, soils per element."""

from __future__ import annotations

import numpy as np
import pytest

from slipenv.terramechanics import (
    CONCRETE,
    LOOSE_SAND,
    LUNAR_SIMULANT,
    ContactGeometry,
    JanosiForceModel,
    SoilParams,
)
from slipenv.terramechanics.janosi import janosi_forces
from slipenv.terramechanics.vectorize import array_law, forces_on_arrays

WHEEL = ContactGeometry(radius_m=0.092, width_m=0.11, contact_length_m=0.06)


def _law(a: float, b: float, c: float = 2.0) -> tuple[float, float]:
    return a * b + c, a - b


def test_array_law_broadcasts_and_returns_float_arrays_of_the_broadcast_shape():
    fn = array_law(_law, n_out=2)
    p, q = fn(np.arange(3.0)[:, None], np.arange(4))
    assert p.shape == q.shape == (3, 4) and p.dtype == q.dtype == np.float64
    np.testing.assert_array_equal(p, np.arange(3.0)[:, None] * np.arange(4) + 2.0)
    np.testing.assert_array_equal(q, np.arange(3.0)[:, None] - np.arange(4))


def test_array_law_gives_0d_arrays_for_scalars_and_accepts_keywords_and_defaults():
    fn = array_law(_law, n_out=2)
    p, q = fn(1.5, b=2.0)
    assert p.shape == () and float(p) == 5.0 and float(q) == -0.5
    assert float(fn(1.0, 1.0, c=0.0)[0]) == 1.0
    with pytest.raises(TypeError):
        fn(1.0, 2.0, d=3.0)


def test_array_law_keeps_the_given_name_and_doc():
    fn = array_law(_law, n_out=2, name="law_n", doc="On arrays.")
    assert fn.__name__ == "law_n" and fn.__doc__ == "On arrays."
    assert array_law(janosi_forces, 2).__doc__ == janosi_forces.__doc__


def test_array_law_equals_the_scalar_law_element_by_element():
    rng = np.random.default_rng(3)
    s, tb, w = rng.uniform(-1, 1, 50), rng.uniform(-1, 1, 50), rng.uniform(1, 500, 50)
    fx, fy = array_law(janosi_forces, 2)(s, tb, w, 12.0, 0.6, 3.0)
    for i in range(50):
        assert (fx[i], fy[i]) == janosi_forces(s[i], tb[i], w[i], 12.0, 0.6, 3.0)


def test_forces_on_arrays_builds_one_kernel_per_distinct_soil():
    model = JanosiForceModel(WHEEL)
    built: list[SoilParams] = []

    def kernel_of(soil: SoilParams):
        built.append(soil)
        return model.scalar_kernel(soil)

    soils = [LOOSE_SAND.params(), CONCRETE.params(), LOOSE_SAND.params(), CONCRETE.params()]
    stacked = SoilParams(*np.array(soils).T)
    s, tb, w = np.array([0.1, 0.2, 0.3, 0.4]), np.full(4, 0.05), np.full(4, 80.0)
    fx, fy, res = forces_on_arrays(kernel_of, s, tb, w, stacked)
    assert len(built) == 2
    for i, soil in enumerate(soils):
        assert (fx[i], fy[i], res[i]) == model.scalar_kernel(soil)(s[i], tb[i], w[i])


def test_forces_on_arrays_counts_negative_loads_as_no_contact():
    model = JanosiForceModel(WHEEL)
    fx, fy, res = forces_on_arrays(model.scalar_kernel, 0.3, 0.1, np.array([-5.0, 0.0]),
                                   LUNAR_SIMULANT.params())
    np.testing.assert_array_equal(np.concatenate([fx, fy, res]), 0.0)

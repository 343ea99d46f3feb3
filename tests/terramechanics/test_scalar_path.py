"""The per-wheel float kernel and the array interface derived from it agree to 1e-12."""

from __future__ import annotations

import numpy as np
import pytest

from slipenv.terramechanics.contact import ContactGeometry
from slipenv.terramechanics.models import FORCE_MODELS
from slipenv.terramechanics.presets import SOILS

GEOMETRIES = {
    "wheel": ContactGeometry(radius_m=0.1651, width_m=0.1143, contact_length_m=0.1),
    "track": ContactGeometry(radius_m=0.06, width_m=0.11, contact_length_m=0.12,
                             track_length_m=0.6),
}


@pytest.mark.parametrize("model_name", sorted(FORCE_MODELS))
@pytest.mark.parametrize("soil_name", sorted(SOILS))
@pytest.mark.parametrize("geometry", sorted(GEOMETRIES))
def test_scalar_path_matches_the_vectorised_law(model_name, soil_name, geometry):
    model = FORCE_MODELS[model_name](GEOMETRIES[geometry])
    soil = SOILS[soil_name].params()
    rng = np.random.default_rng(7)
    slip = np.concatenate([[0.0, 1e-7, -1e-7, 1.0, -1.0], rng.uniform(-1, 1, 200)])
    tan_beta = np.concatenate([[0.0, 0.0, 1e-7, 0.0, 1.0], rng.uniform(-1, 1, 200)])
    load = np.concatenate([[50.0, 1.0, 500.0, 2000.0, 80.0], rng.uniform(1.0, 3000.0, 200)])
    fx, fy = model(slip, tan_beta, load, soil)
    res = model.resistance_n(load, soil)
    for i in range(len(slip)):
        sx, sy, sr = model.scalar(float(slip[i]), float(tan_beta[i]), float(load[i]), soil)
        assert sx == pytest.approx(fx[i], rel=1e-12, abs=1e-12)
        assert sy == pytest.approx(fy[i], rel=1e-12, abs=1e-12)
        assert sr == pytest.approx(res[i], rel=1e-12, abs=1e-12)


def test_reina_scalar_path_without_load_scaling_matches():
    model = FORCE_MODELS["reina"](GEOMETRIES["wheel"], scale_stiffness_with_load=False)
    soil = SOILS["lunar_simulant"].params()
    for s, tb, w in [(0.1, 0.0, 64.7), (-0.3, 0.2, 10.0), (0.9, -0.8, 300.0)]:
        fx, fy = model(np.array([s]), np.array([tb]), np.array([w]), soil)
        sx, sy, _ = model.scalar(s, tb, w, soil)
        assert sx == pytest.approx(fx[0], rel=1e-12) and sy == pytest.approx(fy[0], rel=1e-12)

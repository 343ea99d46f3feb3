"""The Lindgren EKF reproduces its frozen reference outputs (issue 15, item 3).

``data/lindgren_reference.npz`` was written by ``data/make_lindgren_reference.py`` with the
implementation from before the filter was restructured for speed: one FarmField episode's sensor
frames (with a few readings removed and a clutter bearing added) run through schemes 1-4 and the
oracle variant. The restructured filter must give the same state and covariance after every
frame to 1e-12 (relative to each entry's largest magnitude in the run, at least 1), and skip and
accept the same measurements: the numpy filter and the compiled kernel (``_ekf.c``) alike.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from slipenv.estimators.base import OdometryGeometry
from slipenv.estimators.lindgren import LindgrenEKF, LindgrenNoise, OracleSoil
from slipenv.estimators.lindgren.ekf import compiled_available
from tests.estimators.data.make_lindgren_reference import VARIANTS, unpack_frames

DATA = Path(__file__).with_name("data") / "lindgren_reference.npz"
KERNELS = [False, pytest.param(True, marks=pytest.mark.skipif(not compiled_available(), reason=(
    "the compiled EKF kernel (estimators/lindgren/_ekf.c) was not built: `pip install -e .` "
    "builds it; the numpy reference is tested without it")))]


@pytest.fixture(scope="module")
def reference():
    with np.load(DATA) as d:
        return {k: d[k] for k in d.files}


def _filter(variant: str, ref: dict, compiled: bool | None = None) -> LindgrenEKF:
    r, w, cpr = ref["geometry"]
    geometry = OdometryGeometry(float(r), float(w), float(cpr),
                                tuple(int(i) for i in ref["geometry_left"]),
                                tuple(int(i) for i in ref["geometry_right"]))
    params = LindgrenNoise(k_s0=float(ref["k_s0"]))
    if variant == "oracle":
        soil = OracleSoil((0.99 * geometry.wheel_radius_m, 1.01 * geometry.wheel_radius_m),
                          (1.2 * params.k_s0, 0.9 * params.k_s0))
        return LindgrenEKF(geometry, 4, params, ref["beacons_xy"], oracle=soil,
                           compiled=compiled)
    return LindgrenEKF(geometry, int(variant[1]), params, ref["beacons_xy"], compiled=compiled)


@pytest.mark.parametrize("compiled", KERNELS)
@pytest.mark.parametrize("variant", VARIANTS)
def test_lindgren_ekf_matches_frozen_reference_states_and_covariances(reference, variant,
                                                                      compiled):
    frames = unpack_frames(reference)
    ekf = _filter(variant, reference, compiled)
    assert ekf.compiled == compiled
    ekf.reset(*(float(v) for v in reference["pose0"]), frames[0])
    xs, Ps = [ekf.x.copy()], [ekf.P.copy()]
    for frame in frames[1:]:
        ekf.update(frame)
        xs.append(ekf.x.copy())
        Ps.append(ekf.P.copy())
    x_ref, P_ref = reference[f"{variant}_x"], reference[f"{variant}_P"]
    assert len(xs) == len(x_ref) > 50
    # 1e-12 relative to each entry's scale over the run, max(1, max_k |value_k|): k_s is ~700
    # and its variance falls from ~1e5 to ~30 in one update, so its rounding is relative to the
    # prior's 1e5, and an absolute 1e-12 would ask for better than the last bit of a double
    x_err = np.abs(np.array(xs) - x_ref) / np.maximum(np.abs(x_ref).max(axis=0), 1.0)
    P_err = np.abs(np.array(Ps) - P_ref) / np.maximum(np.abs(P_ref).max(axis=0), 1.0)
    assert x_err.max() <= 1e-12, f"state differs by {x_err.max():.2e} (relative)"
    assert P_err.max() <= 1e-12, f"covariance differs by {P_err.max():.2e} (relative)"
    assert repr(sorted(ekf.skipped.items())) == str(reference[f"{variant}_skipped"])
    hist = {k: len(v) for k, v in ekf.history.items()}
    assert repr(sorted(hist.items())) == str(reference[f"{variant}_history"])


@pytest.mark.parametrize("scheme", [3, 4])
def test_inlined_process_model_equals_the_plain_functions_bit_for_bit(reference, scheme):
    """The filter's inlined prediction is models.process_fx/process_F/process_Q, exactly."""
    from slipenv.contracts import wrap_angle
    from slipenv.estimators.lindgren import models as lm

    ekf = _filter(f"s{scheme}", reference, compiled=False)
    rng = np.random.default_rng(7)
    p = ekf.params
    for _ in range(50):
        x = rng.normal(0.0, 1.0, ekf.n)
        x[lm.ITH] = rng.uniform(-3.0, 3.0)
        if ekf.n == lm.N_SLIP:
            x[lm.IKL:] = rng.uniform(100.0, 3000.0, 2)
        tau = float(rng.uniform(1e-3, 0.1))
        ekf.x = x
        xp, F, Q = ekf._process(tau)
        fx = lm.process_fx(x, tau)
        fx[lm.ITH] = wrap_angle(fx[lm.ITH])
        np.testing.assert_array_equal(xp, fx)
        np.testing.assert_array_equal(F, lm.process_F(x, tau))
        np.testing.assert_array_equal(Q, lm.process_Q(x, tau, p.jerk_psd_v, p.jerk_psd_omega,
                                                      p.tilt_psd, p.radius_var_per_m,
                                                      p.k_s_rel_var_per_m))

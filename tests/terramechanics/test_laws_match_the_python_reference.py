"""The C laws (``_laws.h``, through the Python API that binds them) agree with an independent
Python transcription of the same equations (`reference_laws`), over inputs well beyond the
presets.

Tolerance: relative 1e-12 (absolute 1e-12 N, or 1e-12 of the inputs' scale, near zero). The
two differ only in rounding (C's ``hypot`` against Python's own, the order of a few products),
a few ulps; a wrong sign, factor or term is off by far more than 1e-12.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipenv.terramechanics import _laws, bekker, sidewall, slip_dynamics
from slipenv.terramechanics.contact import ContactGeometry
from slipenv.terramechanics.models import (
    JanosiForceModel,
    KernelConstants,
    LinearSlipForceModel,
    ReinaForceModel,
    wheel_kernel,
)
from slipenv.terramechanics.presets import SOILS
from tests.terramechanics import reference_laws as ref

REL = 1e-12
N = 400
WHEEL = ContactGeometry(radius_m=0.165, width_m=0.1, contact_length_m=0.08)
MODELS = [
    JanosiForceModel(WHEEL), JanosiForceModel(WHEEL, lateral_stiffness_ratio=3.6),
    LinearSlipForceModel(WHEEL), LinearSlipForceModel(WHEEL, lateral_stiffness_ratio=0.5),
    ReinaForceModel(WHEEL), ReinaForceModel(WHEEL, scale_stiffness_with_load=False),
    ReinaForceModel(WHEEL, compaction=True),
    ReinaForceModel(WHEEL, scale_stiffness_with_load=False, compaction=True),
    JanosiForceModel(WHEEL, slip_sinkage="full"), LinearSlipForceModel(WHEEL,
                                                                      slip_sinkage="bulldozing"),
    ReinaForceModel(WHEEL, slip_sinkage="bulldozing"),
    ReinaForceModel(WHEEL, compaction=True, slip_sinkage="full", soil_unit_weight_n_m3=2e4),
    ReinaForceModel(WHEEL, slip_sinkage="accumulated"),
    JanosiForceModel(WHEEL, slip_sinkage="accumulated", excavation_depth_m=5e-3),
]


def close(got, want, scale: float = 1.0) -> bool:
    """Every value of ``got`` within REL of ``want`` (or REL * scale near zero)."""
    got, want = np.ravel(np.asarray(got, dtype=float)), np.ravel(np.asarray(want, dtype=float))
    return bool(np.all(np.abs(got - want) <= REL * np.maximum(np.abs(want), scale)))


@pytest.fixture
def rng():
    return np.random.default_rng(20)


@pytest.mark.parametrize("model", MODELS, ids=repr)
@pytest.mark.parametrize("soil_name", sorted(SOILS))
def test_each_models_c_kernel_is_the_reference_force_law(model, soil_name, rng):
    soil = SOILS[soil_name].params()
    constants = model.kernel_constants(soil)
    assert isinstance(constants, KernelConstants)
    kernel = wheel_kernel(model, soil)
    slips = np.concatenate([rng.uniform(-1.0, 1.0, N), [0.0, 1e-9, -1e-7, 1.0, -1.0]])
    tans = np.concatenate([rng.uniform(-1.0, 1.0, N), [0.0, 0.0, 1e-8, 1.0, -0.3]])
    loads = np.concatenate([rng.uniform(0.0, 3000.0, N), [0.0, -5.0, 1e-6, 60.0, 900.0]])
    for s, t, w in zip(slips.tolist(), tans.tolist(), loads.tolist(), strict=True):
        if w < 0.0:
            continue  # the kernel expects W >= 0 (the array interface clamps)
        want = ref.kernel(tuple(constants), s, t, w)
        assert close(kernel(s, t, w), want, scale=1.0 + w), (s, t, w)


@pytest.mark.parametrize("forward_reference", [False, True])
def test_relax_slip_is_the_reference_backward_euler_step(rng, forward_reference):
    low_speed = [(0.3, -0.2, 0.0, 0.0, 0.0, 2.0), (0.0, 0.4, 1.0, 0.0, 0.0, 2.0),
                 (0.0, 0.0, 0.0, 0.0, -0.5, 2.0), (0.9, 0.9, 1e-9, 1e-12, 1e-300, 2.0)]
    draws = [(*rng.uniform(-1.0, 1.0, 2), *rng.uniform(-5.0, 5.0, 3), rng.uniform(0.0, 50.0))
             for _ in range(N)]
    for args in [(*a, forward_reference) for a in low_speed + draws]:
        assert close(slip_dynamics.relax_slip(*args), ref.relax_slip(*args)), args


def test_dampers_are_the_reference_dampers(rng):
    for _ in range(N):
        change, v_ref, d, fade = rng.uniform(-0.1, 0.1), *rng.uniform(0.0, 2.0, 3)
        fade += 0.01
        assert close(slip_dynamics.lateral_soil_damping_n(change, v_ref, d, fade),
                     ref.lateral_soil_damping_n(change, v_ref, d, fade))
        rim, v, c, low = *rng.uniform(-0.1, 0.1, 2), rng.uniform(0.0, 500.0), 0.02
        v_ref = max(abs(rim), abs(v))
        assert close(slip_dynamics.longitudinal_soil_damping_n(rim, v, v_ref, c, low),
                     ref.longitudinal_soil_damping_n(rim, v, v_ref, c, low))
        k, sigma, m, zeta, cap = *rng.uniform(0.0, 1e5, 1), *rng.uniform(0.01, 50.0, 3), 1e3
        assert close(slip_dynamics.critical_damping_ns_per_m(k, sigma, m, zeta, cap),
                     ref.critical_damping_ns_per_m(k, sigma, m, zeta, cap))


def test_resistance_elements_are_the_reference_elements(rng):
    for _ in range(N):
        res, state, v = rng.uniform(0.0, 300.0), rng.uniform(-1.0, 1.0), rng.uniform(-1.0, 1.0)
        dt, stick, c = 1e-3, rng.uniform(1e-4, 1e-2), rng.uniform(0.0, 500.0)
        assert close(slip_dynamics.rut_resistance_n(res, state, v * dt, v, stick, c),
                     ref.rut_resistance_n(res, state, v * dt, v, stick, c), scale=res)
        u = tuple(rng.uniform(-0.6, 0.6, 3).tolist())
        vel = tuple(rng.uniform(-1.0, 1.0, 3).tolist())
        got = slip_dynamics.rut_resistance_vector_n(res, u, vel, dt, stick, c)
        want = ref.rut_resistance_vector_n(res, u, vel, dt, stick, c)
        assert close(got[0], want[0], scale=res) and close(got[1], want[1])


def test_bekker_float_laws_are_the_reference_laws(rng):
    for _ in range(N):
        w, b, d = rng.uniform(-50.0, 3000.0), rng.uniform(0.02, 0.6), rng.uniform(0.05, 1.6)
        k_c, k_phi, n = rng.uniform(0.0, 1e5), rng.uniform(1e4, 1e7), rng.uniform(0.2, 2.0)
        assert close(bekker.wheel_sinkage_float_m(w, b, d, k_c, k_phi, n),
                     ref.wheel_sinkage_m(w, b, d, k_c, k_phi, n), scale=1e-3)
        b2, d2 = rng.uniform(0.02, 0.6), rng.uniform(0.05, 1.6)
        assert close(bekker.rut_load_ratio(b, d, b2, d2, k_c, k_phi),
                     ref.rut_load_ratio(b, d, b2, d2, k_c, k_phi))
        r1, r2 = rng.uniform(0.0, 200.0, 2)
        assert close(bekker.rut_following_compaction_n(r1, r2),
                     ref.rut_following_compaction_n(r1, r2), scale=200.0)


def test_multi_pass_resistance_is_the_reference_composition(rng):
    from slipenv.terramechanics import _laws

    for _ in range(N):
        load, lead_load = rng.uniform(0.0, 3000.0, 2)
        f_r, gamma, e = rng.uniform(0.0, 0.05), rng.uniform(0.0, 2.0), rng.uniform(1.1, 1.6)
        res = ref.motion_resistance_n(load, f_r, gamma, e)
        lead = ref.motion_resistance_n(lead_load, f_r, gamma, e)
        assert close(_laws.motion_resistance_n(load, f_r, gamma, e), res)
        assert close(_laws.multi_pass_resistance_n(res, load, lead, lead_load, f_r),
                     ref.multi_pass_resistance_n(res, load, lead, lead_load, f_r), scale=res)


def test_contact_frame_is_the_reference_frame(rng):
    from slipenv.terramechanics import _laws

    for _ in range(N):
        load = rng.uniform(1.0, 2000.0)
        normal = np.array([0.0, 0.0, 1.0]) + rng.uniform(-0.3, 0.3, 3)
        patch = (*(load * rng.uniform(-1.0, 1.0, 3)), *(load * normal))
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        centre, v, omega = rng.uniform(-1.0, 1.0, 3), rng.uniform(-2, 2, 3), rng.uniform(-9, 9, 3)
        args = ([float(x) for x in patch], load, q.tolist(), centre.tolist(), v.tolist(),
                omega.tolist())
        got, want = _laws.contact_frame(*args), ref.contact_frame(*args)
        flat = [x for part in got for x in np.ravel(part)]
        assert close(flat, [x for part in want for x in np.ravel(part)], scale=10.0)


def test_a_subclass_that_changes_the_law_keeps_its_own_python_kernel():
    class Doubled(JanosiForceModel):
        def _forces(self, soil):
            inner = super()._forces(soil)
            return lambda s, t, w: tuple(2.0 * f for f in inner(s, t, w))

    soil = SOILS["loose_sand"].params()
    assert Doubled(WHEEL).kernel_constants(soil) is None
    fx, fy, res = wheel_kernel(Doubled(WHEEL), soil)(0.2, 0.1, 300.0)
    fx1, fy1, res1 = wheel_kernel(JanosiForceModel(WHEEL), soil)(0.2, 0.1, 300.0)
    assert (fx, fy) == (2.0 * fx1, 2.0 * fy1) and res == res1
    assert math.isfinite(fx)


def test_slip_sinkage_and_bulldozing_laws_are_the_reference_laws(rng):
    for _ in range(N):
        slip = rng.uniform(-1.5, 1.5)
        assert close(bekker.slip_sinkage_factor(slip), ref.slip_sinkage_factor(slip))
        phi, c, gamma = rng.uniform(0.0, 1.2), rng.uniform(0.0, 2e4), rng.uniform(0.0, 2.5e4)
        h = rng.uniform(-0.05, 0.3)
        assert close(sidewall.bulldozing_coefficients(phi), ref.bulldozing_coefficients(phi))
        assert close(sidewall.bulldozing_resistance_n_per_m(h, c, phi, gamma),
                     ref.bulldozing_resistance_n_per_m(h, c, phi, gamma), scale=1e-3)
        rc0, n, z0, b = rng.uniform(0.0, 500.0), rng.uniform(0.2, 2.0), *rng.uniform(0.0, 0.2, 2)
        args = (slip, rc0, n, z0, b, c, phi, gamma)
        assert close(_laws.slip_sinkage_resistance_n(*args), ref.slip_sinkage_resistance_n(*args),
                     scale=1e-3)


def test_slip_sinkage_state_laws_are_the_reference_laws(rng):
    """The dug-depth step, the resistance of a dug depth and the loop's per-substep state of
    a bound model (``laws_kernel_sinkage_state``) against their transcriptions."""
    for _ in range(N):
        phi, c, gamma = rng.uniform(0.0, 1.2), rng.uniform(0.0, 2e4), rng.uniform(0.0, 2.5e4)
        rc0, n, z0, b = rng.uniform(0.0, 500.0), rng.uniform(0.2, 2.0), *rng.uniform(0.0, 0.2, 2)
        dug = rng.uniform(-0.01, 0.3)
        args = (dug, rc0, n, z0, b, c, phi, gamma)
        assert close(_laws.dug_resistance_n(*args), ref.dug_resistance_n(*args), scale=1e-3)
        rim, v = rng.uniform(-3.0, 3.0, 2)
        if rng.uniform() < 0.2:
            rim = v * rng.choice([0.0, 1.0])  # locked, or rolling without slip
        h, delta, cap = rng.uniform(0.0, 0.5), rng.uniform(0.0, 0.01), rng.uniform(-0.01, 0.2)
        step = (dug, rim, v, h, delta, cap)
        assert close(_laws.slip_sinkage_step(*step), ref.slip_sinkage_step(*step), scale=1e-3)
    for model in MODELS:
        for soil_name in sorted(SOILS):
            constants = tuple(model.kernel_constants(SOILS[soil_name].params()))
            for _ in range(20):
                dug, rim, v = rng.uniform(0.0, 0.1), *rng.uniform(-2.0, 2.0, 2)
                h, load = rng.uniform(0.0, 0.3), rng.uniform(-10.0, 2000.0)
                got = _laws.kernel_sinkage_state(constants, dug, rim, v, h, load)
                want = ref.kernel_sinkage_state(constants, dug, rim, v, h, load)
                assert close(got, want, scale=1e-3)

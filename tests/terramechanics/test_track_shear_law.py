"""The track model's decoupled shear law (Ishigami, Miwa, Nagatani & Yoshida, J. Field Robotics
24(3) (2007)) against its closed forms, and against the default resultant law (Wong & Chiang
2001) where the two must agree."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from slipenv.envs.factory import make_force_model, make_soil_map, make_vehicle
from slipenv.sim.simulator import Simulator
from slipenv.sim.track_soil import TrackModelParams
from slipenv.terrain.terrain import TerrainSpec
from slipenv.terramechanics.presets import CONCRETE, DRY_SAND
from slipenv.terramechanics.track import (
    SHEAR_LAWS,
    cell_forces,
    decoupled_cells,
    decoupled_stress_pa,
    soil_damper_forces,
    steady_track_forces,
    track_substep,
)
from slipenv.vehicles.presets import tracked_patako_wong_chiang
from slipenv.vehicles.spec import TRACK_SHEAR_LAWS
from tests.sim.conftest import drive, hold
from tests.terramechanics.test_track import (
    B_W,
    DT,
    DX,
    E_MAX,
    TAN_PHI,
    C,
    K,
    L,
    N,
    P,
    soil,
    steady_turn,
)
from tests.terramechanics.test_track_compiled import _inputs


def _cells(jx, jy, pressure, decoupled, e=None, lateral=False):
    """Forces and stiffness of one-cell tracks with cell displacement (jx, jy) (both faces),
    the direction state along the displacement unless given; with ``lateral`` also the
    decoupled law's lateral stiffness."""
    jx, jy = np.asarray(jx, float), np.asarray(jy, float)
    n_t = jx.size
    j = np.zeros((2, n_t, 2))
    j[0], j[1] = jx.reshape(n_t, 1), jy.reshape(n_t, 1)
    if e is None:
        e = np.stack((jx, jy)).reshape(2, n_t, 1) * 1.0
    b, c, tan_phi, k_mod = soil(n_t)
    pressure = np.broadcast_to(np.asarray(pressure, float).reshape(-1, 1), (n_t, 1)).copy()
    ky = np.full((n_t, 1), np.nan)
    flags = np.full(n_t, decoupled)
    (fx, fy), k = cell_forces(j, e, pressure, b, DX, c, tan_phi, k_mod, None, flags, ky)
    if lateral:
        return fx[:, 0], fy[:, 0], k[:, 0], ky[:, 0]
    return fx[:, 0], fy[:, 0], k[:, 0]


def _janosi_force(j, pressure):
    """The 1-D closed form tau_max (1 - e^{-|j|/K}) b dx, against j (Wong Eqs. 2.54, 2.56)."""
    return -np.sign(j) * (C + pressure * TAN_PHI) * (1.0 - np.exp(-np.abs(j) / K)) * B_W * DX


@pytest.mark.parametrize("axis", [0, 1])
def test_pure_longitudinal_or_lateral_displacement_gives_both_laws_the_janosi_stress(axis):
    j = np.array([-0.08, -0.01, -1e-4, 2e-4, 0.005, 0.03, 0.2])
    pressure = np.linspace(500.0, 6000.0, j.size)
    zero = np.zeros_like(j)
    jx, jy = (j, zero) if axis == 0 else (zero, j)
    want = _janosi_force(j, pressure)
    for decoupled in (False, True):
        f = _cells(jx, jy, pressure, decoupled)
        np.testing.assert_allclose(f[axis], want, rtol=1e-12)
        assert not f[1 - axis].any()


def test_combined_displacement_components_are_their_own_janosi_laws_capped_at_the_strength():
    rng = np.random.default_rng(5)
    jx = rng.normal(0.0, 2.0 * K, 400)
    jy = rng.normal(0.0, 2.0 * K, 400)
    pressure = rng.uniform(300.0, 6000.0, 400)
    fx, fy, _ = _cells(jx, jy, pressure, True)
    free_x, free_y = _janosi_force(jx, pressure), _janosi_force(jy, pressure)
    limit = (C + pressure * TAN_PHI) * B_W * DX
    cap = np.minimum(1.0, limit / np.hypot(free_x, free_y))
    np.testing.assert_allclose(fx, free_x * cap, rtol=1e-9)
    np.testing.assert_allclose(fy, free_y * cap, rtol=1e-9)
    assert (np.hypot(fx, fy) <= limit * (1.0 + 1e-12)).all()  # Mohr-Coulomb everywhere
    assert (cap < 1.0).sum() > 50 and (cap == 1.0).sum() > 50  # both sides of the cap


def test_a_track_sliding_sideways_keeps_the_longitudinal_stress_of_its_longitudinal_slip():
    """j = (K, 10 K): the resultant law directs the saturated stress along j, leaving
    tau_max/sqrt(101) longitudinally; the decoupled law gives tau_max (1 - e^{-1}) before
    the cap, tau_max (1 - e^{-1})/|(1 - e^{-1}, 1 - e^{-10})| after it."""
    jx, jy = np.array([K]), np.array([10.0 * K])
    tau_max_force = (C + P * TAN_PHI) * B_W * DX
    fx_res, _, _ = _cells(jx, jy, P, False)
    fx_dec, fy_dec, _ = _cells(jx, jy, P, True)
    gx, gy = 1.0 - math.exp(-1.0), 1.0 - math.exp(-10.0)
    assert fx_dec[0] == pytest.approx(-tau_max_force * gx / math.hypot(gx, gy), rel=1e-12)
    tau_res = 1.0 - math.exp(-math.sqrt(101.0))  # saturated at |j| = 10.05 K
    assert fx_res[0] == pytest.approx(-tau_max_force * tau_res / math.sqrt(101.0), rel=1e-9)
    assert fx_dec[0] < 5.0 * fx_res[0]  # over five times the longitudinal resistance


def test_the_decoupled_stress_opposes_the_displacement_whatever_the_direction_state():
    jx, jy = np.array([0.01, -0.02]), np.array([-0.003, 0.04])
    e = np.array([[[1.0], [1.0]], [[1.0], [-1.0]]])  # unrelated to j
    fx, fy, _ = _cells(jx, jy, P, True, e=e)
    fx_own, fy_own, _ = _cells(jx, jy, P, True)
    np.testing.assert_array_equal(fx, fx_own)
    np.testing.assert_array_equal(fy, fy_own)
    assert (np.sign(fx) == -np.sign(jx)).all() and (np.sign(fy) == -np.sign(jy)).all()


def test_each_decoupled_stiffness_is_its_components_derivative_by_its_own_displacement():
    """k_x = b dx d tau_x/d j_x and k_y = b dx d tau_y/d j_y against central differences of the
    cell force, below the Mohr-Coulomb cap (tau_max e^{-|j|/K}/K per component) and on it."""
    jx = np.array([0.0, 1e-3, 0.01, -0.02, 0.002, 0.01, 0.08, -0.05, 0.3])
    jy = np.array([0.0, 2e-3, -0.004, 0.03, 0.0, 0.05, 0.09, 0.02, -0.01])
    pressure = np.array([2800.0, 500.0, 2800.0, 6000.0, 1500.0, 2800.0, 2800.0, 900.0, 4000.0])
    fx, fy, kx, ky = _cells(jx, jy, pressure, True, lateral=True)
    strength = (C + pressure * TAN_PHI) * B_W * DX
    capped = np.hypot(_janosi_force(jx, pressure), _janosi_force(jy, pressure)) > strength
    assert capped[-3:].all() and not capped[:-4].any()
    free = ~capped
    np.testing.assert_allclose(kx[free], strength[free] * np.exp(-np.abs(jx[free]) / K) / K,
                               rtol=1e-12)
    np.testing.assert_allclose(ky[free], strength[free] * np.exp(-np.abs(jy[free]) / K) / K,
                               rtol=1e-12)
    assert kx[0] == ky[0] == pytest.approx(strength[0] / K, rel=1e-12)
    h = 1e-8
    slope_x = -(_cells(jx + h, jy, pressure, True)[0] - _cells(jx - h, jy, pressure, True)[0])
    slope_y = -(_cells(jx, jy + h, pressure, True)[1] - _cells(jx, jy - h, pressure, True)[1])
    rounding = 1e-6 * strength / K  # the differences' rounding, far below the stiffnesses
    np.testing.assert_allclose(kx, slope_x / (2 * h), rtol=1e-5, atol=rounding.max())
    np.testing.assert_allclose(ky, slope_y / (2 * h), rtol=1e-5, atol=rounding.max())
    # on the cap the other component holds the strength's share: stiffer than 0, softer than free
    assert (kx[capped] > 0.0).all() and (ky[capped] > 0.0).all()
    assert (kx[capped] < strength[capped] * np.exp(-np.abs(jx[capped]) / K) / K).all()


def test_decoupled_dampers_damp_each_component_with_its_own_stiffness_and_only_dissipate():
    """Per component, critical damping 2 sqrt(k m) of that component's own spring (capped at
    half the explicit limit m/dt): a cell with a stiff x and a saturated y spring is damped
    along x only, whatever the stress direction."""
    rng = np.random.default_rng(11)
    f_shear = rng.normal(size=(2, 2, N)) * 5.0
    kx = rng.uniform(0.0, 2e4, size=(2, N))
    ky = rng.uniform(0.0, 2e4, size=(2, N))
    ky[0, :3] = 0.0  # saturated lateral springs
    dj = rng.normal(size=(2, 2, N)) * 1e-5
    m = 0.8
    args = (E_MAX, 1.0, m, DT)
    assert not soil_damper_forces(np.zeros_like(dj), f_shear, kx, *args, ky).any()
    f = soil_damper_forces(dj, f_shear, kx, *args, ky)
    assert ((f * dj).sum(axis=0) <= 0.0).all() and ((f * dj).sum(axis=0) < 0.0).any()
    cx = np.minimum(2.0 * np.sqrt(kx * m), 0.5 * m / DT)
    cy = np.minimum(2.0 * np.sqrt(ky * m), 0.5 * m / DT)
    np.testing.assert_allclose(f[0], -cx / DT * dj[0], rtol=1e-12)
    np.testing.assert_allclose(f[1], -cy / DT * dj[1], rtol=1e-12)
    assert not f[1, 0, :3].any()
    assert (cx == 0.5 * m / DT).any() and (cx < 0.5 * m / DT).any()  # both sides of the cap


def test_straight_driving_both_laws_give_wongs_track_thrust():
    """No lateral slip: the decoupled law is the resultant one, F = (A c + W tan phi)
    [1 - K/(i L)(1 - e^{-i L/K})] (Wong Ch. 4)."""
    slip, u = 0.2, 0.1
    load = P * B_W * L
    x = slip * L / K
    wong = (B_W * L * C + load * TAN_PHI) * (1.0 - (1.0 - math.exp(-x)) / x)
    for law in SHEAR_LAWS:
        fx, fy, _ = steady_track_forces(u * (1 - slip), 0.0, 0.0, 0.2, u, L, B_W, P, C,
                                        TAN_PHI, K, shear_law=law)
        assert fx == pytest.approx(wong, rel=1e-3) and abs(fy) < 1e-9 * wong


@pytest.mark.parametrize("v,radius,vy,ratio_outer,ratio_inner,moduli", [
    (0.1, 0.5, 0.01, 0.8, 0.85, (1.0, 1.0)), (0.05, 0.25, 0.0, 0.7, 0.7, (1.0, 1.0)),
    (0.05, 0.25, 0.0, 0.7, 0.7, (2.3, 0.69))])
def test_in_a_steady_turn_the_decoupled_cells_give_the_decoupled_integrals(
        v, radius, vy, ratio_outer, ratio_inner, moduli):
    """The transient scheme at steady state with the decoupled law (the soil's K, or K_x and
    K_y of their own, ``moduli`` times K): each track's thrust and lateral force within 5 % of
    the exact integrals of the same law, where the hull turns by less than 2 rad while the
    soil passes under the track (the field's own accuracy bound)."""
    omega, ys, us, j, e = steady_turn(v, radius, vy, ratio_outer, ratio_inner)
    b, c, tan_phi, k = soil(2)
    (fx, fy), _ = cell_forces(j, e, np.full((2, N), P), b, DX, c, tan_phi, k, None,
                              np.ones(2, dtype=bool), None, *moduli)
    checked = 0
    for i in range(2):
        if omega * L / us[i] > 2.0:
            continue  # the upwinded field is smeared by several per cent (test_track.py)
        exact = steady_track_forces(v, vy, omega, ys[i], us[i], L, B_W, P, C, TAN_PHI,
                                    moduli[0] * K, shear_law="decoupled",
                                    lateral_shear_modulus_m=moduli[1] * K)
        assert fx[i].sum() == pytest.approx(exact[0], rel=0.05)
        assert fy[i].sum() == pytest.approx(exact[1], abs=0.05 * abs(exact[0]))
        checked += 1
    assert checked >= 1


def test_the_decoupled_law_is_the_plain_function_the_cells_compile():
    s = C + P * TAN_PHI
    for jx, jy in ((0.01, -0.02), (0.09, 0.08)):  # below the cap and on it
        tx, ty, kx, ky = decoupled_stress_pa(jx, jy, s, K, K)
        fx, fy, kcx, kcy = _cells([jx], [jy], P, True, lateral=True)
        assert (-tx * B_W * DX, -ty * B_W * DX, kx * B_W * DX, ky * B_W * DX) == pytest.approx(
            (fx[0], fy[0], kcx[0], kcy[0]), rel=1e-12)


def test_the_shear_law_option_is_validated_and_named_in_the_error():
    assert TRACK_SHEAR_LAWS == SHEAR_LAWS  # the vehicle's vocabulary is the model's
    spec = tracked_patako_wong_chiang()
    assert spec.track_shear_law == "resultant" and TrackModelParams().shear_law == "resultant"
    assert dataclasses.replace(spec, track_shear_law="decoupled").track_shear_law == "decoupled"
    with pytest.raises(ValueError, match="track_shear_law"):
        dataclasses.replace(spec, track_shear_law="ishigami")
    with pytest.raises(ValueError, match="shear_law"):
        TrackModelParams(shear_law="Decoupled")
    with pytest.raises(ValueError, match="shear_law"):
        steady_track_forces(0.1, 0.0, 0.0, 0.2, 0.1, L, B_W, P, C, TAN_PHI, K,
                            shear_law="vector")


@pytest.mark.parametrize("downhill_deg,ratios", [(-90.0, (1.0, 1.0)), (180.0, (1.0, 1.0)),
                                                  (-90.0, (2.3, 0.7))])
def test_parked_on_a_15_degree_slope_with_the_decoupled_law_the_tracked_vehicle_holds(
        downhill_deg, ratios):
    """The vehicle's ``track_shear_law`` and lateral modulus reach the simulated cells, whose
    soil springs (no direction state) and dampers hold it at rest on Yamauchi's steepest slope
    (side-on or facing uphill)."""
    spec = dataclasses.replace(make_vehicle("tracked_patako_wong_chiang"),
                               track_shear_law="decoupled",
                               track_longitudinal_shear_modulus_ratio=ratios[0],
                               track_lateral_shear_modulus_ratio=ratios[1])
    sim = Simulator(spec, TerrainSpec(kind="slope", slope_deg=15.0,
                                      downhill_azimuth_deg=downhill_deg),
                    make_force_model("janosi", spec), make_soil_map(DRY_SAND, None))
    try:
        assert sim.injector.params.shear_law == "decoupled"
        params = sim.injector.params
        assert (params.longitudinal_shear_modulus_ratio,
                params.lateral_shear_modulus_ratio) == ratios
        sim.reset(0.0, 0.0, 0.0)
        start = np.array(hold(sim, 3.0).position_m)
        end = np.array(hold(sim, 10.0).position_m)
        assert np.linalg.norm(end - start) < 1e-3
    finally:
        sim.close()


def test_the_decoupled_law_applies_where_the_soil_deforms_and_the_resultant_on_rigid_ground():
    resultant, decoupled = (float(SHEAR_LAWS.index(law)) for law in ("resultant", "decoupled"))
    assert decoupled_cells(decoupled, 1.0) and decoupled_cells(decoupled, 0.6)
    assert not decoupled_cells(decoupled, 0.0) and not decoupled_cells(decoupled, 0.4)
    assert not decoupled_cells(resultant, 1.0) and not decoupled_cells(resultant, 0.0)


def test_a_substep_with_one_track_on_rigid_ground_gives_that_track_the_resultant_law():
    """The decoupled law on a deformable and a rigid track: each track's shear forces are those
    of the same substep with both tracks deformable under the decoupled, respectively the
    resultant, law (sinkage and walls zeroed on the rigid track in all three runs)."""
    def shear(law, deformable):
        a = _inputs("both_forward", law)
        a["deformable"] = np.array(deformable)
        a["walls"][:] = 0.0
        track_substep(*a.values())
        return a["out"][2:4]

    mixed = shear("decoupled", [1.0, 0.0])
    soft, rigid = shear("decoupled", [1.0, 1.0]), shear("resultant", [1.0, 0.0])
    np.testing.assert_array_equal(mixed[:, 0], soft[:, 0])
    np.testing.assert_array_equal(mixed[:, 1], rigid[:, 1])
    assert np.abs(soft[:, 1] - rigid[:, 1]).max() > 1e-3 * np.abs(rigid[:, 1]).max()


def test_on_rigid_ground_the_decoupled_vehicle_turns_as_the_resultant_one():
    """Concrete is not deformable: the vehicle selecting the decoupled law drives the same
    turn as the resultant law's bit for bit (the tread's Coulomb friction, not soil shear)."""
    poses = {}
    for law in SHEAR_LAWS:
        spec = dataclasses.replace(make_vehicle("tracked_patako_wong_chiang"),
                                   track_shear_law=law)
        sim = Simulator(spec, TerrainSpec(), make_force_model("janosi", spec),
                        make_soil_map(CONCRETE, None))
        try:
            sim.reset(0.0, 0.0, 0.0)
            truths = drive(sim, 0.05, math.radians(20.0), 2.0)
            poses[law] = np.array([[*t.position_m, t.yaw_rad] for t in truths])
        finally:
            sim.close()
    assert abs(poses["resultant"][-1, 3]) > math.radians(10.0)  # it did turn
    np.testing.assert_array_equal(poses["decoupled"], poses["resultant"])


@pytest.mark.parametrize("ratio", [0.4, 3.0])
def test_the_decoupled_law_takes_the_lateral_modulus_for_the_lateral_component(ratio):
    """Ishigami et al.'s separate moduli: tau_x = tau_max (1 - e^{-|j_x|/K_x}), tau_y =
    tau_max (1 - e^{-|j_y|/K_y}) below the cap, each stiffness tau_max e^{-|j|/K}/K of its
    own modulus; on the cap the resultant is tau_max and the stiffnesses are the derivatives."""
    s, k_y = C + P * TAN_PHI, ratio * K
    for jx, jy in ((0.004, -0.006), (-0.01, 0.002), (0.0, 0.03)):
        tx, ty, kx, ky = decoupled_stress_pa(jx, jy, s, K, k_y)
        gx, gy = 1.0 - math.exp(-abs(jx) / K), 1.0 - math.exp(-abs(jy) / k_y)
        if math.hypot(gx, gy) <= 1.0:
            assert (tx, ty) == pytest.approx((math.copysign(s * gx, jx),
                                              math.copysign(s * gy, jy)), rel=1e-12)
            assert (kx, ky) == pytest.approx((s * math.exp(-abs(jx) / K) / K,
                                              s * math.exp(-abs(jy) / k_y) / k_y), rel=1e-12)
    for jx, jy in ((0.004, -0.006), (0.09, 0.08), (-0.2, 0.05)):  # free and capped
        tx, ty, kx, ky = decoupled_stress_pa(jx, jy, s, K, k_y)
        assert math.hypot(tx, ty) <= s * (1.0 + 1e-12)
        h = 1e-8
        dx = (decoupled_stress_pa(jx + h, jy, s, K, k_y)[0]
              - decoupled_stress_pa(jx - h, jy, s, K, k_y)[0]) / (2 * h)
        dy = (decoupled_stress_pa(jx, jy + h, s, K, k_y)[1]
              - decoupled_stress_pa(jx, jy - h, s, K, k_y)[1]) / (2 * h)
        assert (kx, ky) == pytest.approx((dx, dy), rel=1e-5, abs=1e-6 * s / K)


def test_the_cells_take_the_modulus_ratios_and_the_resultant_law_ignores_them():
    """K_x = 2 K and K_y = 3 K on the decoupled track: its force is the law's with those
    moduli; the resultant law's track is unchanged."""
    j = np.zeros((2, 2, 2))
    j[0], j[1] = 0.01, 0.02
    e = j[:, :, :1] * 1.0
    b, c, tan_phi, k = soil(2)
    flags = np.array([True, False])
    pressure = np.full((2, 1), P)
    (fx1, fy1), _ = cell_forces(j, e, pressure, b, DX, c, tan_phi, k, None, flags, None,
                                1.0, 1.0)
    (fx3, fy3), _ = cell_forces(j, e, pressure, b, DX, c, tan_phi, k, None, flags, None,
                                2.0, 3.0)
    tau = decoupled_stress_pa(0.01, 0.02, C + P * TAN_PHI, 2.0 * K, 3.0 * K)
    assert (fx3[0, 0], fy3[0, 0]) == pytest.approx((-tau[0] * B_W * DX, -tau[1] * B_W * DX),
                                                   rel=1e-12)
    # softer springs: less stress for the same displacement
    assert abs(fx3[0, 0]) < abs(fx1[0, 0]) and abs(fy3[0, 0]) < abs(fy1[0, 0])
    assert (fx3[1, 0], fy3[1, 0]) == (fx1[1, 0], fy1[1, 0])  # the resultant law's track


@pytest.mark.parametrize("axis", ["longitudinal", "lateral"])
def test_the_modulus_ratios_are_validated_and_named_in_the_error(axis):
    spec = tracked_patako_wong_chiang()
    field = f"track_{axis}_shear_modulus_ratio"
    assert getattr(spec, field) == 1.0
    for bad in (0.0, -1.0, float("nan"), 100.0):
        with pytest.raises(ValueError, match=field):
            dataclasses.replace(spec, **{field: bad})
    with pytest.raises(ValueError, match=f"{axis}_shear_modulus_ratio"):
        TrackModelParams(**{f"{axis}_shear_modulus_ratio": 0.0})

"""The effect registry: one module per effect, and a new effect needs no other file."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np
import pytest

from slipenv.diagnose import apply_model
from slipenv.diagnose.effects import EFFECTS, effect, effect_ids, register, unregister
from slipenv.diagnose.effects.base import Bound, Effect, Scalar, Term, finite, require
from slipenv.diagnose.fit import Problem, fit
from slipenv.diagnose.replay import build_segments
from slipenv.diagnose.select import select
from slipenv.envs.config import SlipEnvConfig
from slipenv.logs import Log
from tests.diagnose.test_replay import R, kinematic_log, route

VOCABULARY = ("none", "rolling_radius", "track_width", "torque_slip", "turning_slip",
              "slope_side_slip", "combined_slip", "soil_patch", "soil_map",
              "gyro_bias")  # log-format.md, and soil_map


def test_registry_holds_the_vocabulary_in_its_order():
    assert effect_ids() == VOCABULARY
    for name, eff in EFFECTS.items():
        assert eff.name == name and eff.params.__module__.endswith(f"effects.{name}")


@pytest.mark.parametrize("name", VOCABULARY[1:])
def test_bounds_hold_the_start_and_params_are_frozen(name):
    log = kinematic_log(*route(600))
    n = len(log)
    torque = {f"torque_{w}": np.full(n, 5.0) for w in log.wheels}  # what torque slip needs
    seg = build_segments([Log(log.meta, {**log.signals, **torque})])
    eff = effect(name)
    bounds = eff.bounds(seg)
    assert tuple(bounds) == eff.fields()
    assert all(b.lower <= b.start <= b.upper and b.scale > 0 for b in bounds.values())
    params = eff.from_vector([b.start for b in bounds.values()])
    with pytest.raises(dataclasses.FrozenInstanceError):
        setattr(params, eff.fields()[0], 1.0)
    with pytest.raises(ValueError, match=type(params).__name__):
        eff.from_vector([float("nan")] * len(eff.fields()))


def test_unknown_effect_lists_the_vocabulary():
    with pytest.raises(ValueError, match="the vocabulary is none, rolling_radius"):
        effect("wheel_wobble")


@dataclass(frozen=True)
class OdometerScale(Term):
    """A toy effect: every wheel's radius times one factor [-]."""

    factor: float

    def __post_init__(self) -> None:
        finite(self)
        require(self.factor > 0, self, "factor must be > 0")

    def wheel_radius(self, seg, radius):
        return radius * self.factor


def _apply(edit, p: OdometerScale) -> None:
    r = edit.spec.wheel_radius_nominal_m * p.factor
    edit.set_rolling_radii(r, r)


TOY = Effect(name="odometer_scale", meaning="every wheel rolls a factor further (toy)",
             params=OdometerScale, bounds=lambda seg: {"factor": Bound(1.0, 0.5, 1.5, 0.01)},
             contract=(Scalar("factor", "odometer_factor"),), apply=_apply, rank=1.5)


@pytest.fixture
def toy():
    register(TOY)
    yield TOY
    unregister(TOY.name)


def test_a_toy_effect_registered_here_is_fitted_selected_and_applied(toy):
    assert effect_ids().index("odometer_scale") == 2  # between the radius and the width
    log = kinematic_log(*route(1200), r_true=(1.03 * R, 1.03 * R))
    problem = Problem.from_segments(build_segments([log]))
    f = fit(problem, ("odometer_scale",))
    assert f.params["odometer_scale"].factor == pytest.approx(1.03, rel=1e-4)
    assert f.report(problem.seg)["odometer_factor"][1] > 0
    sel = select(problem)
    cand = {c.name: c for c in sel.candidates}["odometer_scale"]
    assert cand.significant and cand.n_params == 1
    # one parameter explains what the two radii do: parsimony names the toy
    assert sel.cause == "odometer_scale"
    cfg = apply_model(SlipEnvConfig(vehicle="farm_2wd"),
                      {"odometer_scale": {"odometer_factor": 1.03}})
    radii = [w.rolling_radius_m for w in cfg.vehicle.wheels if w.role == "driven"]
    assert radii == pytest.approx([0.275 * 1.03] * 2)


def test_registering_a_taken_name_is_an_error(toy):
    with pytest.raises(ValueError, match="already in the vocabulary"):
        register(TOY)
    assert "odometer_scale" in EFFECTS


def test_unregister_removes_the_effect():
    register(TOY)
    unregister(TOY.name)
    assert "odometer_scale" not in EFFECTS and effect_ids() == VOCABULARY


def test_combined_slip_at_zero_slip_angle_is_a_common_wheel_radius_so_it_is_held_beside_one():
    from slipenv.diagnose.effects.combined_slip import CombinedSlip
    from slipenv.diagnose.effects.rolling_radius import RollingRadius
    from slipenv.diagnose.fit import param_count
    from slipenv.diagnose.kinematic import kinematic_log as kin_log
    from slipenv.diagnose.replay import simulate

    seg = build_segments([kin_log(5, None, duration_s=60.0)])
    s = 0.01  # |g| = |d| (1 - s) on every wheel, forward or back: the radii times 1 - s
    slip = simulate(seg, {"combined_slip": CombinedSlip(s, 0.0, 0.02)})
    r0 = float(seg.radius[0, 0])
    radii = simulate(seg, {"rolling_radius": RollingRadius(r0 * (1 - s), r0 * (1 - s))})
    assert np.allclose(slip, radii, atol=1e-12)
    assert param_count(("rolling_radius", "combined_slip")) == 4  # s_x0 is not a fifth
    f = fit(Problem.from_segments(seg), ("rolling_radius", "combined_slip"))
    assert f.params["combined_slip"].s_x0 == 0.0
    assert effect("combined_slip").redundant == {"s_x0": "rolling_radius"}


@pytest.mark.parametrize("bad", [{"calibration": 1}, {"local": "yes"}, {"condense": "grid"},
                                 {"redundant": {"no_such_field": "x"}},
                                 {"redundant": {"factor": 3}},
                                 {"redundant": {"factor": "odometer_scale"}}])
def test_an_effect_with_a_bad_flag_hook_or_redundant_entry_is_refused_when_built(bad):
    with pytest.raises(ValueError, match="calibration|redundant|local|condense"):
        dataclasses.replace(TOY, **bad)


def test_turning_slip_scales_every_turn_as_a_wider_track_and_moves_only_forward_speed():
    # Endo's split (Yamauchi Eq. 7-8): g_R' - g_L' = (1 - κ)(g_R - g_L) whatever the share
    # f, the turn of a track W/(1 - κ) wide; the mean moves by κ (g_R - g_L)(2f - 1)/2,
    # nothing on a pivot (f = 1/2). Hence the confound the report names on a skid-steer.
    from slipenv.diagnose.effects.turning_slip import TurningSlip
    from slipenv.estimators.skid_steer.endo import endo_left_share

    rng = np.random.default_rng(4)
    left, right = rng.uniform(-0.02, 0.05, (2, 1, 40))
    seg = SimpleNamespace(dt=np.full((1, 40), 0.05))
    kappa, n = 0.4, 0.9
    new_left, new_right = TurningSlip(n, kappa).split(seg, left, right)
    assert np.allclose(new_right - new_left, (1.0 - kappa) * (right - left), rtol=1e-12)
    f = endo_left_share(left / 0.05, right / 0.05, n, 1e-3)
    shift = 0.5 * kappa * (right - left) * (2.0 * f - 1.0)
    assert np.allclose(0.5 * (new_left + new_right) - 0.5 * (left + right), shift, atol=1e-15)
    pivot_l, pivot_r = TurningSlip(n, kappa).split(seg, -right, right)
    assert np.allclose(pivot_l + pivot_r, 0.0, atol=1e-15)
    conf = effect("turning_slip").confound("skid_steer")
    assert conf is not None and conf.shows_as == "track_width"

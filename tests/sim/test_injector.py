"""Both soil force injectors offer the :class:`Injector` surface the layers above read."""

from __future__ import annotations

import inspect
import math

import numpy as np
import pytest

from slipenv.contracts.constants import G_MPS2
from slipenv.sim.injector import Injector
from slipenv.sim.track_soil import TrackSoilInjector
from slipenv.sim.wheel_soil import WheelContactState, WheelSoilInjector
from slipenv.terramechanics.presets import soil_by_name
from tests.sim.conftest import drive, hold

KINDS = [("husky", "loose_sand", "janosi", WheelSoilInjector),
         ("tracked_patako_wong_chiang", "toyoura_sand", "janosi", TrackSoilInjector)]
METHODS = [name for name, member in vars(Injector).items()
           if inspect.isfunction(member) and not name.startswith("_")]
PROPERTIES = [name for name, member in vars(Injector).items() if isinstance(member, property)]


def accepts_the_protocols_call(impl, proto: inspect.Signature) -> bool:
    """``impl`` takes every parameter of ``proto`` by the same name (optional ones optional)
    and needs no other."""
    wanted = proto.parameters
    offered = inspect.signature(impl).parameters
    for name, param in wanted.items():
        if name not in offered:
            return False
        if (param.default is not inspect.Parameter.empty
                and offered[name].default is inspect.Parameter.empty):
            return False
    return all(p.default is not inspect.Parameter.empty or p.kind in (p.VAR_POSITIONAL,
                                                                        p.VAR_KEYWORD)
               for name, p in offered.items() if name not in wanted)


def test_the_protocol_lists_what_the_simulator_sensors_and_env_read():
    assert set(METHODS) == {"sample_soil", "apply", "soil_at_wheel", "rolling_radius_m",
                            "contact_state"}
    assert set(PROPERTIES) == {"links", "load", "force_model"}
    assert "chassis_contact" in Injector.__annotations__


@pytest.mark.parametrize(("vehicle", "soil", "model", "cls"), KINDS)
def test_each_injector_is_an_injector_with_the_protocols_signatures(make_sim, vehicle, soil,
                                                                    model, cls):
    sim = make_sim(vehicle, soil, model)
    assert type(sim.injector) is cls
    assert isinstance(sim.injector, Injector)
    for name in METHODS:
        member = getattr(sim.injector, name)  # an instance's own (a compiled loop's) if set
        try:
            inspect.signature(member)
        except ValueError:  # a compiled function without a signature: called in the next test
            continue
        protocol = inspect.signature(getattr(Injector, name))
        plain = protocol.replace(parameters=list(protocol.parameters.values())[1:])  # no self
        assert accepts_the_protocols_call(member, plain), name


@pytest.mark.parametrize(("vehicle", "soil", "model", "cls"), KINDS)
def test_each_injector_reports_what_the_protocol_promises(make_sim, vehicle, soil, model, cls):
    sim = make_sim(vehicle, soil, model)
    sim.reset(0.0, 0.0, 0.0)
    hold(sim, 1.0)
    injector: Injector = sim.injector
    n = len(sim.spec.wheels)
    assert len(injector.links) == len(injector.load) == n
    assert injector.force_model is sim.force_model
    # Parked on flat ground, the wheels carry the vehicle's weight.
    assert sum(injector.load) == pytest.approx(sim.spec.mass_kg * G_MPS2, rel=0.05)
    expected = soil_by_name(soil).params()
    for k in range(n):
        assert injector.soil_at_wheel(k) == expected
        radius = sim.spec.wheels[k].radius_m
        assert 0.5 * radius < injector.rolling_radius_m(k) <= 1.5 * radius
    drive(sim, 0.1, 0.0, 1.0)
    state = injector.contact_state()
    assert isinstance(state, WheelContactState)
    for name in ("slip", "tan_beta", "load_n", "fx_n", "fy_n", "resistance_n", "in_contact",
                 "damper_n"):
        values = np.asarray(getattr(state, name), dtype=float)
        assert values.shape == (n,) and np.all(np.isfinite(values)), name
    # Driving steadily on the flat, the wheels still carry the weight.
    assert state.load_n.sum() == pytest.approx(sim.spec.mass_kg * G_MPS2, rel=0.05)
    injector.chassis_contact = True
    assert injector.chassis_contact is True
    injector.chassis_contact = False
    assert injector.chassis_contact is False


def test_an_object_missing_a_member_is_not_an_injector():
    class NoContactState:
        links: list[int] = []
        load: list[float] = []
        force_model = None
        chassis_contact = False

        def sample_soil(self, force: bool = False) -> None: ...

        def apply(self) -> None: ...

        def soil_at_wheel(self, k: int): ...

        def rolling_radius_m(self, k: int) -> float:
            return math.nan

    assert not isinstance(NoContactState(), Injector)

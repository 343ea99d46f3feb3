"""The diagnosis names an effect hidden in the physics, says ``none`` on clean logs, and
recovers the effect's parameters within their reported uncertainty."""

from __future__ import annotations

import pytest

from slipenv.diagnose.synth import EXACT
from tests.diagnose.conftest import CASES

Z_LIMIT = 3.0  # |estimate - truth| <= 3 standard errors


@pytest.mark.parametrize(("effect", "kind", "seed"), CASES,
                         ids=[f"{e}-{k}" for e, k, _ in CASES])
def test_names_the_hidden_effect(diagnosed, effect, kind, seed):
    case = diagnosed(effect, kind, seed)
    assert case.selection.cause == effect, (
        f"hid {effect} ({case.synth.world}), diagnosis says {case.selection.cause}; "
        + ", ".join(f"{c.name}: gain {c.gain_relative:.2f} p {c.p_value:.2g}"
                    for c in case.selection.candidates if not c.untestable))


@pytest.mark.parametrize(("effect", "kind", "seed"),
                         [c for c in CASES if c[0] != "none" and c[0] in EXACT[c[1]]],
                         ids=lambda v: str(v))
def test_exact_parameters_within_reported_uncertainty(diagnosed, effect, kind, seed):
    """Where the physics sets the parameter one to one, it lies within 3 SE of the estimate."""
    case = diagnosed(effect, kind, seed)
    assert case.selection.cause == effect
    params = case.parameters()
    for name, true in case.synth.truth.items():
        value, se = params[name]
        assert se > 0
        assert abs(value - true) <= Z_LIMIT * se, f"{name}: {value} ± {se}, true {true}"


GEOMETRY = ("rolling_radius", "track_width")


@pytest.mark.parametrize(("effect", "kind", "seed"),
                         [c for c in CASES if c[0] != "none" and c[0] not in EXACT[c[1]]],
                         ids=lambda v: str(v))
def test_emergent_parameters_near_calibration(diagnosed, effect, kind, seed):
    """Parameters that emerge from the physics agree with a long noise-free calibration run
    of the same world: within 3 SE, or (they also depend on the route driven) 0.5 % for
    geometry and 15 % for slip laws."""
    case = diagnosed(effect, kind, seed)
    assert case.selection.cause == effect
    params = case.parameters()
    slack = 0.005 if effect in GEOMETRY else 0.15
    for name, true in case.synth.truth.items():
        value, se = params[name]
        assert abs(value - true) <= max(Z_LIMIT * se, slack * abs(true)), \
            f"{name}: {value} ± {se}, calibration {true}"


@pytest.mark.parametrize(("effect", "kind", "seed"),
                         [c for c in CASES if c[0] in GEOMETRY], ids=lambda v: str(v))
def test_geometry_near_the_value_set_in_the_physics(diagnosed, effect, kind, seed):
    """Radii and track width are set in the simulated vehicle: recovered within 0.5 %."""
    case = diagnosed(effect, kind, seed)
    params = case.parameters()
    set_values = {k: v for k, v in case.synth.world.items() if k in params}
    assert set_values
    for name, true in set_values.items():
        assert params[name][0] == pytest.approx(true, rel=0.005)


def test_gain_is_held_out_and_positive(diagnosed):
    case = diagnosed("track_width", "diff_drive", 4)
    final = case.selection.final["pose"]
    base = case.selection.baseline["pose"]
    assert final.errors.sum() < 0.5 * base.errors.sum()
    # every segment was predicted by fits that never saw it
    assert len(final.fold_fits) == len(set(case.selection.folds.tolist()))

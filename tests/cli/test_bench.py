"""``slipenv bench``'s breakdown, Coulomb reference and vectorised figure."""

from __future__ import annotations

import json

import gymnasium as gym
import pytest

import slipenv.bench as bench
from slipenv.cli import main
from slipenv.pybullet_quiet import import_pybullet

p = import_pybullet()
ENV = "slipenv/HuskySand-v0"


@pytest.fixture(scope="module")
def husky_result():
    return bench.run_bench([ENV], steps=20, repeats=1, progress=False, vec=False)


def test_breakdown_components_are_non_negative_and_add_up_to_the_total(husky_result):
    b = husky_result["envs"][ENV]["breakdown_us_per_step"]
    assert set(b) == set(bench.BREAKDOWN_KEYS)
    parts = [b[k] for k in bench.BREAKDOWN_KEYS if k != "total"]
    assert all(v >= 0.0 for v in parts)
    assert sum(parts) == pytest.approx(b["total"], abs=0.1 * len(parts))  # rounding to 0.1 us
    # the physics and the force law run at every substep: neither can be missing
    assert b["step_simulation"] > 0.0 and b["force_injection"] > 0.0
    assert b["sensors"] > 0.0 and b["estimator"] > 0.0 and b["observation_reward"] > 0.0


def test_injection_parts_per_substep_come_from_the_compiled_loop(husky_result):
    r = husky_result["envs"][ENV]
    parts = r["injection_parts_us_per_substep"]
    assert parts is not None, "the Husky's wheels run in the compiled loop, which times its parts"
    assert set(parts) == {"read", "force_law", "apply"}
    assert all(v > 0.0 for v in parts.values())
    # the parts are inside the injection the step breakdown timed (per control step)
    total = sum(parts.values()) * r["substeps_per_step"]
    assert total < r["breakdown_us_per_step"]["force_injection"]
    assert "force injection, us per substep" in bench.format_bench(husky_result)


def test_coulomb_reference_is_reported_next_to_the_env_rate(husky_result):
    r = husky_result["envs"][ENV]
    assert r["coulomb_env_steps_per_s"] > 0.0
    assert r["vs_coulomb"] == pytest.approx(r["env_steps_per_s"] / r["coulomb_env_steps_per_s"],
                                            rel=1e-2)
    assert "vec_env_steps_per_s" not in r  # vec=False
    assert husky_result["settings"]["coulomb_mu"] == pytest.approx(0.81)


def test_coulomb_reference_restores_the_worlds_friction_and_the_timers_are_removed():
    env = gym.make(ENV)
    try:
        env.reset(seed=0)
        base = env.unwrapped
        client = base.physics_client_id
        links = bench._links(client)
        before = [p.getDynamicsInfo(b, link, physicsClientId=client)[1] for b, link in links]
        assert bench.coulomb_steps_per_s(client, 3, base.substeps_per_step) > 0.0
        after = [p.getDynamicsInfo(b, link, physicsClientId=client)[1] for b, link in links]
        assert after == before
        compiled_apply = vars(base._sim.injector).get("apply")  # the compiled loop's, if built
        bench.step_breakdown(env, 3)
        assert p.stepSimulation.__name__ == "stepSimulation"
        assert "update" not in vars(base.estimator) and "_observe" not in vars(base)
        # the injector built by the rollout's last reset keeps its own (compiled) apply
        injector = base._sim.injector
        if compiled_apply is not None:
            assert vars(injector)["apply"] == injector._loop.apply
            assert not injector._loop.timing
    finally:
        env.close()


def test_bench_json_keeps_its_schema_and_adds_breakdown_and_vec(tmp_path):
    path = tmp_path / "bench.json"
    assert main(["bench", ENV, "--steps", "5", "--repeats", "1", "--quiet",
                 "--json", str(path)]) == 0
    data = json.loads(path.read_text())
    entry = data["envs"][ENV]
    for key in ("env_steps_per_s", "substeps_per_step", "bare_substeps_per_s", "ratio",
                "vehicle", "wheels", "realtime_factor"):
        assert key in entry
    assert set(entry["breakdown_us_per_step"]) == set(bench.BREAKDOWN_KEYS)
    assert entry["vec_processes"] == bench.VEC_PROCESSES and entry["vec_env_steps_per_s"] > 0
    assert data["settings"]["vec_processes"] == bench.VEC_PROCESSES


def test_format_shows_the_breakdown_table(husky_result):
    text = bench.format_bench(husky_result)
    assert "vs coulomb" in text and "us per control step" in text
    breakdown = text.split("us per control step", 1)[1].splitlines()
    assert any(line.startswith(ENV) for line in breakdown)


def test_a_tracked_env_reports_the_track_models_cost_against_the_per_wheel_law():
    """The same env with the track model switched: both timed, interleaved, and the ratio
    printed as "track model / per-wheel"."""
    tracked = "slipenv/TrackedSlopeCircle-v0"
    cost = bench.track_model_cost(tracked, steps=5, repeats=2)
    assert cost["per_wheel_us_per_step"] > 0.0 and cost["track_model_us_per_step"] > 0.0
    assert cost["ratio"] > 0.0
    result = {"envs": {tracked: {"env_steps_per_s": 1.0, "substeps_per_step": 12,
                                 "bare_substeps_per_s": 1.0, "ratio": 1.0,
                                 "realtime_factor": 1.0, "track_model_vs_per_wheel": cost}}}
    line = next(ln for ln in bench.format_bench(result).splitlines()
                if ln.startswith("track model / per-wheel"))
    assert tracked in line and f"{cost['ratio']:.2f}" in line


def test_untracked_envs_have_no_track_model_figure(husky_result):
    assert "track_model_vs_per_wheel" not in husky_result["envs"][ENV]
    assert "track model / per-wheel" not in bench.format_bench(husky_result)

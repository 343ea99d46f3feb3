"""What the commands print is clean and true: no banner, no stray warnings, truth-judged ends."""

from __future__ import annotations

import logging
import subprocess
import sys
import warnings

import numpy as np
import pytest

from slipenv.cli import main
from slipenv.run import EpisodeRecord, completion_text, plot_episode, slip_groups

ENV = "slipenv/HuskySand-v0"
BANNER = "pybullet build time"


def slipenv_cli(*args: str) -> subprocess.CompletedProcess:
    """The installed command in a fresh process (PyBullet not yet imported)."""
    return subprocess.run([sys.executable, "-m", "slipenv.cli", *args], capture_output=True,
                          text=True, timeout=120)


@pytest.mark.parametrize("args", [
    ("run", ENV, "--max-steps", "3", "--quiet", "--out", "{tmp}"),
    ("bench", ENV, "--steps", "3", "--repeats", "1", "--quiet"),
    ("list",),
])
def test_no_command_prints_the_pybullet_banner(tmp_path, args):
    done = slipenv_cli(*(a.format(tmp=tmp_path) for a in args))
    assert done.returncode == 0, done.stderr
    assert BANNER not in done.stdout and BANNER not in done.stderr


def test_the_quiet_import_keeps_later_output_and_a_plain_import_would_print(tmp_path):
    code = ("from slipenv.pybullet_quiet import import_pybullet\n"
            "p = import_pybullet()\nimport pybullet\nassert pybullet is p\nprint('after')\n")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == 0 and done.stdout == "after\n" and BANNER not in done.stderr
    plain = subprocess.run([sys.executable, "-c", "import pybullet"], capture_output=True,
                           text=True, timeout=60)
    assert BANNER in plain.stdout + plain.stderr  # the test would see the banner if it leaked


def test_bench_collects_estimator_warnings_and_reports_their_count(monkeypatch, capsys):
    import slipenv.bench as bench

    def noisy(env_id, steps, repeats, **kwargs):
        logging.getLogger("slipenv.estimators.lindgren.ekf").warning(
            "LindgrenEKF: skipping measurement (%s)", "odo_invalid_soil")
        warnings.warn("gains are marginal", RuntimeWarning, stacklevel=1)
        return {"env_steps_per_s": 100.0, "substeps_per_step": 12,
                "bare_substeps_per_s": 4000.0, "ratio": 0.3, "realtime_factor": 5.0}

    monkeypatch.setattr(bench, "bench_env", noisy)
    monkeypatch.setattr(bench, "startup_cost", lambda ids: {
        "import_s": 0.2, "first_make_s": dict.fromkeys(ids, 0.6), "compiled": {}})
    assert main(["bench", ENV, "slipenv/FarmField-v0", "--quiet"]) == 0
    out, err = capsys.readouterr()
    assert "skipping measurement" not in err and "gains are marginal" not in err
    table, last = out.strip().splitlines()[:-1], out.strip().splitlines()[-1]
    # header, rule, two envs, then the start-up line: nothing interleaved
    assert len(table) == 6 and table[5].startswith("startup: import slipenv 0.20 s")
    assert last.startswith("4 warning(s) during the benchmark, 2 distinct")


def record(success: bool, progress_true: float, progress_est: float, wheels: int = 2,
           channels: tuple[str, ...] = ("left", "right")) -> EpisodeRecord:
    n = 50
    t = np.arange(1, n + 1) * 0.05
    true = np.stack([np.linspace(0, 6.5, n), np.zeros(n), np.zeros(n)], axis=1)
    est = true + [3.5, 0.0, 0.0]
    return EpisodeRecord(
        env_id=ENV, seed=0, t_s=t, true_pose=true, est_pose=est,
        cross_track_true_m=np.full(n, 1.4), wheel_slip=np.tile(np.linspace(0, 0.3, wheels),
                                                               (n, 1)),
        slip_angle_rad=np.zeros(n), actions=np.zeros((n, 2)), rewards=np.zeros(n),
        reference_xy=np.array([[0.0, 0.0], [10.0, 0.0]]), end_reason="time limit",
        wheel_names=tuple(f"w{k}" for k in range(wheels)), dead_reckoning_xy=est[:, :2],
        wheel_channels=channels, success=success,
        progress_true=np.linspace(0, progress_true, n), progress_est=np.linspace(0, progress_est,
                                                                                 n))


def test_completion_is_judged_on_the_truth_with_the_estimates_view_beside_it():
    text = completion_text(record(success=False, progress_true=0.65, progress_est=1.0))
    truth, estimate = text.splitlines()
    assert truth.startswith("truth: path NOT complete (time limit): progress 65.0 %")
    assert "3.50 m from the path's end point" in truth and "+1.40 m" in truth
    assert estimate == "estimate: progress 100.0 %, 3.50 m from the true position"
    assert completion_text(record(True, 1.0, 0.9)).startswith("truth: path complete")


def test_run_reports_the_truths_verdict_for_a_cut_short_episode(tmp_path, capsys):
    assert main(["run", ENV, "--max-steps", "20", "--quiet", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "truth: path NOT complete (step limit)" in out and "estimate: progress" in out
    assert "progress_true" in out and "progress_estimated" in out


def test_a_tracks_road_wheels_are_one_labelled_slip_line_per_track(tmp_path):
    tracked = record(True, 1.0, 1.0, wheels=10, channels=("left",) * 5 + ("right",) * 5)
    groups = slip_groups(tracked)
    assert [label for label, _ in groups] == ["left (mean of 5 wheels)",
                                              "right (mean of 5 wheels)"]
    np.testing.assert_array_equal(groups[1][1], [5, 6, 7, 8, 9])
    assert [label for label, _ in slip_groups(record(True, 1.0, 1.0))] == ["w0", "w1"]
    png = plot_episode(tracked, tmp_path / "tracked.png")
    assert png.stat().st_size > 10_000

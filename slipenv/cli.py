"""The ``slipenv`` command line.

``slipenv run ENV_ID``    a baseline controller drives one episode: table + trajectory plot.
``slipenv bench``         env steps/s next to bare ``stepSimulation`` of the same world.
``slipenv reproduce NAME``  a source paper's experiment re-run: paper vs simulation.
``slipenv diagnose LOG``  what a measured log says the simulation gets wrong, and the fix.
``slipenv train ENV_ID``  a stable-baselines3 agent, evaluated next to the baseline.
``slipenv list``          registered environment ids.
"""

from __future__ import annotations

import argparse
import json
import sys

import gymnasium as gym

import slipenv  # noqa: F401  (registers the envs)


def _env_ids() -> list[str]:
    return sorted(e for e in gym.registry if e.startswith("slipenv/"))


def cmd_run(args: argparse.Namespace) -> int:
    from slipenv.run import format_table, plot_episode, run_episode, summarize

    if args.env_id not in gym.registry:
        print(f"unknown env id {args.env_id!r}; registered: {', '.join(_env_ids())}",
              file=sys.stderr)
        return 2
    rec = run_episode(args.env_id, seed=args.seed, controller=args.controller,
                      max_steps=args.max_steps, progress=not args.quiet)
    stats = summarize(rec)
    print(format_table(stats, f"{args.env_id}  seed {args.seed}  controller {args.controller}"
                              f"  ({rec.end_reason})"))
    out_dir = args.out or f"runs/{args.env_id.split('/')[-1]}"
    png = plot_episode(rec, f"{out_dir}/trajectory.png")
    print(f"trajectory plot: {png}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"env_id": args.env_id, "seed": args.seed, "metrics": stats,
                       "end_reason": rec.end_reason}, fh, indent=2)
        print(f"metrics: {args.json}")
    return 0


def cmd_bench(args: argparse.Namespace) -> int:
    from slipenv.bench import format_bench, run_bench

    ids = args.env_ids or _env_ids()
    result = run_bench(ids, steps=args.steps, repeats=args.repeats, progress=not args.quiet)
    print(format_bench(result))
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(result, fh, indent=2)
        print(f"written: {args.json}")
    return 0


def cmd_reproduce(args: argparse.Namespace) -> int:
    from slipenv.experiments import experiment

    run = experiment(args.name)
    extra = {"save_model": True} if getattr(args, "save_model", False) else {}
    result = run(quick=args.quick, out_dir=args.out or f"runs/reproduce_{args.name}",
                 json_path=args.json, seed=args.seed, progress=not args.quiet, **extra)
    return 0 if result is not None else 1


def cmd_diagnose(args: argparse.Namespace) -> int:
    from slipenv.diagnose.cli import main as diagnose_main

    return diagnose_main(args)


def cmd_train(args: argparse.Namespace) -> int:
    from slipenv.agents.train import evaluate, train

    model = train(args.env_id, algo=args.algo, total_timesteps=args.timesteps, seed=args.seed,
                  residual=not args.no_residual, out=args.out, progress=not args.quiet)
    agent = evaluate(model, args.env_id, n_episodes=args.episodes,
                     residual=not args.no_residual)
    baseline = evaluate("baseline", args.env_id, n_episodes=args.episodes)
    print(f"{'policy':<10} {'return':>10} {'± std':>8} {'mean |cross-track| [m]':>24}")
    for name, r in (("baseline", baseline), (args.algo, agent)):
        print(f"{name:<10} {r.mean_return:>10.2f} {r.std_return:>8.2f} "
              f"{r.mean_abs_cross_track_m:>24.3f}")
    print(f"model: {args.out}.zip")
    return 0


def cmd_list(args: argparse.Namespace) -> int:
    for env_id in _env_ids():
        print(env_id)
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="slipenv", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)
    run = sub.add_parser("run", help="drive one episode with the baseline controller")
    run.add_argument("env_id", help="e.g. slipenv/HuskySand-v0 (see `slipenv list`)")
    run.add_argument("--seed", type=int, default=0)
    run.add_argument("--controller", default="yamauchi",
                     help="yamauchi (default), yamauchi_feedback, pure_pursuit, stanley")
    run.add_argument("--max-steps", type=int, default=None)
    run.add_argument("--out", default=None, help="output folder (default runs/<env>)")
    run.add_argument("--json", default=None, help="also write the metrics as JSON")
    run.add_argument("--quiet", action="store_true", help="no progress bar")
    run.set_defaults(func=cmd_run)
    bench = sub.add_parser("bench", help="env steps/s next to bare stepSimulation")
    bench.add_argument("env_ids", nargs="*", help="default: every registered id")
    bench.add_argument("--json", default=None, help="write the figures as JSON")
    bench.add_argument("--steps", type=int, default=200, help="env steps per measurement")
    bench.add_argument("--repeats", type=int, default=5, help="interleaved repetitions")
    bench.add_argument("--quiet", action="store_true")
    bench.set_defaults(func=cmd_bench)
    rep = sub.add_parser("reproduce", help="re-run a source paper's experiment")
    rep.add_argument("name", help="lindgren | yamauchi")
    rep.add_argument("--quick", action="store_true", help="shorter runs, same experiments")
    rep.add_argument("--json", default=None, help="write metrics and paper values as JSON")
    rep.add_argument("--out", default=None, help="folder for plots (default runs/reproduce_NAME)")
    rep.add_argument("--seed", type=int, default=0)
    rep.add_argument("--quiet", action="store_true", help="no progress bars")
    rep.add_argument("--save-model", action="store_true",
                     help="yamauchi: also write the fitted slip model to slipenv/data (the "
                          "default observation of slipenv/TrackedSlopeCircle-v0)")
    rep.set_defaults(func=cmd_reproduce)
    diag = sub.add_parser("diagnose", help="diagnose a measured log (slipenv-log/1)")
    diag.add_argument("log_dir", help="folder with meta.json and signals.csv")
    diag.add_argument("--json", default=None, help="write the diagnosis report (JSON)")
    diag.add_argument("--report", default=None, help="folder for the human report (plots+text)")
    diag.add_argument("--seed", type=int, default=0)
    diag.add_argument("--quiet", action="store_true", help="no progress bars")
    diag.set_defaults(func=cmd_diagnose)
    tr = sub.add_parser("train", help="train an SB3 agent (residual on the baseline by default)")
    tr.add_argument("env_id")
    tr.add_argument("--algo", default="ppo", help="ppo | sac")
    tr.add_argument("--timesteps", type=int, default=20_000)
    tr.add_argument("--seed", type=int, default=0)
    tr.add_argument("--episodes", type=int, default=3, help="evaluation episodes")
    tr.add_argument("--no-residual", action="store_true", help="learn the whole action")
    tr.add_argument("--out", default="runs/agents/model", help="model path (without .zip)")
    tr.add_argument("--quiet", action="store_true")
    tr.set_defaults(func=cmd_train)
    sub.add_parser("list", help="registered env ids").set_defaults(func=cmd_list)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except ValueError as exc:
        print(f"slipenv: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())

"""The ``slipenv`` command line.

``slipenv run ENV_ID``      a baseline controller drives one episode: table + trajectory plot.
``slipenv bench [ENV_ID]``  env steps/s next to bare ``stepSimulation`` of the same world.
``slipenv reproduce NAME``  a source paper's experiment re-run: paper vs simulation.
``slipenv diagnose LOG``    what a measured log says the simulation gets wrong, and the fix.
``slipenv train ENV_ID``    a stable-baselines3 agent, evaluated next to the baseline.
``slipenv evaluate ENV_ID`` a policy over seeds: true-pose metrics, table, plot, JSON, TUM.
``slipenv sweep GRID.yaml`` an evaluation grid, on local processes or Ray; resumable.
``slipenv list``            registered environment ids.

Every input is checked before any long work starts (env ids against the Gymnasium registry,
numbers, output paths by writing to them); a bad one exits with status 2 and one line.
Ctrl-C exits with status 130 and one line: where the partial results are, or that nothing was
written.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any, Protocol

import gymnasium as gym

import slipenv
from slipenv.cli_outputs import (
    INTERRUPTED_STATUS,
    interrupted_message,
    output_dir,
    output_file,
    partial_results,
)
from slipenv.cli_types import non_negative_int, positive_int
from slipenv.contracts.names import did_you_mean
from slipenv.evaluation import evaluate_cli, sweep_cli
from slipenv.testbed import cli as testbed_cli


class SubParsers(Protocol):
    """What ``ArgumentParser.add_subparsers()`` returns, as far as a builder needs it."""

    def add_parser(self, name: str, **kwargs: Any) -> argparse.ArgumentParser:
        ...


Builder = Callable[[SubParsers], argparse.ArgumentParser]
Handler = Callable[[argparse.Namespace], int]


class _Formatter(argparse.ArgumentDefaultsHelpFormatter, argparse.RawDescriptionHelpFormatter):
    """Shows every optional option's default; keeps descriptions as written."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        if action.required:  # a default the user must replace is not one to show
            return action.help
        return super()._get_help_string(action)


class _Parser(argparse.ArgumentParser):
    """One-line errors (``slipenv run: error: ...``, status 2) and defaults in ``--help``."""

    def __init__(self, *args, **kwargs) -> None:
        kwargs.setdefault("formatter_class", _Formatter)
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(2, f"{self.prog}: error: {message}\n")


# -- argument types: each raises ArgumentTypeError with a one-line reason --------------------
def env_id(text: str) -> str:
    """A registered Gymnasium env id."""
    if text in gym.registry:
        return text
    known = sorted(e for e in gym.registry if e.startswith("slipenv/"))
    raise argparse.ArgumentTypeError(f"unknown env id {text!r}{did_you_mean(text, known)} "
                                     f"(registered: {', '.join(known)})")


def _one_of(text: str, known, what: str) -> str:
    """``text`` if it is one of ``known``, else the one-line "unknown ``what``" error."""
    if text in known:
        return text
    raise argparse.ArgumentTypeError(f"unknown {what} {text!r}{did_you_mean(text, known)}; "
                                     f"known: {', '.join(sorted(known))}")


def experiment_name(text: str) -> str:
    """A known experiment of ``slipenv reproduce``."""
    from slipenv.experiments import EXPERIMENT_MODULES

    return _one_of(text, EXPERIMENT_MODULES, "experiment")


def tracked_vehicle_name(text: str) -> str:
    """A tracked vehicle preset (``slipenv reproduce yamauchi --vehicle``)."""
    from slipenv.vehicles.presets import VEHICLES

    tracked = [n for n, make in VEHICLES.items() if make().track_length_m is not None]
    return _one_of(text, tracked, "tracked vehicle")


def soil_name(text: str) -> str:
    """A soil preset (``slipenv reproduce yamauchi --soil``)."""
    from slipenv.terramechanics.presets import SOILS

    return _one_of(text, SOILS, "soil")


WORLD_EXPERIMENTS = ("yamauchi",)
"""The experiments whose world ``--vehicle``/``--soil`` can change."""


def _write_json(path: Path, data: dict) -> None:
    path.write_text(json.dumps(data, indent=2) + "\n")


def _fill(template: str, **fields: object) -> str:
    """``template`` with ``{name}`` fields replaced (other braces are left as they are)."""
    for name, value in fields.items():
        template = template.replace("{" + name + "}", str(value))
    return template


def _short_name(env: str) -> str:
    return env.split("/")[-1]


# -- run -----------------------------------------------------------------------------------
def add_run(sub: SubParsers) -> argparse.ArgumentParser:
    from slipenv.controllers.baseline import BASELINE_NAMES
    from slipenv.evaluation.policies import BUILTIN_POLICIES

    p = sub.add_parser("run", help="drive one episode with a baseline controller",
                       description="Drive one episode with a baseline controller; print a "
                                   "table judged on the true pose and write a trajectory plot.")
    p.add_argument("env_id", type=env_id, help="e.g. slipenv/HuskySand-v0 (see `slipenv list`)")
    p.add_argument("--seed", type=non_negative_int, default=0, help="reset seed")
    names = [*BASELINE_NAMES, *(k for k in BUILTIN_POLICIES if k not in BASELINE_NAMES)]
    p.add_argument("--controller", choices=names, default="yamauchi",
                   help="baseline controller (`slipenv evaluate --policy` names too: "
                        "baseline = yamauchi, feedback = yamauchi_feedback)")
    p.add_argument("--max-steps", type=positive_int, default=None,
                   help="stop after this many steps (None: the env's time limit)")
    p.add_argument("--out", default="runs/{env}",
                   help="output folder for the plot ({env} = the env's name)")
    p.add_argument("--json", default=None, help="also write the metrics to this JSON file")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    return p


def cmd_run(args: argparse.Namespace) -> int:
    out_dir = output_dir(_fill(args.out, env=_short_name(args.env_id)), "--out")
    json_path = output_file(args.json, "--json")
    from slipenv.evaluation.policies import BUILTIN_POLICIES
    from slipenv.run import completion_text, format_table, plot_episode, run_episode, summarize

    controller = BUILTIN_POLICIES.get(args.controller, args.controller)  # evaluate's names
    rec = run_episode(args.env_id, seed=args.seed, controller=controller,
                      max_steps=args.max_steps, progress=not args.quiet)
    stats = summarize(rec)
    print(format_table(stats, f"{args.env_id}  seed {args.seed}  controller {controller}"))
    print(completion_text(rec))
    with partial_results(out_dir):
        png = plot_episode(rec, out_dir / "trajectory.png")
        print(f"trajectory plot: {png}")
        if json_path is not None:
            _write_json(json_path, {"env_id": args.env_id, "seed": args.seed,
                                    "controller": controller, "metrics": stats,
                                    "success": rec.success, "end_reason": rec.end_reason})
            print(f"metrics: {json_path}")
    return 0


# -- bench ---------------------------------------------------------------------------------
def add_bench(sub: SubParsers) -> argparse.ArgumentParser:
    p = sub.add_parser("bench", help="env steps/s next to bare stepSimulation")
    p.add_argument("env_ids", nargs="*", type=env_id, default=[],
                   help="env ids to measure ([] = every registered slipenv id)")
    p.add_argument("--json", default=None, help="write the figures to this JSON file")
    p.add_argument("--steps", type=positive_int, default=200, help="env steps per measurement")
    p.add_argument("--repeats", type=positive_int, default=5, help="interleaved repetitions")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--no-vec", action="store_true",
                   help="skip the vectorised-throughput figure (saves the worker start-up)")
    return p


def cmd_bench(args: argparse.Namespace) -> int:
    json_path = output_file(args.json, "--json")
    from slipenv.bench import format_bench, run_bench

    ids = args.env_ids or sorted(e for e in gym.registry if e.startswith("slipenv/"))
    result = run_bench(ids, steps=args.steps, repeats=args.repeats, progress=not args.quiet,
                       vec=not args.no_vec)
    print(format_bench(result))
    if json_path is not None:
        _write_json(json_path, result)
        print(f"written: {json_path}")
    return 0


# -- reproduce -----------------------------------------------------------------------------
def add_reproduce(sub: SubParsers) -> argparse.ArgumentParser:
    p = sub.add_parser("reproduce", help="re-run a source paper's experiment")
    p.add_argument("name", type=experiment_name, help="lindgren | yamauchi | reina")
    p.add_argument("--quick", action="store_true", help="shorter runs, same experiments")
    p.add_argument("--json", default=None, help="write metrics and paper values to this JSON")
    p.add_argument("--out", default="runs/reproduce_{name}",
                   help="folder for the plots ({name} = the experiment)")
    p.add_argument("--seed", type=non_negative_int, default=0, help="random seed")
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    p.add_argument("--save-model", default=None, metavar="PATH",
                   help="yamauchi: also write the fitted slip model to PATH (maintainers: "
                        "slipenv/data/yamauchi_slip_model.json of a source checkout)")
    p.add_argument("--docs", default=None, metavar="DIR",
                   help="write the page DIR/NAME.md (yamauchi in another world: "
                        "DIR/yamauchi_<world>.md)")
    p.add_argument("--vehicle", type=tracked_vehicle_name, default=None,
                   help="yamauchi: run on this tracked vehicle preset (None: "
                        "tracked_patako_wong_chiang, the Wong-Chiang track model, the env's; "
                        "tracked_patako: the per-wheel law; tracked_patako_decoupled: "
                        "Ishigami's decoupled shear law, its moduli calibrated on Endo's n)")
    p.add_argument("--soil", type=soil_name, default=None,
                   help="yamauchi: run on this soil preset (None: toyoura_sand, the env's; "
                        "that world is the one --save-model needs)")
    return p


def cmd_reproduce(args: argparse.Namespace) -> int:
    world = {k: v for k, v in (("vehicle", args.vehicle), ("soil", args.soil)) if v is not None}
    if world and args.name not in WORLD_EXPERIMENTS:
        raise ValueError(f"{' and '.join('--' + k for k in world)} only "
                         f"appl{'y' if len(world) > 1 else 'ies'} to "
                         f"{', '.join(WORLD_EXPERIMENTS)}, not {args.name}")
    if args.save_model and args.name == "yamauchi":
        from slipenv.experiments.yamauchi.settings import (
            REPRODUCTION_SOIL,
            REPRODUCTION_VEHICLE,
            is_env_world,
        )

        vehicle = args.vehicle if args.vehicle is not None else REPRODUCTION_VEHICLE
        soil = args.soil if args.soil is not None else REPRODUCTION_SOIL
        if not is_env_world(vehicle, soil):
            raise ValueError("--save-model writes the model the env observes with, fitted in "
                             "the env's own world: drop --vehicle/--soil (this run's world: "
                             f"{vehicle} on {soil})")
    out_dir = output_dir(_fill(args.out, name=args.name), "--out")
    json_path = output_file(args.json, "--json")
    output_file(args.save_model, "--save-model")
    docs_dir = None if args.docs is None else str(output_dir(args.docs, "--docs"))
    from slipenv.experiments import experiment

    run = experiment(args.name)
    extra: dict[str, Any] = {"save_model": args.save_model} if args.save_model else {}
    if world:
        from slipenv.experiments.yamauchi import FULL, QUICK

        extra["settings"] = dataclasses.replace(QUICK if args.quick else FULL, **world)
    with partial_results(out_dir):
        result = run(quick=args.quick, out_dir=str(out_dir),
                     json_path=None if json_path is None else str(json_path), seed=args.seed,
                     progress=not args.quiet, docs_dir=docs_dir, **extra)
    return 0 if result is not None else 1


# -- diagnose ------------------------------------------------------------------------------
def add_diagnose(sub: SubParsers) -> argparse.ArgumentParser:
    from slipenv.diagnose.cli import add_parser

    return add_parser(sub)


def cmd_diagnose(args: argparse.Namespace) -> int:
    output_file(args.json, "--json")
    if args.report is not None:
        output_dir(args.report, "--report")
    from slipenv.diagnose.cli import main as diagnose_main

    return diagnose_main(args)


# -- train ---------------------------------------------------------------------------------
def add_train(sub: SubParsers) -> argparse.ArgumentParser:
    p = sub.add_parser(
        "train", help="train an SB3 agent (residual on the baseline by default)",
        description="Train PPO, SAC or TD3 with the env's hyperparameters (rl-zoo3 YAML), "
                    "then evaluate it next to the baseline on held-out seeds. OUT receives "
                    "config.json, model.zip, checkpoints/ and logs/ (CSV + TensorBoard).")
    p.add_argument("env_id", type=env_id, help="e.g. slipenv/HuskySand-v0")
    p.add_argument("--algo", choices=("ppo", "sac", "td3"), default="ppo", help="algorithm")
    p.add_argument("--timesteps", type=positive_int, default=None,
                   help="total env steps (None: n_timesteps of the hyperparameter file)")
    p.add_argument("--out", default="runs/train/{env}_{algo}_seed{seed}",
                   help="run folder ({env}, {algo}, {seed} are filled in)")
    p.add_argument("--seed", type=non_negative_int, default=0, help="training seed")
    p.add_argument("--n-envs", type=positive_int, default=None,
                   help="parallel envs, SubprocVecEnv when > 1 (None: the file's n_envs)")
    p.add_argument("--residual", action=argparse.BooleanOptionalAction, default=None,
                   help="learn a residual on the baseline path follower (None: as the "
                        "file's env_wrapper says; the shipped files say yes)")
    p.add_argument("--hyperparams", default=None,
                   help="rl-zoo3 YAML file (None: the shipped agents/hyperparams/ALGO.yml)")
    p.add_argument("--checkpoint-freq", type=non_negative_int, default=None,
                   help="env steps between checkpoints (None: a quarter of the run; 0: none)")
    p.add_argument("--episodes", type=positive_int, default=3,
                   help="evaluation episodes (seeds 100, 101, ...)")
    p.add_argument("--quiet", action="store_true", help="no progress bar, no training table")
    return p


def cmd_train(args: argparse.Namespace) -> int:
    from slipenv.agents.train import evaluate, load_policy, resolve_config, timesteps_note, train

    config, _ = resolve_config(args.env_id, args.algo, args.timesteps, args.seed, args.n_envs,
                               args.residual, args.hyperparams)  # a bad file fails here
    out_dir = output_dir(_fill(args.out, env=_short_name(args.env_id), algo=args.algo,
                               seed=args.seed), "--out")
    print(f"training {config.algo} on {config.env_id}: {config.total_timesteps} steps, "
          f"{config.n_envs} env(s), residual={config.residual}, seed {config.seed} -> {out_dir}")
    note = timesteps_note(config)
    if note:
        print(note)
    formats = ("csv", "tensorboard") if args.quiet else ("stdout", "csv", "tensorboard")
    # train() saves OUT/interrupted.zip on Ctrl-C; before the model exists only logs are there.
    with partial_results(out_dir / "interrupted.zip", out_dir):
        train(args.env_id, algo=args.algo, total_timesteps=args.timesteps, seed=args.seed,
              n_envs=args.n_envs, residual=args.residual, out=out_dir,
              progress=not args.quiet, hyperparams=args.hyperparams,
              checkpoint_freq=args.checkpoint_freq, log_formats=formats)
    with partial_results(out_dir / "model.zip",
                         note="training finished; its evaluation did not"):
        policy, _ = load_policy(out_dir)
        agent = evaluate(policy, args.env_id, n_episodes=args.episodes, **config.env_kwargs)
        baseline = evaluate("baseline", args.env_id, n_episodes=args.episodes,
                            **config.env_kwargs)
    print(f"evaluation on seeds {', '.join(map(str, agent.seeds))}:")
    print(f"{'policy':<10} {'return':>10} {'± std':>8} {'mean |cross-track| [m]':>24} "
          f"{'success':>8}")
    for name, r in (("baseline", baseline), (args.algo, agent)):
        print(f"{name:<10} {r.mean_return:>10.2f} {r.std_return:>8.2f} "
              f"{r.mean_abs_cross_track_m:>24.3f} {r.success_rate:>8.0%}")
    print(f"model: {out_dir / 'model.zip'}   logs: {out_dir / 'logs'} "
          f"(tensorboard --logdir {out_dir / 'logs'})")
    return 0


# -- list ----------------------------------------------------------------------------------
def add_list(sub: SubParsers) -> argparse.ArgumentParser:
    return sub.add_parser("list", help="registered env ids")


def cmd_list(args: argparse.Namespace) -> int:
    for name in sorted(e for e in gym.registry if e.startswith("slipenv/")):
        print(name)
    return 0


SUBCOMMANDS: dict[str, tuple[Builder, Handler]] = {
    "run": (add_run, cmd_run),
    "bench": (add_bench, cmd_bench),
    "reproduce": (add_reproduce, cmd_reproduce),
    "diagnose": (add_diagnose, cmd_diagnose),
    "train": (add_train, cmd_train),
    "evaluate": (evaluate_cli.add_parser, evaluate_cli.main),
    "sweep": (sweep_cli.add_parser, sweep_cli.main),
    "fit-soil": (testbed_cli.add_parser, testbed_cli.main),
    "list": (add_list, cmd_list),
}
"""name -> (function adding its sub-parser, handler returning the exit status). A new command
is one entry: its builder calls ``sub.add_parser(name, help=...)`` (one-line errors and shown
defaults come with it) and adds its arguments; its handler checks outputs
(``slipenv.cli_outputs.output_dir``/``output_file``), then works, inside
``partial_results(PATH)`` where a Ctrl-C would leave something at PATH."""
NEEDS_NO_PHYSICS = ("list",)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="slipenv", description=__doc__)
    parser.add_argument("--version", action="version", version=f"slipenv {slipenv.__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND",
                                parser_class=_Parser)
    for builder, handler in SUBCOMMANDS.values():
        builder(sub).set_defaults(func=handler)
    return parser


def _one_line_warning(message: Warning | str, category: type[Warning], filename: str,
                      lineno: int, line: str | None = None) -> str:
    return f"warning: {message}\n"


def main(argv: list[str] | None = None) -> int:
    """Entry point; returns the exit status (2: bad input, one line on stderr; 130: Ctrl-C,
    one line saying where the partial results are, if any)."""
    command = "slipenv"
    try:
        try:
            args = build_parser().parse_args(argv)
        except SystemExit as exc:  # argparse: --help, --version, or a usage error already printed
            return int(exc.code or 0)
        command = f"slipenv {args.command}"
        if args.command not in NEEDS_NO_PHYSICS:
            from slipenv.pybullet_quiet import import_pybullet

            import_pybullet()  # first import of PyBullet in the process: no build-time banner
        # A warning is one line on a terminal ("warning: ..."), not Python's two with the
        # source line; restored after, so callers of main() keep their own format.
        default_format = warnings.formatwarning
        warnings.formatwarning = _one_line_warning
        try:
            return args.func(args)
        finally:
            warnings.formatwarning = default_format
    except ValueError as exc:
        print(f"{command}: error: {exc}".splitlines()[0], file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:
        # A handler marks what it leaves behind with ``partial_results``; the rest of the
        # traceback (tens of lines of the simulator's internals) tells the user nothing.
        fresh_line = "\n" if sys.stderr.isatty() else ""  # after the terminal's "^C"
        print(f"{fresh_line}{command}: {interrupted_message(exc)}", file=sys.stderr)
        return INTERRUPTED_STATUS


if __name__ == "__main__":
    sys.exit(main())

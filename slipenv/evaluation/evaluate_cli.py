"""``slipenv evaluate ENV_ID --policy P --episodes N --seed S``: the subcommand's parser and main.

Registered by :mod:`slipenv.cli` with ``add_parser(sub)``; ``main(args)`` returns the exit code.
Bad input (env id, policy name, model path, env-kwargs JSON, an output path that cannot be
written) exits with code 2 and one line on stderr before any episode runs.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from slipenv.evaluation.policies import BUILTIN_POLICIES

DEFAULT_OUT = "runs/evaluate/{env}_{policy}"


def parse_env_kwargs(text: str | None) -> dict:
    """``--env-kwargs`` JSON -> dict (ValueError naming the option on bad JSON)."""
    if not text:
        return {}
    try:
        value = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ValueError(f"--env-kwargs: not valid JSON ({exc.msg} at char {exc.pos})") from None
    if not isinstance(value, dict):
        raise ValueError(f"--env-kwargs: must be a JSON object, got {type(value).__name__}")
    return value


def add_parser(sub: Any) -> argparse.ArgumentParser:
    """Add the ``evaluate`` subcommand to ``sub`` (an ``add_subparsers()`` result)."""
    p = sub.add_parser("evaluate", help="evaluate a controller or agent over seeds (true-pose "
                                        "metrics, table, plot, JSON, TUM trajectories)")
    p.add_argument("env_id", help="e.g. slipenv/TrackedSlopeCircle-v0 (see `slipenv list`)")
    p.add_argument("--policy", default="baseline",
                   help=f"{' | '.join(BUILTIN_POLICIES)} | PATH to an SB3 .zip")
    p.add_argument("--episodes", type=int, default=5, help="episodes, seeds S..S+N-1")
    p.add_argument("--seed", type=int, default=0, help="first seed")
    p.add_argument("--env-kwargs", default=None,
                   help='JSON overrides of the preset, e.g. \'{"soil": "field_loam"}\'')
    p.add_argument("--max-steps", type=int, default=None, help="step limit per episode")
    p.add_argument("--json", default=None, help="write the evaluation as JSON")
    p.add_argument("--out", default=DEFAULT_OUT,
                   help="folder for the plot and TUM trajectories ({env} = the env's name, "
                        "{policy} = the policy's name or the model file's stem)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=main)
    return p


def _fail(message: str) -> int:
    print(f"slipenv evaluate: error: {message}", file=sys.stderr)
    return 2


def main(args: argparse.Namespace) -> int:
    """Run ``slipenv evaluate``; 0 on success, 2 on bad input."""
    from slipenv.cli_outputs import output_dir, output_file, partial_results
    from slipenv.evaluation.evaluator import check_env, evaluate
    from slipenv.evaluation.policies import resolve_policy

    try:
        env_kwargs = parse_env_kwargs(args.env_kwargs)
        if args.episodes < 1:
            raise ValueError(f"--episodes must be >= 1, got {args.episodes}")
        if args.max_steps is not None and args.max_steps < 1:
            raise ValueError(f"--max-steps must be >= 1, got {args.max_steps}")
        check_env(args.env_id, env_kwargs)
        source = resolve_policy(args.policy)
        label = Path(source.label).stem if source.kind == "model" else source.label
        out = output_dir(_fill(args.out or DEFAULT_OUT, env=args.env_id.split("/")[-1],
                               policy=label), "--out")
        json_path = output_file(args.json, "--json")
    except ValueError as exc:
        return _fail(str(exc).splitlines()[0])
    seeds = range(args.seed, args.seed + args.episodes)
    ev = evaluate(source, args.env_id, seeds, env_kwargs, max_steps=args.max_steps,
                  progress=not args.quiet)
    print(ev.table())
    from slipenv.evaluation.plots import plot_evaluation

    with partial_results(out, json_path):
        png = plot_evaluation(ev, out / "evaluation.png")
        tum = ev.export_tum(out / "tum")
        print(f"plot: {png}")
        print(f"TUM trajectories ({len(tum)} files): {out / 'tum'}  "
              f"(e.g. evo_ape tum {tum[0].name} {tum[1].name})")
        if json_path is not None:
            print(f"JSON: {ev.write_json(json_path)}")
    return 0


def _fill(template: str, **fields: str) -> str:
    """``template`` with ``{name}`` fields replaced (other braces are left as they are)."""
    for name, value in fields.items():
        template = template.replace("{" + name + "}", value)
    return template

"""``tolins train bc|rs-gail|tolerance-guided``, their options generated from the run
configs (:mod:`tolins.learning.imitation.config`)."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from tolins.cli import checks
from tolins.cli.args import add_config_arguments, config_from_args
from tolins.learning.imitation.config import BCConfig, ResidualConfig, RSGailConfig, TaskConfig

if TYPE_CHECKING:
    from tolins.learning.imitation.runs import Demos

#: The config dataclasses whose fields are the options of each method.
_CONFIGS: dict[str, tuple[type, ...]] = {
    "bc": (TaskConfig, BCConfig),
    "rs-gail": (TaskConfig, BCConfig, RSGailConfig),
    "tolerance-guided": (TaskConfig, RSGailConfig, ResidualConfig),
}
#: ``tolins.learning.imitation.rs_gail.CHECKPOINT``, named here without importing torch
#: (a test holds them equal).
CHECKPOINT = "checkpoint.pt"
_HELP = {
    "bc": "behaviour cloning of a scripted expert",
    "rs-gail": "the nominal policy π_n by RS-GAIL (CMA-ES) from a BC policy",
    "tolerance-guided": "the residual φ2 of π_φ by RS-GAIL over several workpieces",
}


def add_parser(commands: argparse._SubParsersAction) -> None:
    """Add ``train bc|rs-gail|tolerance-guided`` to the ``tolins`` parser."""
    train = commands.add_parser("train", help="train policies (BC, RS-GAIL, tolerance-guided)")
    methods = train.add_subparsers(dest="method", required=True)
    for method, help_text in _HELP.items():
        parser = methods.add_parser(method, help=help_text)
        several = method == "tolerance-guided"
        env_help = "preset env ids, comma-separated" if several else "a preset env id"
        parser.add_argument(
            "--env",
            required=True,
            type=checks.preset_env_ids(several=several),
            help=f"{env_help}, e.g. tolins/Circle2x2-v1",
        )
        out_help = "output folder (its files are replaced)"
        if method != "bc":
            out_help = "output folder (a new run, or --resume to continue its checkpoint)"
        parser.add_argument("--out", required=True, help=out_help)
        for config in _CONFIGS[method]:
            add_config_arguments(parser, config)
        if method in ("bc", "rs-gail"):
            parser.add_argument(
                "--demos",
                metavar="DATASET",
                help="demonstrations from a Minari dataset of --env (a folder or a local id; "
                "docs/datasets.md) instead of the expert's (--expert, --demonstrations unused)",
            )
        if method == "rs-gail":
            parser.add_argument("--init", help="BC policy.pt to start from (default: clone here)")
        if method == "tolerance-guided":
            parser.add_argument("--nominal", required=True, help="π_n's policy.pt (φ1)")
        if method != "bc":
            parser.add_argument("--resume", action="store_true", help="continue OUT/checkpoint")
        parser.set_defaults(run=run)


def _check_paths(args: argparse.Namespace) -> None:
    """Raise :class:`~tolins.cli.checks.OptionError` for a bad --out, --init or --nominal."""
    out = checks.output_folder("--out", args.out)
    for option in ("init", "nominal"):
        if getattr(args, option, None) is not None:
            checks.input_file(f"--{option}", getattr(args, option))
    if args.method == "bc":
        return
    found = (out / CHECKPOINT).exists()
    if not args.resume and found:
        raise checks.OptionError(
            f"--out {out}: holds {CHECKPOINT} of an earlier run; allowed: --resume to "
            "continue it, or a folder without one"
        )
    if args.resume and not found:
        raise checks.OptionError(
            f"--resume: no checkpoint found in {out} (no {CHECKPOINT}); allowed: --out the "
            "folder of an earlier run, or no --resume to start a new one"
        )


def _check_policies(args: argparse.Namespace) -> None:
    """Raise :class:`~tolins.cli.checks.OptionError` unless --init and --nominal (when
    given) are nominal policy files."""
    for option in ("init", "nominal"):
        path = getattr(args, option, None)
        if path is None:
            continue
        from tolins.learning.imitation.policy import load_policy

        try:
            load_policy(path, kind="nominal")
        except ValueError as error:
            raise checks.OptionError(f"--{option}: {error}") from None


def _demos(args: argparse.Namespace) -> Demos | None:
    """The episodes of ``--demos``, checked against ``--env``; ``None`` without the
    option. Raises ``ValueError``."""
    if getattr(args, "demos", None) is None:
        return None
    from tolins.datasets.reader import load_demonstrations, require_minari

    try:
        require_minari("--demos")
    except ImportError as error:
        raise checks.OptionError(str(error)) from None
    from tolins.learning.imitation.runs import Demos

    return Demos(str(args.demos), load_demonstrations(args.demos, args.env))


def run(args: argparse.Namespace) -> int:
    """Check every option, train, and say what was written: a bad option exits 2, a run
    that refuses to start or go on (:class:`~tolins.learning.artefacts.RunRefused`: a
    checkpoint of another configuration, a diverged training) 3, each with one line."""
    prog = f"tolins train {args.method}"
    try:
        configs = {cls.__name__: config_from_args(cls, args) for cls in _CONFIGS[args.method]}
        _check_paths(args)
        _check_policies(args)
        demos = _demos(args)
    except ValueError as error:  # OptionError, a config's check, a --demos dataset's
        return checks.fail(prog, error)
    from tolins.learning.artefacts import RunRefused
    from tolins.learning.imitation import runs

    try:
        task = configs["TaskConfig"]
        if args.method == "bc":
            result = runs.run_bc(args.env, task, configs["BCConfig"], args.out, demos=demos)
            print(
                f"wrote {args.out}: BC loss {result.losses[0]:.4f} → {result.losses[-1]:.4f}, "
                f"held-out {result.held_out_loss:.4f} ({result.held_out_episodes} episodes)"
            )
            return 0
        if args.method == "rs-gail":
            result = runs.run_rs_gail(
                args.env,
                task,
                configs["BCConfig"],
                configs["RSGailConfig"],
                args.out,
                init=args.init,
                resume=args.resume,
                demos=demos,
            )
        else:
            result = runs.run_tolerance_guided(
                args.env.split(","),
                task,
                configs["RSGailConfig"],
                configs["ResidualConfig"],
                args.out,
                nominal=args.nominal,
                resume=args.resume,
            )
    except RunRefused as error:
        return checks.refused(prog, error)
    except FileNotFoundError as error:
        return checks.fail(prog, error)
    final = result.final
    print(
        f"wrote {args.out}: {len(result.history)} iterations ({result.stopped}); final policy: "
        f"reward {final['reward']:.2f}, success {final['success']:.2f}, "
        f"D(student) {final['d_expert']:.2f}"
    )
    return 0

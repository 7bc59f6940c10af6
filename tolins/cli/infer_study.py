"""``tolins infer-study``: the paper's probabilistic-inference study, its options generated
from :class:`~tolins.inference.study.StudyConfig`."""

from __future__ import annotations

import argparse
import time

from tolins.cli import checks
from tolins.cli.args import Option, add_config_arguments, config_from_args
from tolins.geometry.delicate import PIN_MODELS
from tolins.geometry.materials import MATERIALS
from tolins.inference.study import METHODS, StudyConfig

#: The study's settings the command line leaves at their defaults.
_FIXED = ("max_attempts", "kinds", "not_insertable_below")


def add_parser(commands: argparse._SubParsersAction) -> None:
    """Add ``infer-study`` to the ``tolins`` parser."""
    study = commands.add_parser(
        "infer-study", help="the paper's probabilistic-inference study (2*1, bent pins)"
    )
    counts = Option(type=checks.positive_int)
    options = {
        "samples": counts,
        "particles": counts,
        "workers": counts,
        "kind_samples": counts,
        "methods": Option(
            action=checks.JoinedList,
            default=None,
            help=f"comma-separated subset of {', '.join(METHODS)} (default: all); "
            "repeated, they add up",
        ),
        "pins": Option(choices=PIN_MODELS),
        "pin_material": Option(choices=sorted(MATERIALS)),
    }
    add_config_arguments(study, StudyConfig, options, skip=_FIXED)
    study.add_argument(
        "--json", metavar="OUT.json", help="write the figures as JSON (replaced if present)"
    )
    study.add_argument(
        "--plot", metavar="OUT.png", help="save the cumulative-success plot (replaced if present)"
    )
    study.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Run the study with a progress bar, print its table and write the files asked for."""
    if args.json:
        checks.output_file("--json", args.json)
    if args.plot:
        checks.output_file("--plot", args.plot, suffixes=(".png",))
    from tqdm import tqdm

    from tolins.inference.report import format_table, save_plot, write_json
    from tolins.inference.study import parse_methods, run_study

    try:
        methods = StudyConfig.methods if args.methods is None else parse_methods(args.methods)
        # pins that bend: the bent workpieces only (the per-kind study keeps rigid pins)
        kinds = StudyConfig.kinds if args.pins == "rigid" else ("bent",)
        config = config_from_args(StudyConfig, args, methods=methods, kinds=kinds)
    except ValueError as error:
        return checks.fail("tolins infer-study", error)
    start = time.perf_counter()
    with tqdm(total=config.samples, desc="inference study", unit="workpiece") as bar:
        result = run_study(config, on_workpiece=lambda _: bar.update())
    print(format_table(result))
    print(f"seed {config.seed}, {config.particles} particles, {time.perf_counter() - start:.0f} s")
    if args.json:
        print(f"wrote {write_json(result, args.json)}")
    if args.plot:
        print(f"wrote {save_plot(result, args.plot)}")
    return 0

"""``tolins bench``: :func:`tolins.bench.pipeline.runner.run_bench`, its options generated
from :class:`~tolins.bench.pipeline.config.BenchConfig`."""

from __future__ import annotations

import argparse
import sys
import traceback
from pathlib import Path
from typing import TYPE_CHECKING

from tolins.bench.pipeline.config import SEEDS_MAX, BenchConfig
from tolins.bench.pipeline.executor import EXECUTORS, failed_stage
from tolins.bench.pipeline.profiles import PROFILES
from tolins.cli import checks
from tolins.cli.args import Option, add_config_arguments, config_from_args
from tolins.physics import BACKENDS

if TYPE_CHECKING:
    from tolins.bench.pipeline.runner import PlannedStage


def add_parser(commands: argparse._SubParsersAction) -> None:
    """Add ``bench`` to the ``tolins`` parser."""
    bench = commands.add_parser(
        "bench",
        help="train and evaluate the paper's Table 1 and its inference study, with reports",
        description="Train what each row of the paper's Table 1 needs, evaluate every row "
        "and run the inference study; write results.json, results.md, plots and rerun "
        "recordings into --out. Stages are cached by config hash: an interrupted run "
        "resumes, a finished one is only re-reported.",
    )
    options = {
        "profile": Option(choices=PROFILES),
        "rows": Option(
            action=checks.JoinedList,
            help="comma-separated row ids, e.g. C2.1,C2.3 (default: all); repeated, they add up",
        ),
        "backend": Option(choices=BACKENDS),
        "seeds": Option(
            type=checks.positive_int,
            help=f"training seeds, at most {SEEDS_MAX} (default: the profile's)",
        ),
        "out": Option(default=None, help="output folder (default: results/PROFILE)"),
        "workers": Option(type=checks.positive_int),
        "executor": Option(choices=EXECUTORS),
    }
    add_config_arguments(bench, BenchConfig, options)
    bench.add_argument(
        "--dry-run",
        action="store_true",
        help="print the stages still to run and their expected cost, and run nothing",
    )
    bench.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Check every option, run the bench, and print its table and claims. A bad option,
    a missing optional part (the Panda's ``tolins[robot]``) or a damaged stage file is one
    line and exit status 2; a training that refused to go on (its checkpoint from another
    configuration, a diverged run: :class:`~tolins.learning.artefacts.RunRefused`) one line
    and exit status 3; any other stage that raised is its traceback and exit status 1."""
    try:
        out = checks.output_folder("--out", args.out or Path("results") / args.profile)
        config = config_from_args(BenchConfig, args, out=str(out))
        if config.robot and config.backend == "mujoco":
            checks.require_robot("its Panda table (on by default; --no-robot leaves it out)")
    except ValueError as error:  # OptionError too
        return checks.fail("tolins bench", error)
    from tolins.bench.pipeline.runner import plan_bench, run_bench
    from tolins.bench.reports.markdown import format_claims, format_results_table
    from tolins.bench.store.integrity import StageFileError
    from tolins.learning.artefacts import RunRefused

    if args.dry_run:
        try:
            print(format_plan(plan_bench(config), config))
        except (ValueError, FileNotFoundError) as error:
            return checks.fail("tolins bench", error)
        return 0

    try:
        bench = run_bench(config)
    except (ValueError, FileNotFoundError, RunRefused) as error:
        stage = failed_stage(error)
        if isinstance(error, RunRefused):  # a training that will not go on: say why
            where = "tolins bench" if stage is None else f"tolins bench: stage {stage}"
            return checks.refused(where, error)
        if stage is None or isinstance(error, StageFileError):  # refused, or a file damaged
            return checks.fail("tolins bench", error)
        traceback.print_exception(error)
        print(
            f"tolins bench: stage {stage} failed ({type(error).__name__}, its traceback "
            "above); the finished stages are kept: the same command resumes",
            file=sys.stderr,
        )
        return 1
    print(format_results_table(bench.results))
    print("\nThe paper's claims in this run:")
    print(format_claims(bench.claims))
    plots = " and plots" if config.figures else ""
    print(f"\n{bench.wall_s / 60:.1f} min; wrote {config.out}/results.md, results.json{plots}")
    return 0


def format_plan(stages: list[PlannedStage], config: BenchConfig) -> str:
    """``tolins bench --dry-run``'s report: per kind of stage, how many are finished, how
    many to run and their expected work, and how long that work takes on
    ``config.workers`` run as the executors run it (its dependencies, the costliest chain
    first: :func:`~tolins.bench.pipeline.progress.schedule_length`)."""
    from tolins.bench.pipeline.progress import KINDS, format_duration, schedule_length, stage_kind

    def work(of: list[PlannedStage]) -> float:
        return sum(stage.expected_s for stage in of)

    todo = [stage for stage in stages if not stage.finished]
    lines = [
        f"{len(stages)} stages in {config.out}: {len(stages) - len(todo)} finished, "
        f"{len(todo)} to run",
        "",
        "| stages | finished | to run | expected work to run |",
        "|---|--:|--:|--:|",
    ]
    for kind in KINDS:
        of_kind = [stage for stage in stages if stage_kind(stage.name) == kind]
        if of_kind:
            left = [stage for stage in of_kind if not stage.finished]
            done = len(of_kind) - len(left)
            lines.append(f"| {kind} | {done} | {len(left)} | {format_duration(work(left))} |")
    total = work(todo)
    lines.append(f"| all | {len(stages) - len(todo)} | {len(todo)} | {format_duration(total)} |")
    place = "cores" if config.executor == "local" else "Ray CPUs"
    expected = {stage.name: stage.expected_s for stage in todo}
    needs = {stage.name: stage.needs for stage in todo}
    wall = schedule_length(needs, expected, expected, (), config.workers)
    lines += [
        "",
        f"About {format_duration(wall)} on {config.workers} {place} (--workers), the "
        "stages run as the executor orders them: each stage's budget at the speed per env "
        "step of an idle quick bench on 2 cores (tolins.bench.pipeline.progress."
        "STEP_SECONDS). Nothing was run.",
    ]
    return "\n".join(lines)

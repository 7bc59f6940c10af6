"""``tolins bench``: the command-line face of :func:`tolins.bench.runner.run_bench`."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from tolins.bench.config import BACKENDS, SEEDS_MAX, BenchConfig
from tolins.bench.executor import EXECUTORS
from tolins.bench.profiles import PROFILES
from tolins.cli_checks import JoinedList, fail, output_folder, positive_int


def add_bench_parser(commands: argparse._SubParsersAction) -> None:
    """Add ``bench`` to the ``tolins`` parser."""
    bench = commands.add_parser(
        "bench",
        help="train and evaluate the paper's Table 1 and its inference study, with reports",
        description="Train what each row of the paper's Table 1 needs, evaluate every row "
        "and run the inference study; write results.json, results.md, plots and rerun "
        "recordings into --out. Stages are cached by config hash: an interrupted run "
        "resumes, a finished one is only re-reported.",
    )
    bench.add_argument(
        "--profile",
        default="quick",
        choices=list(PROFILES),
        help="budgets: quick (≤ 15 min on 2 cores), paper (the paper's), tiny (smoke test)",
    )
    bench.add_argument(
        "--rows",
        action=JoinedList,
        help="comma-separated row ids, e.g. C2.1,C2.3 (default: all); repeated, they add up",
    )
    bench.add_argument("--backend", default="mujoco", choices=BACKENDS, help="simulator")
    bench.add_argument(
        "--seeds",
        type=positive_int,
        help=f"training seeds, at most {SEEDS_MAX} (default: the profile's)",
    )
    bench.add_argument("--out", help="output folder (default: results/PROFILE)")
    bench.add_argument("--workers", type=positive_int, default=2, help="evaluation threads")
    bench.add_argument("--no-study", action="store_true", help="skip the inference study")
    bench.add_argument(
        "--no-robustness", action="store_true", help="skip the robustness table (grades, defects)"
    )
    bench.add_argument(
        "--executor",
        default="local",
        choices=EXECUTORS,
        help="where stages run: local (this process) or ray (Ray tasks; pip install "
        "'tolins[ray]'); results are identical",
    )
    bench.add_argument(
        "--address",
        help="with --executor ray: auto or HOST:PORT of a running Ray cluster "
        "(default: start Ray on this machine)",
    )
    bench.set_defaults(run=_run)


def _run(args: argparse.Namespace) -> int:
    try:
        out = output_folder("--out", args.out or Path("results") / args.profile)
        config = BenchConfig(
            profile=args.profile,
            rows=args.rows,
            backend=args.backend,
            seeds=args.seeds,
            out=str(out),
            study=not args.no_study,
            robustness=not args.no_robustness,
            workers=args.workers,
            executor=args.executor,
            address=args.address,
        )
    except ValueError as error:  # OptionError too
        return fail("tolins bench", error)
    from tolins.bench.report import format_claims, format_results_table
    from tolins.bench.runner import run_bench

    try:
        run = run_bench(config)
    except (ValueError, FileNotFoundError) as error:
        print(f"tolins bench: {error}", file=sys.stderr)
        return 2
    print(format_results_table(run.results))
    print("\nThe paper's claims in this run:")
    print(format_claims(run.claims))
    print(f"\n{run.wall_s / 60:.1f} min; wrote {config.out}/results.md, results.json and plots")
    return 0


def add_evaluate_parser(commands: argparse._SubParsersAction) -> None:
    """Add ``evaluate`` to the ``tolins`` parser."""
    from tolins.learning.external import ALLOWED

    evaluate = commands.add_parser(
        "evaluate",
        help="score any policy on the bench's evaluation protocol, beside the reference rows",
        description="Evaluate a policy like a row of `tolins bench` (same evaluation seeds, "
        "sparse reward, summary and results.json schema) and print it beside the rows of "
        f"the same eval env. --policy: {ALLOWED}.",
    )
    evaluate.add_argument(
        "--policy",
        required=True,
        help="MODULE:NAME (imports that module: it runs its code), PATH, PATH.zip or expert",
    )
    evaluate.add_argument(
        "--trust-pickle",
        action="store_true",
        help="load an SB3 PATH.zip with SB3's own load, which unpickles and so runs code "
        "stored in the zip (default: rebuilt from its JSON and weights, without pickle)",
    )
    evaluate.add_argument("--env", required=True, help="eval env id, e.g. tolins/Circle2x2-v1")
    evaluate.add_argument("--episodes", type=positive_int, default=100, help="evaluation episodes")
    evaluate.add_argument("--backend", default="mujoco", choices=BACKENDS, help="simulator")
    evaluate.add_argument("--name", help="the row's label (default: --policy)")
    evaluate.add_argument("--out", help="write DIR/results.json (the bench's schema)")
    evaluate.add_argument(
        "--reference",
        metavar="DIR",
        help="the rows to show beside it: a `tolins bench` results folder or results.json, "
        "or reference:NAME (shipped); default: a shipped reference of --backend, else the "
        "paper's Table 1",
    )
    evaluate.set_defaults(run=_evaluate)


def _evaluate(args: argparse.Namespace) -> int:
    if args.out:
        output_folder("--out", args.out)
    from tolins.bench.scoring import (
        evaluate_policy,
        format_rows,
        reference_rows,
        write_evaluation,
    )

    name = args.name or args.policy
    from tolins.learning.external import trust_pickle

    trust_pickle(args.trust_pickle)  # this command's choice, not an earlier call's
    try:
        source, rows = reference_rows(args.env, args.reference, backend=args.backend)
        profile = Path(args.out) / "force_profile.png" if args.out else None
        entry = evaluate_policy(
            args.policy,
            args.env,
            episodes=args.episodes,
            backend=args.backend,
            name=name,
            profile_plot=profile,
        )
    except (ValueError, FileNotFoundError) as error:
        print(f"tolins evaluate: {error}", file=sys.stderr)
        return 2
    print(format_rows({name: entry}))
    if rows:
        print(f"\nreference rows on {args.env}, from {source}:")
        print(format_rows(rows))
    from tolins.bench.force_table import format_force_table

    forces = format_force_table({name: entry, **rows})
    if forces:
        print(f"\ncontact forces (tolins.rollouts.forces):\n{forces}")
    print(
        f"\n{entry['episodes']} episodes (seeds 10000…), {args.backend} backend, "
        f"{entry['faults']} simulator faults"
    )
    if args.out:
        print(f"wrote {write_evaluation(args.out, name, entry, backend=args.backend)}, {profile}")
    return 0

"""``tolins evaluate``: any policy on the bench's evaluation protocol
(:func:`tolins.bench.evaluate.evaluate_policy`), printed beside the reference rows."""

from __future__ import annotations

import argparse
from pathlib import Path

from tolins.cli import checks
from tolins.learning.agents.external import ALLOWED
from tolins.physics import BACKENDS


def add_parser(commands: argparse._SubParsersAction) -> None:
    """Add ``evaluate`` to the ``tolins`` parser."""
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
        help=checks.TRUST_PICKLE_HELP,
    )
    evaluate.add_argument("--env", required=True, help="eval env id, e.g. tolins/Circle2x2-v1")
    evaluate.add_argument(
        "--episodes", type=checks.positive_int, default=100, help="evaluation episodes"
    )
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
    evaluate.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Evaluate the policy, print its row beside the reference rows, and write them."""
    checks.require_robot_for(args.env, "--env")
    if args.out:
        checks.output_folder("--out", args.out)
    from tolins.bench.evaluate import evaluate_policy, format_rows, reference_rows, write_evaluation
    from tolins.learning.agents.external import trust_pickle

    name = args.name or args.policy
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
        return checks.fail("tolins evaluate", error)
    print(format_rows({name: entry}))
    if rows:
        print(f"\nreference rows on {args.env}, from {source}:")
        print(format_rows(rows))
    from tolins.bench.table.force_table import format_force_table

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

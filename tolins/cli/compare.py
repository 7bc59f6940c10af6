"""``tolins compare``: two bench results side by side, row by row
(:func:`tolins.bench.table.compare.compare`)."""

from __future__ import annotations

import argparse

from tolins.cli import checks


def add_parser(commands: argparse._SubParsersAction) -> None:
    """Add ``compare`` to the ``tolins`` parser."""
    compare = commands.add_parser(
        "compare",
        help="two results side by side per row, with the 95 %% CI of each difference",
        description="Compare two `tolins bench` results (folders, results.json files or "
        "reference:NAME, a shipped reference) row by row: each row's mean reward in A and "
        "B and the 95 % bootstrap CI of A − B, over training seeds when both have ≥ 2, "
        "else over episodes (stated, with the margin a trained row must clear). A row "
        "differs when its CI lies beyond that margin, else it is consistent.",
    )
    compare.add_argument(
        "a", metavar="RESULTS_A", help="results folder, results.json or reference:NAME"
    )
    compare.add_argument(
        "b", metavar="RESULTS_B", help="results folder, results.json or reference:NAME"
    )
    compare.add_argument("--json", metavar="OUT.json", help="also write the comparison as JSON")
    compare.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Print the comparison (and write it as JSON with ``--json``)."""
    if args.json:
        checks.output_file("--json", args.json, suffixes=(".json",))
    from tolins.bench.table.compare import compare, comparison_json, format_comparison

    try:
        result = compare(args.a, args.b)
    except ValueError as error:
        return checks.fail("tolins compare", error)
    print(format_comparison(result))
    if args.json:
        from tolins.atomic import atomic_json

        print(f"wrote {atomic_json(args.json, comparison_json(result))}")
    return 0

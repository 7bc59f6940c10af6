"""``tolins demo``: both experts in every preset environment, as a table."""

from __future__ import annotations

import argparse
import time

from tolins.cli.checks import positive_int, seed
from tolins.physics import BACKENDS


def add_parser(commands: argparse._SubParsersAction) -> None:
    """Add ``demo`` to the ``tolins`` parser."""
    demo = commands.add_parser(
        "demo", help="roll out both experts in every preset environment and print a table"
    )
    demo.add_argument("--episodes", type=positive_int, default=100, help="episodes per row")
    demo.add_argument("--seed", type=seed, default=0, help="seed of the first episode")
    demo.add_argument("--workers", type=positive_int, default=2, help="threads")
    demo.add_argument("--backend", default="mujoco", choices=BACKENDS, help="simulator")
    demo.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Roll out and print the table with what it took."""
    from tolins.demo import format_table, run_demo

    start = time.perf_counter()
    rows = run_demo(args.episodes, args.seed, args.workers, args.backend)
    print(format_table(rows))
    print(
        f"\n{args.episodes} episodes per row, seeds {args.seed}…{args.seed + args.episodes - 1}, "
        f"backend {args.backend}, {time.perf_counter() - start:.1f} s"
    )
    return 0

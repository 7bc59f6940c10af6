"""The ``tolins`` command: wires arguments to library functions."""

from __future__ import annotations

import argparse
import sys
import time


def _demo(args: argparse.Namespace) -> int:
    from tolins.demo import format_table, run_demo

    start = time.perf_counter()
    rows = run_demo(args.episodes, args.seed, args.workers, args.backend)
    print(format_table(rows))
    print(
        f"\n{args.episodes} episodes per row, seeds {args.seed}…{args.seed + args.episodes - 1}, "
        f"backend {args.backend}, {time.perf_counter() - start:.1f} s"
    )
    return 0


def _positive_int(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"{value} is not allowed; allowed: an integer ≥ 1")
    return value


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="tolins", description=__doc__)
    commands = parser.add_subparsers(dest="command", required=True)
    demo = commands.add_parser(
        "demo", help="roll out both experts in every preset environment and print a table"
    )
    demo.add_argument("--episodes", type=_positive_int, default=100, help="episodes per row")
    demo.add_argument("--seed", type=int, default=0, help="seed of the first episode")
    demo.add_argument("--workers", type=_positive_int, default=2, help="threads")
    demo.add_argument("--backend", default="mujoco", choices=["mujoco"], help="simulator")
    demo.set_defaults(run=_demo)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    return args.run(args)


if __name__ == "__main__":
    sys.exit(main())

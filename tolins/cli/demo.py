"""``tolins demo``: both experts in every preset environment, as a table."""

from __future__ import annotations

import argparse
import sys
import time

from tolins.cli import checks
from tolins.cli.checks import positive_int, seed
from tolins.physics import BACKENDS

#: Episodes per Panda row by default: a Panda control step costs 23–31 ms, 4–35 times the
#: free body's (docs/robot.md); the 16 Panda rows' 160 episodes took 2.4 CPU-minutes.
ROBOT_EPISODES = 10


def add_parser(commands: argparse._SubParsersAction) -> None:
    """Add ``demo`` to the ``tolins`` parser."""
    demo = commands.add_parser(
        "demo",
        help="roll out both experts in every preset environment and print a table",
        description="Both experts in the newest id of every paper preset (-v2) and, with "
        "tolins[robot] on MuJoCo, in the Franka Panda's of the same workpieces (-v3).",
    )
    demo.add_argument("--episodes", type=positive_int, default=100, help="episodes per row")
    demo.add_argument(
        "--robot-episodes",
        type=checks.non_negative_int,
        default=ROBOT_EPISODES,
        help="episodes per Panda row (0: no Panda rows)",
    )
    demo.add_argument("--seed", type=seed, default=0, help="seed of the first episode")
    demo.add_argument("--workers", type=positive_int, default=2, help="threads")
    demo.add_argument("--backend", default="mujoco", choices=BACKENDS, help="simulator")
    demo.set_defaults(run=run)


def _robot_episodes(args: argparse.Namespace) -> int:
    """``--robot-episodes``, or 0 (saying why on stderr) where the Panda cannot run."""
    if not args.robot_episodes:
        return 0
    if args.backend != "mujoco":
        print(
            f"tolins demo: no Panda rows on --backend {args.backend} (MuJoCo only)", file=sys.stderr
        )
        return 0
    try:
        checks.require_robot("its Panda rows")
    except checks.OptionError as error:
        print(f"tolins demo: {error}; running without them", file=sys.stderr)
        return 0
    return args.robot_episodes


def run(args: argparse.Namespace) -> int:
    """Roll out and print the table with what it took."""
    from tolins.demo import format_table, run_demo

    robot_episodes = _robot_episodes(args)
    start = time.perf_counter()
    rows = run_demo(
        args.episodes, args.seed, args.workers, args.backend, robot_episodes=robot_episodes
    )
    print(format_table(rows))
    robot = f", {robot_episodes} per Panda row" if robot_episodes else ""
    print(
        f"\n{args.episodes} episodes per row{robot}, seeds {args.seed}…"
        f"{args.seed + max(args.episodes, robot_episodes) - 1}, "
        f"backend {args.backend}, {time.perf_counter() - start:.1f} s"
    )
    return 0

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


def _record(args: argparse.Namespace) -> int:
    import gymnasium as gym
    from tqdm import tqdm

    import tolins  # noqa: F401  (registers the env ids)
    from tolins.policies.experts import EXPERTS
    from tolins.record import record_episodes
    from tolins.record.recorder import check_output_path

    if args.env not in gym.registry:
        ids = sorted(i for i in gym.registry if i.startswith("tolins/"))
        print(
            f"tolins record: unknown --env {args.env!r}; allowed: {', '.join(ids)}", file=sys.stderr
        )
        return 2
    try:
        check_output_path(args.out)
    except ValueError as error:
        print(f"tolins record: {error}", file=sys.stderr)
        return 2
    env = gym.make(args.env)
    try:
        with tqdm(total=args.episodes, desc=f"recording {args.env}", unit="episode") as bar:
            episodes = record_episodes(
                env,
                EXPERTS[args.policy](),
                args.episodes,
                args.out,
                seed=args.seed,
                policy_name=args.policy,
                on_episode=lambda _: bar.update(),
            )
    except ValueError as error:
        print(f"tolins record: {error}", file=sys.stderr)
        return 2
    finally:
        env.close()
    successes = sum(e.success for e in episodes)
    print(f"wrote {args.out}: {len(episodes)} episodes, {successes} successful")
    return 0


def _replay(args: argparse.Namespace) -> int:
    from tolins.record import RrdError, replay

    try:
        return replay(args.file, web=args.web, screenshot=args.screenshot, web_port=args.port)
    except (RrdError, ValueError, RuntimeError) as error:
        print(f"tolins replay: {error}", file=sys.stderr)
        return 1


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
    demo.add_argument(
        "--backend", default="mujoco", choices=["mujoco", "kinematic"], help="simulator"
    )
    demo.set_defaults(run=_demo)
    record = commands.add_parser("record", help="record expert episodes to a rerun .rrd file")
    record.add_argument("--env", required=True, help="env id, e.g. tolins/Circle2x2-v0")
    record.add_argument("--policy", default="safe", choices=["safe", "efficient"], help="expert")
    record.add_argument("--episodes", type=_positive_int, default=5, help="episodes")
    record.add_argument("--out", required=True, help="output file, FILE.rrd")
    record.add_argument("--seed", type=int, default=0, help="seed of the first episode")
    record.set_defaults(run=_record)
    replay = commands.add_parser("replay", help="show a .rrd recording in the rerun viewer")
    replay.add_argument("file", help="a .rrd file written by `tolins record`")
    mode = replay.add_mutually_exclusive_group()
    mode.add_argument("--web", action="store_true", help="serve the web viewer on 127.0.0.1")
    mode.add_argument("--screenshot", metavar="OUT.png", help="render headless to a PNG")
    replay.add_argument("--port", type=int, default=9090, help="web viewer port (with --web)")
    replay.set_defaults(run=_replay)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    return args.run(args)


if __name__ == "__main__":
    sys.exit(main())

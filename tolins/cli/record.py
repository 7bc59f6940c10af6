"""``tolins record`` and ``tolins replay``: a policy's episodes to a rerun ``.rrd`` file,
and that file in the rerun viewer."""

from __future__ import annotations

import argparse
import sys

from tolins.cli import checks
from tolins.physics import BACKENDS


def add_parser(commands: argparse._SubParsersAction) -> None:
    """Add ``record`` and ``replay`` to the ``tolins`` parser."""
    _add_record(commands)
    _add_replay(commands)


def _add_record(commands: argparse._SubParsersAction) -> None:
    record = commands.add_parser("record", help="record a policy's episodes to a rerun .rrd file")
    record.add_argument(
        "--env",
        required=True,
        type=checks.preset_env_ids(),
        help="a preset env id, e.g. tolins/Circle2x2-v1",
    )
    record.add_argument(
        "--policy",
        default="safe",
        help="safe, efficient (the experts), a tolins policy file PATH, an SB3 PATH.zip or "
        "MODULE:NAME (imports that module: it runs its code; as `tolins evaluate --policy`)",
    )
    record.add_argument(
        "--trust-pickle",
        action="store_true",
        help=checks.TRUST_PICKLE_HELP,
    )
    record.add_argument("--backend", default="mujoco", choices=BACKENDS, help="simulator")
    record.add_argument("--episodes", type=checks.positive_int, default=5, help="episodes")
    record.add_argument("--out", required=True, help="output file, FILE.rrd (replaced if present)")
    record.add_argument("--seed", type=checks.seed, default=0, help="seed of the first episode")
    record.set_defaults(run=run_record)


def _add_replay(commands: argparse._SubParsersAction) -> None:
    replay = commands.add_parser("replay", help="show a .rrd recording in the rerun viewer")
    replay.add_argument("file", help="a .rrd file written by `tolins record`")
    mode = replay.add_mutually_exclusive_group()
    mode.add_argument("--web", action="store_true", help="serve the web viewer on 127.0.0.1")
    mode.add_argument("--screenshot", metavar="OUT.png", help="render headless to a PNG")
    when = replay.add_mutually_exclusive_group()
    when.add_argument(
        "--step", type=int, help="the control step the screenshot shows (default: the last)"
    )
    when.add_argument(
        "--time",
        type=checks.non_negative_float,
        metavar="SECONDS",
        help="the simulated time the screenshot shows",
    )
    replay.add_argument(
        "--port", type=checks.port, default=9090, help="web viewer port (with --web)"
    )
    replay.add_argument(
        "--grpc-port",
        type=checks.port,
        default=9876,
        help="port serving the recording (with --web)",
    )
    replay.set_defaults(run=run_replay)


def run_record(args: argparse.Namespace) -> int:
    """Record the episodes with a progress bar and say what was written."""
    checks.output_file("--out", args.out, suffixes=(".rrd",))
    import gymnasium as gym
    from tqdm import tqdm

    from tolins.learning.agents.actors import make_actor
    from tolins.learning.agents.external import trust_pickle
    from tolins.record import record_episodes

    trust_pickle(args.trust_pickle)  # this command's choice, not an earlier call's
    env = gym.make(args.env, backend=args.backend)
    try:
        policy = make_actor(args.policy, env.unwrapped.nominal_socket)
        with tqdm(total=args.episodes, desc=f"recording {args.env}", unit="episode") as bar:
            episodes = record_episodes(
                env,
                policy,
                args.episodes,
                args.out,
                seed=args.seed,
                policy_name=args.policy,
                on_episode=lambda _: bar.update(),
            )
    except ValueError as error:
        return checks.fail("tolins record", error)
    finally:
        env.close()
    successes = sum(e.success for e in episodes)
    print(f"wrote {args.out}: {len(episodes)} episodes, {successes} successful")
    return 0


def _check_replay(args: argparse.Namespace) -> None:
    """Raise :class:`~tolins.cli.checks.OptionError` for options that do not go together."""
    checks.input_file("FILE", args.file)
    if args.web and args.port == args.grpc_port:
        raise checks.OptionError(
            f"--port {args.port} is also --grpc-port; allowed: two different ports"
        )
    if args.screenshot is not None:
        checks.output_file("--screenshot", args.screenshot, suffixes=(".png",))
    picked = "--step" if args.step is not None else "--time" if args.time is not None else None
    if picked and args.screenshot is None:
        raise checks.OptionError(
            f"{picked} picks what a screenshot shows; allowed: with --screenshot"
        )
    if (args.step or 0) < 0:  # --time is never negative (checks.non_negative_float)
        raise checks.OptionError(f"{picked} is negative; allowed: a step ≥ 0 or a time ≥ 0 s")


def run_replay(args: argparse.Namespace) -> int:
    """Show the recording (or take its screenshot); 2 for a bad file, 1 if the viewer fails."""
    _check_replay(args)
    from tolins.record import replay

    try:
        return replay(
            args.file,
            web=args.web,
            screenshot=args.screenshot,
            web_port=args.port,
            grpc_port=args.grpc_port,
            step=args.step,
            time=args.time,
        )
    except ValueError as error:  # the file (an RrdError), or a step/time outside it
        return checks.fail("tolins replay", error)
    except RuntimeError as error:  # the viewer failed
        print(f"tolins replay: {error}", file=sys.stderr)
        return 1

"""The ``tolins`` command: wires arguments to library functions."""

from __future__ import annotations

import argparse
import sys
import time

from tolins import cli_checks
from tolins.cli_checks import positive_int, seed


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
    cli_checks.output_file("--out", args.out, suffixes=(".rrd",))
    import gymnasium as gym
    from tqdm import tqdm

    from tolins.learning.actors import make_actor
    from tolins.learning.external import trust_pickle
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
        print(f"tolins record: {error}", file=sys.stderr)
        return 2
    finally:
        env.close()
    successes = sum(e.success for e in episodes)
    print(f"wrote {args.out}: {len(episodes)} episodes, {successes} successful")
    return 0


def _replay(args: argparse.Namespace) -> int:
    cli_checks.input_file("FILE", args.file)
    if args.web and args.port == args.grpc_port:
        raise cli_checks.OptionError(
            f"--port {args.port} is also --grpc-port; allowed: two different ports"
        )
    if args.screenshot is not None:
        cli_checks.output_file("--screenshot", args.screenshot, suffixes=(".png",))
    picked = "--step" if args.step is not None else "--time" if args.time is not None else None
    if picked and args.screenshot is None:
        raise cli_checks.OptionError(
            f"{picked} picks what a screenshot shows; allowed: with --screenshot"
        )
    if (args.step or 0) < 0 or (args.time or 0.0) < 0:
        raise cli_checks.OptionError(f"{picked} is negative; allowed: a step ≥ 0 or a time ≥ 0 s")
    from tolins.record import RrdError, replay

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
    except (RrdError, ValueError) as error:  # the file, or a step/time outside it
        print(f"tolins replay: {error}", file=sys.stderr)
        return 2
    except RuntimeError as error:  # the viewer failed
        print(f"tolins replay: {error}", file=sys.stderr)
        return 1


def _embed_train(args: argparse.Namespace) -> int:
    from tolins.config_args import config_from_args
    from tolins.learning.embedding_config import EmbeddingTrainConfig

    try:
        config = config_from_args(EmbeddingTrainConfig, args)
    except ValueError as error:
        print(f"tolins embed train: {error}", file=sys.stderr)
        return 2
    suffix = "" if config.model == "paper" else f"_{config.model}"
    out = cli_checks.output_file("--out", args.out or f"runs/embedding_{config.family}{suffix}.pt")
    from tqdm import tqdm

    from tolins.learning.checkpoint import save_checkpoint
    from tolins.learning.embedding_eval import held_out_specs, measure
    from tolins.learning.embedding_train import train_embedding

    start = time.perf_counter()
    with tqdm(total=config.epochs, desc=f"training {config.family} embedding", unit="epoch") as bar:

        def advance(_: int, loss: float) -> None:
            bar.set_postfix(loss=f"{loss:.4f}")
            bar.update()

        try:
            result = train_embedding(config, on_epoch=advance)
        except ValueError as error:  # diverged: no checkpoint of NaN weights
            bar.close()
            print(f"tolins embed train: {error}", file=sys.stderr)
            return 2
    path = save_checkpoint(out, result.model)
    quality = measure(
        result.model, held_out_specs(config.family, args.held_out, model=config.model)
    )
    print(
        f"wrote {path} ({path.stat().st_size / 1e3:.0f} kB, {time.perf_counter() - start:.0f} s); "
        f"{quality.count} held-out workpieces: region IoU {quality.iou:.3f} "
        f"(worst {quality.worst_iou:.3f}), theta error {quality.theta_error:.4f} rad "
        f"({quality.relative_theta_error:.1%} of each image's largest theta)"
    )
    return 0


def _infer_study(args: argparse.Namespace) -> int:
    if args.json:
        cli_checks.output_file("--json", args.json)
    if args.plot:
        cli_checks.output_file("--plot", args.plot, suffixes=(".png",))
    from tqdm import tqdm

    from tolins.inference.report import format_table, save_plot, write_json
    from tolins.inference.study import StudyConfig, parse_methods, run_study

    try:
        methods = StudyConfig.methods if args.methods is None else parse_methods(args.methods)
        config = StudyConfig(
            samples=args.samples,
            seed=args.seed,
            particles=args.particles,
            workers=args.workers,
            methods=methods,
            discard_below=args.discard_below,
            physics=args.physics,
            kind_samples=args.kind_samples,
        )
    except ValueError as error:
        print(f"tolins infer-study: {error}", file=sys.stderr)
        return 2
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


def build_parser() -> argparse.ArgumentParser:
    import tolins

    parser = cli_checks.Parser(prog="tolins", description=__doc__)
    parser.add_argument(
        "--version",
        action="version",
        version=f"tolins {tolins.__version__}",
        help="print the installed version and exit",
    )
    commands = parser.add_subparsers(dest="command", required=True)
    demo = commands.add_parser(
        "demo", help="roll out both experts in every preset environment and print a table"
    )
    demo.add_argument("--episodes", type=positive_int, default=100, help="episodes per row")
    demo.add_argument("--seed", type=seed, default=0, help="seed of the first episode")
    demo.add_argument("--workers", type=positive_int, default=2, help="threads")
    demo.add_argument(
        "--backend", default="mujoco", choices=["mujoco", "kinematic"], help="simulator"
    )
    demo.set_defaults(run=_demo)
    record = commands.add_parser("record", help="record a policy's episodes to a rerun .rrd file")
    record.add_argument(
        "--env",
        required=True,
        type=cli_checks.preset_env_ids(),
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
        help="load an SB3 PATH.zip with SB3's own load, which unpickles and so runs code "
        "stored in the zip (default: rebuilt from its JSON and weights, without pickle)",
    )
    record.add_argument(
        "--backend", default="mujoco", choices=["mujoco", "kinematic"], help="simulator"
    )
    record.add_argument("--episodes", type=positive_int, default=5, help="episodes")
    record.add_argument("--out", required=True, help="output file, FILE.rrd (replaced if present)")
    record.add_argument("--seed", type=seed, default=0, help="seed of the first episode")
    record.set_defaults(run=_record)
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
        type=cli_checks.non_negative_float,
        metavar="SECONDS",
        help="the simulated time the screenshot shows",
    )
    replay.add_argument(
        "--port", type=cli_checks.port, default=9090, help="web viewer port (with --web)"
    )
    replay.add_argument(
        "--grpc-port",
        type=cli_checks.port,
        default=9876,
        help="port serving the recording (with --web)",
    )
    replay.set_defaults(run=_replay)
    _add_embed(commands)
    _add_infer_study(commands)
    _add_train(commands)
    _add_bench(commands)
    _add_evaluate(commands)
    _add_compare(commands)
    _add_dataset(commands)
    _add_export(commands)
    return parser


def _add_bench(commands: argparse._SubParsersAction) -> None:
    from tolins.bench.cli import add_bench_parser

    add_bench_parser(commands)


def _add_evaluate(commands: argparse._SubParsersAction) -> None:
    from tolins.bench.cli import add_evaluate_parser

    add_evaluate_parser(commands)


def _add_compare(commands: argparse._SubParsersAction) -> None:
    from tolins.bench.compare_cli import add_compare_parser

    add_compare_parser(commands)


def _add_dataset(commands: argparse._SubParsersAction) -> None:
    from tolins.datasets.cli import add_dataset_parser

    add_dataset_parser(commands)


def _export(args: argparse.Namespace) -> int:
    from tolins.mjcf.export import EXPORT_SUFFIXES

    out = cli_checks.output_file("--out", args.out, suffixes=EXPORT_SUFFIXES)
    from pathlib import Path

    from tolins import atomic
    from tolins.geometry.spec_json import spec_from_json
    from tolins.mjcf.export import export_bytes

    try:
        if args.env is not None:
            from tolins.envs.tasks import PRESETS

            spec = next(task.socket for task in PRESETS if task.gym_id == args.env)
        elif args.socket.lstrip().startswith("{"):
            spec = spec_from_json(args.socket)
        elif Path(args.socket).is_file():
            spec = spec_from_json(Path(args.socket).read_text(encoding="utf-8"))
        else:
            raise ValueError(
                f"--socket {args.socket}: no such file, nor a JSON object; allowed: a JSON "
                'object of a spec\'s fields (e.g. {"rows": 2, "cols": 2}) or a file holding one'
            )
        data = export_bytes(spec, out.suffix, args.part)
    except (ValueError, OSError) as error:  # UnicodeDecodeError is a ValueError
        print(f"tolins export: {error}", file=sys.stderr)
        return 2
    atomic.atomic_write(out, lambda file: file.write(data))
    print(f"wrote {out} ({len(data) / 1e3:.0f} kB)")
    return 0


def _add_export(commands: argparse._SubParsersAction) -> None:
    from tolins.envs import tasks

    export = commands.add_parser(
        "export", help="write a workpiece as a mesh (STL, GLB) or its MJCF model (.xml)"
    )
    which = export.add_mutually_exclusive_group(required=True)
    which.add_argument(
        "--env",
        type=cli_checks.env_ids(
            tasks.env_ids(generic=False),
            reasons={tasks.GENERIC_ID: "its workpiece is given with --socket"},
        ),
        help="a preset env id: its nominal workpiece, e.g. tolins/Circle2x2-v1",
    )
    which.add_argument(
        "--socket",
        metavar="JSON",
        help='a spec\'s fields as a JSON object, defects included (e.g. {"rows": 2, "cols": '
        '1, "pin_offsets": [[0.1, 0], [0, -0.05]]}; a recording\'s spec), or a file holding one',
    )
    export.add_argument(
        "--out",
        required=True,
        help="PART.stl (mm), PART.glb (glTF: metres, y up) or MODEL.xml (the MJCF model); "
        "replaced if present",
    )
    export.add_argument(
        "--part",
        default="all",
        help="all (the workpiece 2 mm over the board), board or workpiece; meshes only",
    )
    export.set_defaults(run=_export)


def _add_train(commands: argparse._SubParsersAction) -> None:
    from tolins.learning.train_cli import add_train_parser

    add_train_parser(commands)


def _add_embed(commands: argparse._SubParsersAction) -> None:
    from tolins.config_args import add_config_arguments
    from tolins.learning.embedding_config import EmbeddingTrainConfig

    embed = commands.add_parser("embed", help="the tolerance embedding (autoencoder)")
    actions = embed.add_subparsers(dest="action", required=True)
    train = actions.add_parser("train", help="train the autoencoder of one workpiece family")
    add_config_arguments(train, EmbeddingTrainConfig)
    train.add_argument(
        "--out", help="checkpoint file, replaced if present (default: runs/embedding_FAMILY.pt)"
    )
    train.add_argument(
        "--held-out", type=positive_int, default=200, help="held-out workpieces to score"
    )
    train.set_defaults(run=_embed_train)


def _add_infer_study(commands: argparse._SubParsersAction) -> None:
    study = commands.add_parser(
        "infer-study", help="the paper's probabilistic-inference study (2*1, bent pins)"
    )
    study.add_argument("--samples", type=positive_int, default=500, help="workpieces")
    study.add_argument("--seed", type=seed, default=0, help="seed of defects and methods")
    study.add_argument(
        "--particles", type=positive_int, default=1000, help="posterior samples per query"
    )
    study.add_argument("--workers", type=positive_int, default=2, help="processes")
    study.add_argument(
        "--kind-samples",
        type=positive_int,
        default=12,
        help="workpieces per defect kind besides bent (pitch, burr, blocked)",
    )
    study.add_argument(
        "--methods",
        action=cli_checks.JoinedList,
        help="comma-separated subset of inference, inference_blocked, inference_contact, "
        "random, nominal, oracle (default: all)",
    )
    study.add_argument(
        "--discard-below",
        type=float,
        default=0.0,
        help="inference gives up when the best expected success falls below this (0: never)",
    )
    study.add_argument(
        "--physics",
        action="store_true",
        help="outcomes, blocked pins and touch bearings from MuJoCo contact physics",
    )
    study.add_argument(
        "--json", metavar="OUT.json", help="write the figures as JSON (replaced if present)"
    )
    study.add_argument(
        "--plot", metavar="OUT.png", help="save the cumulative-success plot (replaced if present)"
    )
    study.set_defaults(run=_infer_study)


def _prog(args: argparse.Namespace) -> str:
    words = [args.command, getattr(args, "action", None), getattr(args, "method", None)]
    return " ".join(["tolins", *(word for word in words if word)])


def main(argv: list[str] | None = None) -> int:
    try:
        args = build_parser().parse_args(argv)
    except cli_checks.UsageError as error:
        return cli_checks.fail(error.prog, error)
    try:
        return args.run(args)
    except cli_checks.OptionError as error:
        return cli_checks.fail(_prog(args), error)
    except KeyboardInterrupt:  # finished stages, checkpoints and written files stay
        print(f"{_prog(args)}: interrupted", file=sys.stderr)
        return 130
    except RuntimeError as error:
        from tolins.learning.external import PolicyError

        if not isinstance(error, PolicyError):
            raise
        print(error.details, end="", file=sys.stderr)  # the user's policy's own traceback
        print(f"{_prog(args)}: {error} (its traceback above)", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())

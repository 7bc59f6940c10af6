"""``tolins embed train``: the tolerance autoencoder of one workpiece family, its options
generated from :class:`~tolins.learning.embedding.config.EmbeddingTrainConfig`."""

from __future__ import annotations

import argparse
import time

from tolins.cli import checks
from tolins.cli.args import add_config_arguments, config_from_args
from tolins.learning.embedding.config import EmbeddingTrainConfig


def add_parser(commands: argparse._SubParsersAction) -> None:
    """Add ``embed train`` to the ``tolins`` parser."""
    embed = commands.add_parser("embed", help="the tolerance embedding (autoencoder)")
    actions = embed.add_subparsers(dest="action", required=True)
    train = actions.add_parser("train", help="train the autoencoder of one workpiece family")
    add_config_arguments(train, EmbeddingTrainConfig)
    train.add_argument(
        "--out", help="checkpoint file, replaced if present (default: runs/embedding_FAMILY.pt)"
    )
    train.add_argument(
        "--held-out", type=checks.positive_int, default=200, help="held-out workpieces to score"
    )
    train.set_defaults(run=run_train)


def run_train(args: argparse.Namespace) -> int:
    """Train with a progress bar, save the checkpoint and score it on held-out workpieces."""
    try:
        config = config_from_args(EmbeddingTrainConfig, args)
    except ValueError as error:
        return checks.fail("tolins embed train", error)
    suffix = "" if config.model == "paper" else f"_{config.model}"
    out = checks.output_file("--out", args.out or f"runs/embedding_{config.family}{suffix}.pt")
    from tqdm import tqdm

    from tolins.learning.artefacts import RunRefused
    from tolins.learning.embedding.checkpoint import save_checkpoint
    from tolins.learning.embedding.evaluation import held_out_specs, measure
    from tolins.learning.embedding.train import train_embedding

    start = time.perf_counter()
    with tqdm(total=config.epochs, desc=f"training {config.family} embedding", unit="epoch") as bar:

        def advance(_: int, loss: float) -> None:
            bar.set_postfix(loss=f"{loss:.4f}")
            bar.update()

        try:
            result = train_embedding(config, on_epoch=advance)
        except RunRefused as error:  # diverged: no checkpoint of NaN weights
            bar.close()
            return checks.refused("tolins embed train", error)
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

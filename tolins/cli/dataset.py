"""``tolins dataset``: a policy's (or a recipe's) episodes as a local Minari dataset.

The datasets layer sits below learning, so the policies that need learning code are
handed to it from here (:func:`tolins.datasets.sources.make_source`).
"""

from __future__ import annotations

import argparse
import functools
import re
from pathlib import Path
from typing import TYPE_CHECKING

from tolins.cli import checks
from tolins.physics import BACKENDS

if TYPE_CHECKING:
    from tolins.datasets.sources import Policy, Source
    from tolins.geometry.specs import SocketSpec

_RECIPES = "expert-safe, expert-efficient, bc, random, mixed"
_NAMED = {"safe": "expert-safe", "efficient": "expert-efficient"}


def add_parser(commands: argparse._SubParsersAction) -> None:
    """Add ``dataset`` to the ``tolins`` parser."""
    parser = commands.add_parser(
        "dataset", help="write a policy's episodes as a Minari dataset (docs/datasets.md)"
    )
    parser.add_argument(
        "--env",
        required=True,
        type=checks.preset_env_ids(),
        help="a preset env id, e.g. tolins/Circle2x2-v1",
    )
    who = parser.add_mutually_exclusive_group(required=True)
    who.add_argument(
        "--policy",
        help="safe, efficient, random, bc (cloned here from the safe expert), a tolins "
        "policy file PATH, an SB3 PATH.zip or MODULE:NAME (imports that module)",
    )
    who.add_argument("--recipe", help=f"a named mix of policies: {_RECIPES}")
    parser.add_argument("--episodes", type=checks.positive_int, default=50, help="episodes")
    parser.add_argument(
        "--out",
        required=True,
        help="datasets root: the dataset goes to OUT/NAME (MINARI_DATASETS_PATH=OUT finds it)",
    )
    parser.add_argument(
        "--name",
        help="Minari dataset id (default: tolins/ENV/RECIPE-v0, e.g. "
        "tolins/circle2x2/expert-safe-v0 for tolins/Circle2x2-v1 and "
        "tolins/circle2x2-v2/expert-safe-v0 for -v2)",
    )
    parser.add_argument("--backend", default="mujoco", choices=BACKENDS, help="simulator")
    parser.add_argument(
        "--seed",
        type=checks.seed,
        default=0,
        help="seeds the episodes (those `tolins train --seed SEED` collects) and bc",
    )
    parser.set_defaults(run=run)


def default_name(env_id: str, label: str) -> str:
    """``tolins/circle2x2/expert-safe-v0`` for ``tolins/Circle2x2-v1`` and ``expert-safe``;
    ``tolins/circle2x2-v2/expert-safe-v0`` for ``tolins/Circle2x2-v2``: the env's physics
    version beyond the first in its part of the id, so datasets of two versions do not
    take the same place."""
    env = env_id.removeprefix("tolins/").lower().removesuffix("-v1")
    slug = re.sub(r"[^a-z0-9]+", "-", label.lower()).strip("-") or "policy"
    return f"tolins/{env}/{slug}-v0"


def _label(args: argparse.Namespace) -> str:
    """What the default dataset id calls the policy: the recipe, an expert's recipe name,
    ``MODULE-NAME`` or a policy file's stem."""
    if args.recipe is not None:
        return args.recipe
    entry = args.policy
    if entry in _NAMED:
        return _NAMED[entry]
    if ":" in entry and not Path(entry).exists():
        return entry.replace(":", "-")
    return Path(entry.partition("=")[2] or entry).stem


def run(args: argparse.Namespace) -> int:
    """Check every option and the target folder, then write the dataset."""
    from tolins.datasets.reader import require_minari

    prog = "tolins dataset"
    try:
        require_minari(prog)
    except ImportError as error:
        return checks.fail(prog, error)
    from tolins.datasets.target import check_target, claim_target

    try:
        name = args.name or default_name(args.env, _label(args))
        checks.output_folder("--out", args.out)
        check_target(args.out, name)
        sources = _sources(args)
        with claim_target(args.out, name) as target:
            successes = _write(args, sources, name)
    except ValueError as error:  # OptionError too
        return checks.fail(prog, error)
    print(
        f"wrote {target}: {args.episodes} episodes, {successes} successful; "
        f"MINARI_DATASETS_PATH={args.out} minari.load_dataset({name!r})"
    )
    return 0


def _sources(args: argparse.Namespace) -> list[Source]:
    """The policies of ``--recipe`` or ``--policy`` (``ValueError`` for a bad one); none has
    done any work yet."""
    import gymnasium as gym

    from tolins.datasets.sources import make_source, recipe_entries

    entries = recipe_entries(args.recipe) if args.recipe else (args.policy,)
    socket = gym.spec(args.env).kwargs["socket"]
    train_bc = functools.partial(_trained_bc, args.env, args.backend, args.seed)
    return [make_source(e, socket, make_actor=_make_actor, train_bc=train_bc) for e in entries]


def _make_actor(entry: str, socket: SocketSpec) -> Policy:
    """:func:`tolins.learning.agents.actors.make_actor`, imported (with torch) on first use."""
    from tolins.learning.agents.actors import make_actor

    return make_actor(entry, socket)


def _trained_bc(env_id: str, backend: str, seed: int) -> Policy:
    """:func:`tolins.learning.imitation.runs.trained_bc`, imported (with torch) on first use."""
    from tolins.learning.imitation.runs import trained_bc

    return trained_bc(env_id, backend, seed)


def _write(args: argparse.Namespace, sources: list[Source], name: str) -> int:
    """Write the dataset ``name`` with a progress bar; the number of successful episodes."""
    from tqdm import tqdm

    from tolins.datasets.writer import write_dataset

    successes = 0
    with tqdm(total=args.episodes, desc=f"dataset {name}", unit="episode") as bar:

        def advance(record) -> None:
            nonlocal successes
            successes += bool(record.buffer.infos["success"][-1])
            bar.update()

        write_dataset(
            args.env,
            sources,
            args.episodes,
            args.out,
            name,
            backend=args.backend,
            seed=args.seed,
            on_episode=advance,
        )
    return successes

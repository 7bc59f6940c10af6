"""Write a policy's episodes as a local Minari dataset (hdf5), atomically.

Layout (Minari's own): ``ROOT/NAME/data/{metadata.json, main_data.hdf5}``, so that
``MINARI_DATASETS_PATH=ROOT`` makes ``minari.load_dataset(NAME)`` find it. Per step, beside
``observations`` (``T + 1``), ``actions`` (``T``, clipped as the env applied them),
``rewards``, ``terminations`` and ``truncations``, the ``infos`` group has ``T + 1`` rows
(the reset's first, Minari's convention) of :data:`STEP_INFO`: the true pose, the true
wrench, the peak force, the collision flag and count, success, the step, the goal and
every reward term. Per episode (``episode.attrs`` / ``dataset.storage.get_episode_metadata``):
``seed``, ``policy``, ``socket`` (the workpiece's spec as JSON, bent pins included),
``pin_offsets`` (``(n_pins, 2)`` mm, the ground-truth defects), ``error`` (``""`` unless a
simulator fault truncated it).
"""

from __future__ import annotations

import contextlib
import errno
import json
import os
import shutil
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from tolins.datasets.envspec import dataset_env_spec, socket_to_json
from tolins.datasets.sources import Source
from tolins.datasets.target import HDF5_IO, claim_target, temporary_folder
from tolins.rollouts.collectors import Transitions
from tolins.rollouts.episodes import run_episode

#: The ``info`` keys stored per step (every key of the env's info but ``error``).
STEP_INFO = (
    "pose",
    "wrench",
    "peak_force",
    "collision",
    "n_collisions",
    "success",
    "step",
    "goal",
    "reward_success",
    "reward_collision",
    "reward_approach",
    "reward_height",
    "reward_alignment",
    "reward_depth",
    "reward_offset",
)
#: The units of the observation and action entries (``InsertionEnv``'s tables), stored in
#: the dataset's metadata as ``tolins_units`` and checked when a dataset is read.
UNITS = {
    "observation": ["mm", "mm", "rad", "mm", "N", "N", "N·mm", "N"],
    "action": ["mm/s", "mm/s", "rad/s", "mm/s"],
}


@dataclass(frozen=True)
class EpisodeRecord:
    """One episode as Minari stores it, with its metadata."""

    buffer: Any  # minari.data_collector.EpisodeBuffer
    metadata: dict[str, Any]


def episode_seeds(seed: int, episodes: int, stream: int = 0) -> list[int]:
    """The episode seeds of a dataset with ``seed``: the ones ``tolins train --seed SEED``
    draws for the demonstrations on its env number ``stream`` (0: the first;
    :func:`tolins.learning.imitation.runs.demonstrations`), so that a safe-expert dataset of
    the same seed holds the very same episodes."""
    if not 0 <= stream < 1000:
        raise ValueError(f"stream={stream}; allowed: 0 <= stream < 1000 (an env's index)")
    state = np.random.SeedSequence([seed * 1000 + stream, 0xDE70]).generate_state(episodes)
    return [int(s) for s in state]


def record_episode(env: gym.Env, policy: Callable, seed: int, name: str, index: int):
    """Run ``policy`` in ``env`` from ``reset(seed=seed)``; the episode as an
    :class:`EpisodeRecord` with id ``index``."""
    from minari.data_collector import EpisodeBuffer

    steps = Transitions()
    episode = run_episode(env, policy, seed, (steps,))
    socket = env.unwrapped.socket
    buffer = EpisodeBuffer(
        id=index,
        seed=seed,
        observations=np.array(steps.observations),
        actions=np.array(steps.actions),
        rewards=[float(r) for r in steps.rewards],
        terminations=[bool(t) for t in steps.terminations],
        truncations=[bool(t) for t in steps.truncations],
        infos={key: np.array([step[key] for step in steps.infos]) for key in STEP_INFO},
    )
    offsets = getattr(socket, "offsets", np.zeros((socket.n_pins, 2)))
    metadata = {
        "policy": name,
        "socket": json.dumps(socket_to_json(socket)),
        "pin_offsets": np.asarray(offsets, dtype=float),
        "error": episode.error or "",
    }
    return EpisodeRecord(buffer, metadata)


def write_dataset(
    env_id: str,
    sources: Sequence[Source],
    episodes: int,
    root: str | os.PathLike,
    name: str,
    *,
    backend: str = "mujoco",
    seed: int = 0,
    env_kwargs: dict[str, Any] | None = None,
    description: str = "",
    on_episode: Callable[[EpisodeRecord], None] | None = None,
    stream: int = 0,
) -> Path:
    """Write ``episodes`` episodes of ``env_id`` on ``backend`` to ``ROOT/NAME`` (episode
    ``i`` acts with ``sources[i % len(sources)]``, seeded by :func:`episode_seeds`).
    ``env_kwargs`` go to the env (``socket=`` for ``tolins/Insert-v1``) and into its spec;
    ``stream`` picks the seeds of a training's env number ``stream`` (:func:`episode_seeds`).

    The dataset is built in a hidden folder beside its place and renamed onto it at the
    end: on any error or Ctrl-C the hidden folder is removed and nothing is left. While it
    is built, its place is claimed (:func:`~tolins.datasets.target.claim_target`): a
    second writer of ``ROOT/NAME`` gets ``ValueError`` at once.
    """
    from minari.dataset.minari_storage import MinariStorage

    spec = dataset_env_spec(env_id, **(env_kwargs or {}), backend=backend)
    with claim_target(root, name) as target, contextlib.closing(gym.make(spec)) as env:
        temp = temporary_folder(target)
        try:
            records = []
            for index, seed_i in enumerate(episode_seeds(seed, episodes, stream)):
                source = sources[index % len(sources)]
                records.append(record_episode(env, source.make(seed_i), seed_i, source.name, index))
                if on_episode is not None:
                    on_episode(records[-1])
            metadata = _metadata(name, env_id, backend, seed, sources, description)
            with HDF5_IO:
                storage = MinariStorage.new(
                    temp / "data",
                    observation_space=env.observation_space,
                    action_space=env.action_space,
                    env_spec=spec,
                )
                for index, record in enumerate(records):
                    storage.update_episodes([record.buffer])
                    storage.update_episode_metadata([record.metadata], [index])
                storage.update_metadata({**metadata, "tolins_stream": int(stream)})
            _move_into_place(temp, target)
        except BaseException:
            shutil.rmtree(temp, ignore_errors=True)
            raise
    return target


def _move_into_place(temp: Path, target: Path) -> None:
    """Rename the finished folder ``temp`` onto ``target``; ``ValueError`` if a dataset
    has appeared there meanwhile (written by a writer that holds no claim)."""
    try:
        os.rename(temp, target)
    except OSError as error:
        if error.errno not in (errno.ENOTEMPTY, errno.EEXIST):
            raise
        raise ValueError(
            f"{target} was written by another process meanwhile; allowed: a new --name or "
            "--out (or remove it)"
        ) from None


def _metadata(name, env_id, backend, seed, sources, description) -> dict[str, Any]:
    import minari

    import tolins

    policies = ", ".join(dict.fromkeys(s.name for s in sources))
    return {
        "dataset_id": name,
        "algorithm_name": policies,
        "author": {"tolins"},
        "description": description or f"{policies} on {env_id} ({backend} backend), seed {seed}",
        "minari_version": minari.__version__,
        "requirements": [f"tolins=={tolins.__version__}"],
        "tolins_version": tolins.__version__,
        "tolins_env": env_id,
        "tolins_backend": backend,
        "tolins_seed": int(seed),
        "tolins_units": UNITS,
    }

"""Read demonstrations from any Minari dataset of a tolins env, checked before use.

A dataset is named by its folder (``ROOT/NAME``, or its ``data`` folder) or by its Minari
id under ``MINARI_DATASETS_PATH`` (``~/.minari/datasets`` by default). It is accepted for
an env ``ENV`` when its env spec is ``ENV``, its observation and action spaces are
``ENV``'s, and, where it states them (``tolins_units``, written by ``tolins dataset``), its
units are tolins's (mm, rad, N, N·mm; mm/s, rad/s). Its episodes are checked for what they
hold before a learner sees them: readable, observations and actions as wide as the spaces
(one observation more than actions), every value finite, every action inside the action box
and every observation inside the observation box. Anything else is refused with one line
saying what differs.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from tolins.datasets.target import HDF5_IO
from tolins.datasets.writer import UNITS
from tolins.envs.tasks import env_ids
from tolins.rollouts.episodes import Episode

#: How to get Minari (the extra of :mod:`tolins.datasets`).
INSTALL_DATA = "pip install 'tolins[data]'"


def require_minari(user: str) -> None:
    """Raise ``ImportError`` (``user`` needs Minari, and how to install it) unless Minari
    imports; ``user`` names what needs it, e.g. ``tolins dataset``."""
    try:
        import minari  # noqa: F401
    except ImportError as error:
        raise ImportError(f"{user} needs Minari ({error}); allowed: {INSTALL_DATA}") from None


def dataset_folder(source: str | os.PathLike) -> Path:
    """The ``data`` folder of the dataset ``source`` (a folder or a local Minari id);
    ``ValueError`` if it is neither."""
    path = Path(source)
    for candidate in (path / "data", path):
        if (candidate / "metadata.json").is_file():
            return candidate
    if not path.exists() and not path.is_absolute():  # Minari's root, without creating it
        root = os.environ.get("MINARI_DATASETS_PATH", Path.home() / ".minari" / "datasets")
        by_id = Path(root) / str(source) / "data"
        if (by_id / "metadata.json").is_file():
            return by_id
    raise ValueError(
        f"--demos {source}: not a Minari dataset; allowed: a dataset folder (holding "
        "data/metadata.json) or the id of a local dataset under MINARI_DATASETS_PATH"
    )


def open_dataset(source: str | os.PathLike, env_id: str | None = None) -> Any:
    """The ``minari.MinariDataset`` at ``source``, checked against ``env_id`` (default: its
    own env, which must be a tolins env). Raises ``ValueError`` naming what differs."""
    import minari

    folder = dataset_folder(source)
    try:
        dataset = minari.MinariDataset(folder)
    except Exception as error:  # a corrupt or foreign folder: say so in one line
        raise ValueError(f"--demos {source}: unreadable ({_reason(error)})") from None
    check_dataset(dataset, env_id, str(source))
    return dataset


def check_dataset(dataset: Any, env_id: str | None, label: str) -> None:
    """Raise ``ValueError`` unless ``dataset`` holds episodes of the tolins env ``env_id``."""
    spec = dataset.env_spec
    found = None if spec is None else spec.id
    if found is None or found not in env_ids():
        raise ValueError(
            f"--demos {label}: env {found!r} is not a tolins env; allowed: a dataset of "
            f"one of {', '.join(env_ids())}"
        )
    if env_id is not None and found != env_id:
        raise ValueError(f"--demos {label}: episodes of {found}; allowed: episodes of {env_id}")
    reference = gym.spec(found)
    env = gym.make(reference) if "socket" in reference.kwargs else None
    if env is not None:
        for name in ("observation_space", "action_space"):
            theirs, ours = getattr(dataset, name), getattr(env.unwrapped, name)
            if theirs != ours:
                raise ValueError(f"--demos {label}: {name} {theirs}; allowed: {ours}")
        env.close()
    units = dataset.storage.metadata.get("tolins_units")
    if units is not None and units != UNITS:
        raise ValueError(f"--demos {label}: units {units}; allowed: {UNITS}")
    if dataset.total_episodes < 1:
        raise ValueError(f"--demos {label}: no episodes; allowed: a dataset with episodes")


def to_rollout(episode: Any) -> Episode:
    """A Minari episode as the learners' :class:`~tolins.rollouts.episodes.Episode` (the
    ``T`` observations each action answered, the ``T`` actions; ``steps`` is ``T``)."""
    infos = episode.infos or {}
    success = infos["success"][-1] if "success" in infos else episode.terminations[-1]
    collisions = infos["n_collisions"][-1] if "n_collisions" in infos else 0
    actions = np.asarray(episode.actions, dtype=np.float64)
    return Episode(
        reward=float(np.sum(episode.rewards)),
        success=bool(success),
        steps=len(actions),
        collisions=int(collisions),
        observations=np.asarray(episode.observations[:-1], dtype=np.float64),
        actions=actions,
    )


def check_episode(episode: Any, dataset: Any, label: str) -> None:
    """Raise ``ValueError`` (naming the episode, the field and what is allowed) unless
    ``episode`` holds what ``dataset``'s spaces allow (see the module docstring)."""
    where = f"--demos {label}: episode {episode.id}"
    observations = _field(episode.observations, "observations", dataset.observation_space, where)
    actions = _field(episode.actions, "actions", dataset.action_space, where)
    if len(observations) != len(actions) + 1:
        raise ValueError(
            f"{where}: {len(observations)} observations for {len(actions)} actions; "
            "allowed: one observation more than actions"
        )
    rewards = np.asarray(episode.rewards, dtype=np.float64)
    if not np.all(np.isfinite(rewards)):
        raise ValueError(f"{where}: rewards hold {_first_bad(rewards)}; allowed: finite values")


def _field(values: Any, field: str, space: gym.spaces.Box, where: str) -> np.ndarray:
    """``values`` as an array of rows of ``space``'s width, checked finite and inside
    ``space``'s box; ``ValueError`` naming ``field`` otherwise."""
    if not isinstance(space, gym.spaces.Box) or len(space.shape) != 1:
        raise ValueError(f"{where}: {field} of the space {space}; allowed: a 1-D Box")
    array = np.asarray(values, dtype=np.float64)
    width = space.shape[0]
    if array.ndim != 2 or array.shape[1] != width:
        raise ValueError(
            f"{where}: {field} of shape {array.shape}; allowed: rows of width {width} "
            f"(the {field.removesuffix('s')} space's)"
        )
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{where}: {field} hold {_first_bad(array)}; allowed: finite values")
    low, high = (np.broadcast_to(bound, array.shape) for bound in (space.low, space.high))
    outside = (array < low) | (array > high)
    if np.any(outside):
        step, column = np.argwhere(outside)[0]
        raise ValueError(
            f"{where}: {field}[{step}, {column}] = {array[step, column]:g} is outside the "
            f"{field.removesuffix('s')} space; allowed: {low[step, column]:g} … "
            f"{high[step, column]:g}"
        )
    return array


def _first_bad(array: np.ndarray) -> str:
    """The first value of ``array`` that is not finite, with its index."""
    index = tuple(int(i) for i in np.argwhere(~np.isfinite(array))[0])
    return f"{array[index]} at {list(index)}"


def _episodes(dataset: Any, label: str) -> Iterator[Any]:
    """The episodes of ``dataset``, read from its file in turn; ``ValueError`` for a file
    that cannot be read (truncated, empty, not hdf5)."""
    episodes = iter(dataset.iterate_episodes())
    while True:
        try:
            episode = next(episodes)
        except StopIteration:
            return
        except Exception as error:  # h5py's and Minari's errors for a damaged file: one line
            raise ValueError(
                f"--demos {label}: its episodes are unreadable ({_reason(error)}); allowed: "
                "a complete dataset file (write it again)"
            ) from None
        yield episode


def _reason(error: Exception) -> str:
    """``error`` as one line: its type and the first line of its message."""
    return f"{type(error).__name__}: {error}".splitlines()[0]


def load_demonstrations(source: str | os.PathLike, env_id: str | None = None) -> list[Episode]:
    """Every episode of the dataset ``source`` (checked by :func:`open_dataset` and
    :func:`check_episode`), in order. Raises ``ValueError`` naming what is wrong."""
    rollouts = []
    with HDF5_IO:
        dataset = open_dataset(source, env_id)
        for episode in _episodes(dataset, str(source)):
            check_episode(episode, dataset, str(source))
            rollouts.append(to_rollout(episode))
    return rollouts

"""The checkpoint of an SB3 training (:func:`tolins.learning.agents.sb3.train_sb3`): all that
the rest of the training depends on, so that a resumed training ends with the weights of an
uninterrupted one, bit for bit.

It is taken where SB3 starts a rollout (its last update done, the next transition not yet
taken) and holds:

- the networks and their optimisers (SB3's ``get_parameters``) and SAC's entropy
  coefficient;
- SB3's counters (``num_timesteps``, ``_episode_num``, ``_n_updates``, the target and
  progress of the running ``learn`` call, which the learning-rate schedule reads), its last
  observations and episode starts, and its episode-info buffer;
- SAC's replay buffer (the filled part);
- the random states: Python's, numpy's global generator (SB3's minibatches), torch's (the
  policy's actions) and the action space's (SAC's random first steps);
- the training envs: each env's running episode
  (:meth:`~tolins.rollouts.sb3_vec.Sb3VectorEnv.episodes`), replayed into the new envs on
  resume, and ``VecMonitor``'s running returns;
- the training loop's own state (the learning curve so far, its timings).

One torch file, written atomically and read with ``weights_only`` (no pickle: a checkpoint
is data, docs/security.md). A checkpoint of another configuration, one that cannot be read
or whose envs do not replay to its observations is refused (:class:`RunRefused`).
"""

from __future__ import annotations

import random
import time
from collections import deque
from pathlib import Path
from typing import Any

import numpy as np
import stable_baselines3
import torch
from stable_baselines3.common.save_util import recursive_getattr

from tolins.learning.artefacts import RunRefused, atomic_torch_save, load_payload
from tolins.rollouts.sb3_vec import RunningEpisode

FORMAT = "tolins.sb3_run/1"
#: SB3's counters of a training (plain numbers).
COUNTERS = (
    "num_timesteps",
    "_total_timesteps",
    "_num_timesteps_at_start",
    "_episode_num",
    "_n_updates",
    "_current_progress_remaining",
)
#: The arrays of SB3's replay buffer (``None`` where a buffer has no such array).
BUFFER_ARRAYS = ("observations", "next_observations", "actions", "rewards", "dones", "timeouts")


def save_checkpoint(path: Path, model, metadata: dict[str, Any], loop: dict[str, Any]) -> None:
    """Write the checkpoint of ``model`` (at the start of a rollout, or between ``learn``
    calls) and of the training loop's ``loop`` (plain data) to ``path``, atomically."""
    payload = {
        "format": FORMAT,
        "metadata": metadata,
        "loop": loop,
        "model": _model_state(model),
        "random": _random_states(model),
        "buffer": _buffer_state(model),
        "envs": _env_state(model.env),
    }
    atomic_torch_save(path, payload)


def load_checkpoint(path: Path, model, metadata: dict[str, Any]) -> dict[str, Any]:
    """Put the checkpoint at ``path`` into ``model`` (new: made by ``make_model`` and never
    trained; its envs never reset) and return the training loop's state. Raises
    :class:`RunRefused` for a checkpoint of another ``metadata``, one that cannot be read,
    or one whose envs do not replay to its observations."""
    try:
        payload = load_payload(path, FORMAT)
    except ValueError as error:
        raise RunRefused(f"{error}; delete it to start the training afresh") from None
    _check_metadata(path, payload["metadata"], metadata)
    try:
        _restore_model(model, payload["model"])
        _restore_buffer(model, payload["buffer"])
        observations = _restore_envs(model.env, payload["envs"])
        _restore_random(model, payload["random"])
        loop = dict(payload["loop"])
    except (KeyError, AttributeError, TypeError, ValueError, RuntimeError) as error:
        raise RunRefused(
            f"{path}: not a complete SB3 checkpoint ({type(error).__name__}: {error}); allowed: "
            "a checkpoint this tolins wrote; delete it to start the training afresh"
        ) from error
    if not np.array_equal(observations, model._last_obs):
        raise RunRefused(
            f"{path}: its envs do not replay to the observations it holds (another env or "
            "physics version, or an edited file); delete it to start the training afresh"
        )
    return loop


def versions() -> dict[str, str]:
    """The versions a checkpoint's bit-for-bit resume depends on (torch's random
    generator, SB3's loop)."""
    return {
        "stable_baselines3": str(stable_baselines3.__version__),
        "torch": str(torch.__version__),
    }


def _check_metadata(path: Path, stored: dict[str, Any], wanted: dict[str, Any]) -> None:
    stored = {k: v for k, v in stored.items() if k != "tolins_version"}
    wanted = {k: v for k, v in wanted.items() if k != "tolins_version"}
    if stored != wanted:
        differ = sorted(k for k in stored.keys() | wanted.keys() if stored.get(k) != wanted.get(k))
        raise RunRefused(
            f"{path} was written by another training (differs in: {', '.join(differ)}); "
            "cannot resume it; allowed: the same configuration and versions, or delete it to "
            "start the training afresh"
        )


# --- the model -------------------------------------------------------------------------


def _model_state(model) -> dict[str, Any]:
    _, variables = model._get_torch_save_params()
    return {
        "parameters": model.get_parameters(),
        "variables": {name: recursive_getattr(model, name).detach().clone() for name in variables},
        "counters": {name: getattr(model, name) for name in COUNTERS},
        "last_obs": torch.from_numpy(np.array(model._last_obs)),
        "last_episode_starts": torch.from_numpy(np.array(model._last_episode_starts)),
        "episode_infos": [_plain(info) for info in model.ep_info_buffer or ()],
        "episode_successes": [_plain(success) for success in model.ep_success_buffer or ()],
    }


def _restore_model(model, state: dict[str, Any]) -> None:
    model.set_parameters(state["parameters"], exact_match=True, device="cpu")
    with torch.no_grad():
        for name, value in state["variables"].items():
            recursive_getattr(model, name).copy_(value)
    for name in COUNTERS:
        setattr(model, name, state["counters"][name])
    model._last_obs = state["last_obs"].numpy().copy()
    model._last_episode_starts = state["last_episode_starts"].numpy().copy()
    window = model._stats_window_size
    model.ep_info_buffer = deque(state["episode_infos"], maxlen=window)
    model.ep_success_buffer = deque(state["episode_successes"], maxlen=window)


def _plain(value: Any) -> Any:
    """``value`` (a dict, a number) with numpy scalars as Python numbers."""
    if isinstance(value, dict):
        return {key: _plain(item) for key, item in value.items()}
    return value.item() if isinstance(value, np.generic) else value


# --- random states -----------------------------------------------------------------------


def _random_states(model) -> dict[str, Any]:
    name, keys, position, has_gauss, gauss = np.random.get_state()
    version, words, gauss_next = random.getstate()
    return {
        "torch": torch.get_rng_state(),
        "numpy": {
            "name": name,
            "keys": torch.from_numpy(keys.astype(np.int64)),
            "position": int(position),
            "has_gauss": int(has_gauss),
            "gauss": float(gauss),
        },
        "python": {"version": version, "words": list(words), "gauss_next": gauss_next},
        "action_space": model.action_space.np_random.bit_generator.state,
    }


def _restore_random(model, states: dict[str, Any]) -> None:
    torch.set_rng_state(states["torch"])
    state = states["numpy"]
    keys = state["keys"].numpy().astype(np.uint32)
    np.random.set_state(
        (state["name"], keys, state["position"], state["has_gauss"], state["gauss"])
    )
    python = states["python"]
    random.setstate((python["version"], tuple(python["words"]), python["gauss_next"]))
    model.action_space.np_random.bit_generator.state = states["action_space"]


# --- the replay buffer -------------------------------------------------------------------


def _buffer_state(model) -> dict[str, Any] | None:
    buffer = getattr(model, "replay_buffer", None)
    if buffer is None:
        return None
    filled = buffer.buffer_size if buffer.full else buffer.pos
    arrays = {
        name: torch.from_numpy(np.array(getattr(buffer, name)[:filled]))
        for name in BUFFER_ARRAYS
        if getattr(buffer, name, None) is not None
    }
    return {"pos": int(buffer.pos), "full": bool(buffer.full), "arrays": arrays}


def _restore_buffer(model, state: dict[str, Any] | None) -> None:
    buffer = getattr(model, "replay_buffer", None)
    if (buffer is None) != (state is None):
        raise ValueError("a replay buffer in only one of the checkpoint and the model")
    if buffer is None:
        return
    for name, saved in state["arrays"].items():
        values = saved.numpy()
        target = getattr(buffer, name)
        if values.dtype != target.dtype or values.shape[1:] != target.shape[1:]:
            raise ValueError(f"replay buffer {name} {values.dtype}{values.shape}")
        target[: len(values)] = values
    buffer.pos, buffer.full = state["pos"], state["full"]


# --- the envs ----------------------------------------------------------------------------


def _env_state(monitor) -> dict[str, Any]:
    return {
        "episodes": [
            {"rng": episode.rng_state, "actions": torch.from_numpy(episode.actions)}
            for episode in monitor.venv.episodes()
        ],
        "returns": torch.from_numpy(np.array(monitor.episode_returns)),
        "lengths": torch.from_numpy(np.array(monitor.episode_lengths)),
        "count": int(monitor.episode_count),
        "elapsed_s": time.time() - monitor.t_start,
    }


def _restore_envs(monitor, state: dict[str, Any]) -> np.ndarray:
    """Replay the running episodes into ``monitor``'s envs and set its running returns;
    the observations (float32), which must be the checkpoint's last ones."""
    episodes = [
        RunningEpisode(episode["rng"], episode["actions"].numpy()) for episode in state["episodes"]
    ]
    observations = monitor.venv.replay(episodes)
    monitor.episode_returns = state["returns"].numpy().copy()
    monitor.episode_lengths = state["lengths"].numpy().copy()
    monitor.episode_count = state["count"]
    monitor.t_start = time.time() - state["elapsed_s"]
    return observations

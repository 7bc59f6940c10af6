"""An SB3 model zip's deterministic policy, rebuilt without unpickling (needs ``tolins[rl]``).

stable-baselines3's ``load`` unpickles (cloudpickle) the objects of the zip's ``data``
entry: a zip from someone else could run code. Here nothing is unpickled: the policy
class, its keyword arguments and the spaces are read from the JSON that SB3 writes beside
each pickled object (class names, plain values, array texts), the network is built from
SB3's own class and the weights ``policy.pth`` are loaded with ``weights_only=True``.
Supported: PPO and A2C (``ActorCriticPolicy``), SAC and TD3 ``MlpPolicy`` on ``Box``
spaces with SB3's or tolins's features extractor and a ``torch.nn`` activation; anything
else is refused with a message (``--trust-pickle`` loads it with SB3, running its code).
"""

from __future__ import annotations

import io
import json
import os
import re
import zipfile
from typing import Any

import numpy as np

#: ``__init__`` of the policy class (as SB3's JSON names it) -> where it lives.
_POLICIES = {
    "ActorCriticPolicy": "stable_baselines3.common.policies",
    "SACPolicy": "stable_baselines3.sac.policies",
    "TD3Policy": "stable_baselines3.td3.policies",
}
_EXTRACTORS = {
    "stable_baselines3.common.torch_layers.FlattenExtractor",
    "tolins.learning.agents.sb3.ScaledObservation",
}
_ACTIVATIONS = ("Tanh", "ReLU", "ELU", "LeakyReLU", "GELU", "SiLU", "Sigmoid", "Softplus")
#: Plain keyword arguments of the policies, taken as stored (JSON values).
_PLAIN = {
    "net_arch", "use_sde", "log_std_init", "full_std", "use_expln", "squash_output",
    "ortho_init", "share_features_extractor", "n_critics", "normalize_images", "clip_mean",
    "features_extractor_kwargs",
}  # fmt: skip
#: Keyword arguments that do not change the deterministic action (dropped).
_IGNORED = {"optimizer_class", "optimizer_kwargs"}
_CLASS = re.compile(r"^<class '([\w.]+)'>$")


class Sb3ZipError(ValueError):
    """The zip cannot be rebuilt without unpickling (or is no SB3 model)."""


def load_policy_without_pickle(path: str | os.PathLike, algorithm: str) -> Any:
    """The SB3 policy (``predict(observation, deterministic=True)``) of the zip at
    ``path``, saved by ``algorithm`` (``PPO``, ``A2C``, ``SAC``, ``TD3``), in eval mode."""
    import torch

    try:
        with zipfile.ZipFile(path) as archive:
            data = json.loads(archive.read("data"))
            weights = archive.read("policy.pth")
    except (zipfile.BadZipFile, KeyError, json.JSONDecodeError, OSError) as error:
        raise Sb3ZipError(f"{path}: not a stable-baselines3 model zip ({error})") from error
    policy_class = _policy_class(path, data.get("policy_class"))
    observations = _box(path, "observation_space", data.get("observation_space"))
    actions = _box(path, "action_space", data.get("action_space"))
    kwargs = _policy_kwargs(path, data.get("policy_kwargs") or {})
    if algorithm in ("PPO", "A2C") and "use_sde" in data:
        kwargs["use_sde"] = bool(data["use_sde"])
    try:
        policy = policy_class(observations, actions, lambda _: 0.0, **kwargs)
    except (TypeError, ValueError) as error:
        raise Sb3ZipError(f"{path}: cannot rebuild its policy ({error})") from error
    try:
        state = torch.load(io.BytesIO(weights), map_location="cpu", weights_only=True)
        policy.load_state_dict(state)
    except Exception as error:
        first = str(error).strip().splitlines()[0] if str(error).strip() else ""
        raise Sb3ZipError(
            f"{path}: its weights do not fit the policy it declares "
            f"({type(error).__name__}: {first})"
        ) from error
    policy.set_training_mode(False)
    return policy


def _refuse(path: Any, what: str) -> Sb3ZipError:
    return Sb3ZipError(
        f"{path}: {what}; it cannot be rebuilt without unpickling, which runs code stored "
        "in the zip; allowed: a zip of a standard SB3 MlpPolicy, or --trust-pickle if you "
        "trust whoever made the file"
    )


def _policy_class(path: Any, stored: Any) -> type:
    import importlib

    init = stored.get("__init__", "") if isinstance(stored, dict) else ""
    match = re.match(r"^<function (\w+)\.__init__ at ", init if isinstance(init, str) else "")
    name = match.group(1) if match else None
    module = stored.get("__module__") if isinstance(stored, dict) else None
    if name not in _POLICIES or module != _POLICIES[name]:
        raise _refuse(path, f"policy class {name or '?'} from {module!r}")
    return getattr(importlib.import_module(module), name)


def _box(path: Any, field: str, stored: Any):
    from gymnasium.spaces import Box

    if not isinstance(stored, dict) or stored.get(":type:") != (
        "<class 'gymnasium.spaces.box.Box'>"
    ):
        found = stored.get(":type:") if isinstance(stored, dict) else type(stored).__name__
        raise _refuse(path, f"{field} is {found}, not a gymnasium Box")
    try:
        shape = tuple(int(n) for n in stored["_shape"])
        dtype = np.dtype(stored["dtype"])
        low, high = (_array_text(stored[key], shape) for key in ("low", "high"))
        return Box(low.astype(dtype), high.astype(dtype), shape, dtype)
    except (KeyError, TypeError, ValueError) as error:
        raise Sb3ZipError(f"{path}: {field} unreadable ({error})") from error


def _array_text(text: str, shape: tuple[int, ...]) -> np.ndarray:
    """``str(array)`` of a small float array back as an array of ``shape``."""
    if not isinstance(text, str) or "..." in text:
        raise ValueError(f"array text {text!r}")
    values = np.array([float(v) for v in text.replace("[", " ").replace("]", " ").split()])
    return values.reshape(shape)


def _policy_kwargs(path: Any, stored: dict[str, Any]) -> dict[str, Any]:
    kwargs: dict[str, Any] = {}
    for key, value in stored.items():
        if key.startswith(":") or key in _IGNORED:
            continue
        if key in _PLAIN:
            kwargs[key] = value
        elif key == "activation_fn":
            kwargs[key] = _activation(path, value)
        elif key == "features_extractor_class":
            kwargs[key] = _extractor(path, value)
        else:
            raise _refuse(path, f"policy keyword {key}={value!r}")
    return kwargs


def _activation(path: Any, value: Any) -> type:
    import torch

    match = _CLASS.match(value) if isinstance(value, str) else None
    name = match.group(1).rsplit(".", 1)[-1] if match else None
    if not match or not match.group(1).startswith("torch.nn.") or name not in _ACTIVATIONS:
        raise _refuse(path, f"activation {value!r}")
    return getattr(torch.nn, name)


def _extractor(path: Any, value: Any) -> type:
    import importlib

    match = _CLASS.match(value) if isinstance(value, str) else None
    if not match or match.group(1) not in _EXTRACTORS:
        raise _refuse(path, f"features extractor {value!r}")
    module, _, name = match.group(1).rpartition(".")
    return getattr(importlib.import_module(module), name)

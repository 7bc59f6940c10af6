"""An SB3 model zip's deterministic policy, rebuilt without unpickling (needs ``tolins[rl]``).

stable-baselines3's ``load`` unpickles (cloudpickle) the objects of the zip's ``data``
entry: a zip from someone else could run code. Here nothing is unpickled: the policy
class, its keyword arguments and the spaces are read from the JSON that SB3 writes beside
each pickled object (class names, plain values, array texts), the network is built from
SB3's own class and the weights ``policy.pth`` are loaded with ``weights_only=True``.
Supported: PPO and A2C (``ActorCriticPolicy``), SAC and TD3 ``MlpPolicy`` on ``Box``
spaces with SB3's or tolins's features extractor and a ``torch.nn`` activation; anything
else is refused with a message (``--trust-pickle`` loads it with SB3, running its code).
The sizes the zip declares are checked before anything is built (:func:`check_sizes`).
"""

from __future__ import annotations

import io
import itertools
import os
import re
import zipfile
from typing import Any

import numpy as np

from tolins.json_input import parse_json, shorten
from tolins.learning.imitation.config import HIDDEN_MAX

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
#: What the ``data`` entry of a zip may be, for error messages.
DATA_ALLOWED = "a stable-baselines3 model zip, as SB3's save writes it"
#: The most hidden layers per network, critics (SAC, TD3) and parameters in all (target
#: networks included: 2**26 float32 are 268 MB) a zip may declare; each hidden layer has
#: 1 … ``HIDDEN_MAX`` units.
LAYERS_MAX = 16
CRITICS_MAX = 16
PARAMETERS_MAX = 2**26
#: The hidden layers each policy class builds when ``net_arch`` is not given.
_DEFAULT_ARCH = {"ActorCriticPolicy": [64, 64], "SACPolicy": [256, 256], "TD3Policy": [400, 300]}


class Sb3ZipError(ValueError):
    """The zip cannot be rebuilt without unpickling (or is no SB3 model)."""


def load_policy_without_pickle(path: str | os.PathLike, algorithm: str) -> Any:
    """The SB3 policy (``predict(observation, deterministic=True)``) of the zip at
    ``path``, saved by ``algorithm`` (``PPO``, ``A2C``, ``SAC``, ``TD3``), in eval mode."""
    import torch

    try:
        with zipfile.ZipFile(path) as archive:
            raw = archive.read("data")
            weights = archive.read("policy.pth")
    except (zipfile.BadZipFile, KeyError, OSError) as error:
        raise Sb3ZipError(f"{path}: not a stable-baselines3 model zip ({error})") from error
    data = read_data(path, raw)
    policy_class = _policy_class(path, data.get("policy_class"))
    observations = _box(path, "observation_space", data.get("observation_space"))
    actions = _box(path, "action_space", data.get("action_space"))
    kwargs = _policy_kwargs(path, data.get("policy_kwargs") or {})
    if algorithm in ("PPO", "A2C") and "use_sde" in data:
        kwargs["use_sde"] = bool(data["use_sde"])
    check_sizes(path, policy_class.__name__, kwargs, observations.shape, actions.shape)
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


def read_data(path: Any, raw: bytes) -> dict[str, Any]:
    """The JSON object of a zip's ``data`` entry ``raw``; :class:`Sb3ZipError` (one line)
    for anything else."""
    try:
        data = parse_json(raw, f"{path}: its data entry", DATA_ALLOWED)
    except ValueError as error:
        raise Sb3ZipError(str(error)) from None
    if not isinstance(data, dict):
        raise Sb3ZipError(f"{path}: its data entry is not an object; allowed: {DATA_ALLOWED}")
    return data


def check_sizes(
    path: Any,
    policy: str,
    kwargs: dict[str, Any],
    observation_shape: tuple[int, ...],
    action_shape: tuple[int, ...],
) -> None:
    """Raise :class:`Sb3ZipError` (one line) unless the networks ``kwargs`` declare for the
    policy class named ``policy`` keep within the bounds: ``net_arch`` a list of hidden
    layer widths or ``{"pi": [...], "vf"|"qf": [...]}``, each 1 … ``HIDDEN_MAX`` units and
    at most :data:`LAYERS_MAX` of them; ``n_critics`` 1 … :data:`CRITICS_MAX`; at most
    :data:`PARAMETERS_MAX` parameters in all."""
    critic = "vf" if policy == "ActorCriticPolicy" else "qf"
    arch = kwargs.get("net_arch")
    try:
        actor_layers, critic_layers = _arch(arch, critic, _DEFAULT_ARCH[policy])
    except ValueError as error:
        raise Sb3ZipError(f"{path}: net_arch={shorten(repr(arch))}: {error}") from None
    critics = kwargs.get("n_critics", 2) if critic == "qf" else 1
    if type(critics) is not int or not 1 <= critics <= CRITICS_MAX:
        raise Sb3ZipError(
            f"{path}: n_critics={shorten(repr(critics))}; allowed: an integer 1 … {CRITICS_MAX}"
        )
    inputs, outputs = int(np.prod(observation_shape)), int(np.prod(action_shape))
    count = _parameters(inputs, actor_layers, 2 * outputs)  # SAC: mean and log std
    count += critics * _parameters(inputs + outputs, critic_layers, 1)
    if critic == "qf":
        count *= 2  # the target networks
    if count > PARAMETERS_MAX:
        critics_text = f" and n_critics={critics}" if critic == "qf" else ""
        raise Sb3ZipError(
            f"{path}: net_arch={shorten(repr(arch))}{critics_text} on {inputs} observations "
            f"make {count:,} parameters; allowed: at most {PARAMETERS_MAX:,}"
        )


def _arch(arch: Any, critic: str, default: list[int]) -> tuple[list[int], list[int]]:
    """The actor's and the critic's hidden layers of ``net_arch`` ``arch`` (``critic``:
    ``vf`` or ``qf``, the key of the critic); ``ValueError`` saying what is allowed."""
    allowed = f'a list of widths or {{"pi": [...], "{critic}": [...]}}'
    if arch is None:
        return default, default
    if critic == "vf" and isinstance(arch, list) and len(arch) == 1 and isinstance(arch[0], dict):
        arch = arch[0]  # SB3 < 1.8's form, which SB3 still reads
    if isinstance(arch, list):
        return _widths(arch), _widths(arch)
    keys = set(arch) if isinstance(arch, dict) else {"?"}
    if not keys <= {"pi", critic} or (critic == "qf" and len(keys) < 2):
        raise ValueError(f"another form; allowed: {allowed}")
    return _widths(arch.get("pi", [])), _widths(arch.get(critic, []))


def _widths(layers: Any) -> list[int]:
    """``layers`` if it is a list of at most :data:`LAYERS_MAX` widths 1 … ``HIDDEN_MAX``."""
    allowed = f"at most {LAYERS_MAX} hidden layers of 1 … {HIDDEN_MAX} units each"
    if not isinstance(layers, list):
        raise ValueError(f"a {type(layers).__name__} of layers; allowed: {allowed}")
    if len(layers) > LAYERS_MAX:
        raise ValueError(f"{len(layers)} hidden layers; allowed: {allowed}")
    for width in layers:
        if type(width) is not int or not 1 <= width <= HIDDEN_MAX:
            raise ValueError(f"a layer of {shorten(repr(width))} units; allowed: {allowed}")
    return layers


def _parameters(inputs: int, hidden: list[int], outputs: int) -> int:
    """The weights and biases of an MLP ``inputs → hidden… → outputs``."""
    sizes = [inputs, *hidden, outputs]
    return sum(a * b + b for a, b in itertools.pairwise(sizes))


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

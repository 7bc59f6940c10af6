"""Policies from outside tolins as actors ``observation (8,) -> action (4,)``.

The protocol (:func:`as_actor`), checked in this order:

1. an object with ``predict(observation, deterministic=True)`` (stable-baselines3's
   signature); when it returns a tuple, its first item is the action;
2. an object with ``act(observation)``;
3. any callable ``policy(observation) -> action``.

``observation`` is the env's float64 array ``[x̂−x*, ŷ−y*, θ̂−θ*, ẑ, F̂x, F̂y, q̂θ, F̂z]``
(mm, rad, N, N·mm); the action is 4 numbers ``[ux, uy, utheta, uz]`` in mm/s and rad/s
(the env clips them to ``a_max``). A policy trained behind wrappers adapts itself, except
for SB3 ``.zip`` files (:func:`load_sb3`), whose spaces say how.
"""

from __future__ import annotations

import importlib
import os
import sys
import traceback
import zipfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from tolins.paper import A_MAX

#: What :func:`tolins.learning.agents.actors.make_actor` accepts, for error messages and help
#: texts (here, in a module without torch, so that building the CLI's parser stays fast).
ALLOWED = (
    "an expert (safe, efficient), a tolins policy file (PATH, as `tolins train` writes, or "
    "its --out folder), "
    "an SB3 model (PATH.zip) or MODULE:NAME (a callable or an object with predict/act; "
    "imported, so it runs that module's code)"
)

Actor = Callable[[np.ndarray], np.ndarray]

#: The policy module of an SB3 zip's ``policy_class`` -> the algorithm that loads it.
_SB3_ALGORITHMS = {
    "stable_baselines3.sac.policies": "SAC",
    "stable_baselines3.td3.policies": "TD3",
    "stable_baselines3.common.policies": "PPO",  # or A2C: told apart by their data below
}


class PolicyError(RuntimeError):
    """A user's policy raised (also ``SystemExit``): the message names the policy and its
    exception (chained as ``__cause__``), ``details`` is that exception's traceback."""

    def __init__(self, name: str, error: BaseException) -> None:
        message = str(error).strip().splitlines()[0] if str(error).strip() else ""
        super().__init__(f"{name} raised {type(error).__name__}" + (f": {message}" * bool(message)))
        self.details = "".join(traceback.format_exception(error))


def _calling(name: str, fn: Callable[..., Any], *args: Any) -> Any:
    """``fn(*args)``, an exception of the user's code raised as :class:`PolicyError`."""
    try:
        return fn(*args)
    except (Exception, SystemExit) as error:
        raise PolicyError(name, error) from error


def as_actor(policy: Any, name: str = "policy") -> Actor:
    """``policy`` (see the module's protocol) as ``observation -> action (4,) float64``.

    Each action is checked: ``ValueError`` when it is not 4 finite numbers; whatever the
    policy raises (``SystemExit`` too) comes out as :class:`PolicyError`.
    """
    if hasattr(policy, "predict"):

        def call(observation: np.ndarray) -> Any:
            out = policy.predict(observation, deterministic=True)
            return out[0] if isinstance(out, tuple) else out

    elif hasattr(policy, "act"):
        call = policy.act
    elif callable(policy):
        call = policy
    else:
        raise ValueError(
            f"{name} ({type(policy).__name__}) is not a policy; allowed: a callable "
            "observation -> action, or an object with a predict() or act() method"
        )

    def act(observation: np.ndarray) -> np.ndarray:
        out = _calling(name, call, observation)
        try:
            action = np.asarray(out, dtype=np.float64).reshape(-1)
        except (TypeError, ValueError):
            action = np.full(1, np.nan)
        if action.shape != (4,) or not np.all(np.isfinite(action)):
            shown = repr(action.tolist() if action.size > 1 else out)
            raise ValueError(
                f"{name} returned {shown[:200]}; allowed: 4 finite numbers "
                "[ux, uy, utheta, uz] (mm/s, rad/s)"
            )
        return action

    return act


def import_policy(target: str) -> Actor:
    """The actor named by ``MODULE:NAME`` (``NAME`` may be dotted); a class is
    instantiated without arguments. The current folder is importable."""
    module_name, _, attribute = target.partition(":")
    if not module_name or not attribute:
        raise ValueError(f"policy {target!r}; allowed: MODULE:NAME, e.g. mypkg.agents:policy")
    if os.getcwd() not in sys.path:
        sys.path.insert(0, os.getcwd())
    try:
        obj: Any = importlib.import_module(module_name)
    except ImportError as error:
        raise ValueError(f"policy {target!r}: cannot import {module_name!r} ({error})") from error
    except (Exception, SystemExit) as error:  # the module's own code, run on import
        raise PolicyError(f"policy {target!r} (importing {module_name!r})", error) from error
    for part in attribute.split("."):
        if not hasattr(obj, part):
            raise ValueError(f"policy {target!r}: module {module_name!r} has no {attribute!r}")
        obj = getattr(obj, part)
    if isinstance(obj, type):
        obj = _calling(f"policy {target!r} ({attribute}())", obj)
    return as_actor(obj, name=f"policy {target!r}")


def sb3_algorithm(path: str | os.PathLike) -> str:
    """The SB3 algorithm (``PPO``, ``A2C``, ``SAC``, ``TD3``) that saved the zip ``path``."""
    from tolins.learning.agents.sb3_zip import read_data

    try:
        with zipfile.ZipFile(path) as archive:
            raw = archive.read("data")
    except (zipfile.BadZipFile, KeyError, OSError) as error:
        raise ValueError(f"{path}: not a stable-baselines3 model zip ({error})") from error
    data = read_data(path, raw)
    try:
        module = data["policy_class"]["__module__"]
    except (KeyError, TypeError) as error:
        raise ValueError(f"{path}: not a stable-baselines3 model zip ({error})") from error
    if module not in _SB3_ALGORITHMS:
        raise ValueError(
            f"{path}: policy from {module!r}; allowed: stable-baselines3 PPO, A2C, SAC, TD3 "
            "(for others, load the model yourself and pass MODULE:NAME)"
        )
    algorithm = _SB3_ALGORITHMS[module]
    return "A2C" if algorithm == "PPO" and "clip_range" not in data else algorithm


_TRUST_PICKLE = False


def trust_pickle(enabled: bool = True) -> None:
    """Let :func:`load_sb3` load zips with SB3's own ``load`` (unpickling: it runs code
    stored in the zip) by default: ``--trust-pickle`` of ``evaluate`` and ``record``."""
    global _TRUST_PICKLE
    _TRUST_PICKLE = bool(enabled)


def load_sb3(path: str | os.PathLike, *, trust_pickle: bool | None = None) -> Actor:
    """The deterministic actor of the SB3 model zip at ``path`` (needs ``tolins[rl]``).

    By default nothing in the zip is unpickled (it could run code): the policy is rebuilt
    from the JSON and weights (:mod:`tolins.learning.agents.sb3_zip`), and a zip that cannot be
    is refused with a message. ``trust_pickle=True`` (default: :func:`trust_pickle`'s
    setting) loads it with SB3's ``load`` instead.

    The model's own spaces adapt it to the env: observations are cast to its observation
    dtype (``DtypeObservation`` during training), and its action bounds are mapped
    linearly onto ``±a_max`` (``RescaleAction``; identity when it was trained on the
    env's own bounds). Other wrappers (e.g. observation normalisation) are not known
    from a zip: wrap such a model in a callable of your own and pass ``MODULE:NAME``.
    """
    algorithm = sb3_algorithm(path)
    try:
        import stable_baselines3
    except ImportError as error:
        raise ValueError(
            f"{path}: loading an SB3 zip needs stable-baselines3: pip install 'tolins[rl]'"
        ) from error
    if _TRUST_PICKLE if trust_pickle is None else trust_pickle:
        model = getattr(stable_baselines3, algorithm).load(path, device="cpu")
    else:
        from tolins.learning.agents.sb3_zip import load_policy_without_pickle

        model = load_policy_without_pickle(path, algorithm)
    space, actions = model.observation_space, model.action_space
    if space.shape != (8,) or actions.shape != (4,):
        raise ValueError(
            f"{path}: model spaces {space.shape} -> {actions.shape}; allowed: (8,) -> (4,) "
            "(a model trained on a tolins env)"
        )
    low, high = np.asarray(actions.low, float), np.asarray(actions.high, float)
    predict = as_actor(model, name=f"SB3 model {Path(path).name}")

    def act(observation: np.ndarray) -> np.ndarray:
        action = predict(np.asarray(observation, dtype=space.dtype))
        return -A_MAX + (action - low) * (2 * A_MAX) / (high - low)

    return act

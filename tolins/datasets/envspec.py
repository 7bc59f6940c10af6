"""A tolins env as a JSON-ready gymnasium ``EnvSpec``: what a Minari dataset stores so that
``dataset.recover_environment()`` rebuilds the very env that wrote it.

A registered tolins id keeps its ``SocketSpec`` in ``kwargs``, which JSON cannot hold, so
Minari would drop the spec. :func:`dataset_env_spec` keeps the id and writes every keyword
as JSON data (the socket as ``{"type": "CircularSocket", ...}``, the initial-pose
distribution as ``{"type": "InitialPoseDistribution", ...}``, arrays as lists), with
:func:`make_env` as the entry point that turns them back.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.envs.registration import EnvSpec

import tolins  # noqa: F401  (registers the env ids)
from tolins.envs.initial_pose import InitialPoseDistribution
from tolins.envs.insertion_env import InsertionEnv
from tolins.envs.tasks import check_env_id
from tolins.geometry.specs import CircularSocket, PolygonSocket, SocketSpec

#: The entry point of every dataset's env spec.
ENTRY_POINT = "tolins.datasets.envspec:make_env"
_TYPES = {cls.__name__: cls for cls in (CircularSocket, PolygonSocket, InitialPoseDistribution)}


def encode(value: Any) -> Any:
    """``value`` as JSON data: a spec or pose distribution as ``{"type": NAME, **fields}``,
    arrays and tuples as lists."""
    if type(value).__name__ in _TYPES and dataclasses.is_dataclass(value):
        fields = {f.name: encode(getattr(value, f.name)) for f in dataclasses.fields(value)}
        return {"type": type(value).__name__, **fields}
    if isinstance(value, np.ndarray | tuple | list):
        return [encode(v) for v in (value.tolist() if isinstance(value, np.ndarray) else value)]
    if isinstance(value, np.generic):
        return value.item()
    return value


def decode(value: Any) -> Any:
    """What :func:`encode` wrote, back as a spec or distribution (lists stay lists)."""
    if isinstance(value, dict) and "type" in value:
        fields = dict(value)
        kind = fields.pop("type")
        if kind not in _TYPES:
            raise ValueError(f"type={kind!r}; allowed: {sorted(_TYPES)}")
        return _TYPES[kind](**fields)
    return value


def socket_to_json(spec: SocketSpec) -> dict[str, Any]:
    """A socket spec as JSON data (``{"type": "CircularSocket", "rows": 2, ...}``)."""
    return encode(spec)


def make_env(**kwargs: Any) -> InsertionEnv:
    """The ``InsertionEnv`` of JSON keywords written by :func:`dataset_env_spec`."""
    return InsertionEnv(**{name: decode(value) for name, value in kwargs.items()})


def dataset_env_spec(env_id: str, **kwargs: Any) -> EnvSpec:
    """The JSON-ready spec of ``gymnasium.make(env_id, **kwargs)``: the id, its registered
    keywords and ``kwargs`` (``tolins/Insert-v1`` needs ``socket=``).

    Raises ``ValueError`` for an id that is not a tolins env.
    """
    registered = gym.spec(check_env_id(env_id))
    merged = {**registered.kwargs, **kwargs}
    if "socket" not in merged:
        raise ValueError(
            f"env {env_id!r} needs socket=; allowed: a CircularSocket or PolygonSocket"
        )
    return EnvSpec(
        id=env_id,
        entry_point=ENTRY_POINT,
        kwargs={name: encode(value) for name, value in merged.items()},
    )

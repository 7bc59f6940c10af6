"""Policies named on a command line, ready to act: ``observation (8,) -> action (4,)``."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from tolins.geometry.specs import SocketSpec
from tolins.learning.embedding import encode
from tolins.learning.external import ALLOWED
from tolins.learning.policy import load_policy
from tolins.policies import EXPERTS

#: The policy file in the folder of a ``tolins train`` run.
POLICY_FILE = "policy.pt"


def make_actor(entry: str, socket: SocketSpec) -> Callable[[np.ndarray], np.ndarray]:
    """The policy ``entry``: an expert by name (``safe``, ``efficient``); a policy file
    saved by ``tolins train`` (``PATH`` or ``NAME=PATH``; ``PATH`` may be the run's folder,
    holding ``policy.pt``; a tolerance-guided policy gets the embedding of ``socket``); a
    stable-baselines3 model (``PATH.zip``, :func:`tolins.learning.external.load_sb3`); or
    ``MODULE:NAME`` (:func:`tolins.learning.external.import_policy`).

    Raises ``ValueError`` (one line: what was wrong, what is allowed).
    """
    if entry in EXPERTS:
        return EXPERTS[entry]()
    name, sep, rest = entry.partition("=")
    path = Path(rest if sep and name.isidentifier() else entry)
    if path.is_dir() and (path / POLICY_FILE).is_file():
        path = path / POLICY_FILE
    if path.suffix == ".zip" or path.is_file():
        if not path.is_file():
            raise ValueError(f"policy {entry!r}: no such file {str(path)!r}")
        if path.suffix == ".zip":
            from tolins.learning.external import load_sb3

            return load_sb3(path)
        return _policy_file(path, socket)
    if ":" in entry and not sep:
        from tolins.learning.external import import_policy

        return import_policy(entry)
    if path.is_dir():
        raise ValueError(f"policy {entry!r}: a folder without {POLICY_FILE}; allowed: {ALLOWED}")
    missing = f"no such file {str(path)!r}" if path.suffix or "/" in entry else "unknown"
    raise ValueError(f"policy {entry!r}: {missing}; allowed: {ALLOWED}")


def _policy_file(path: Path, socket: SocketSpec) -> Callable[[np.ndarray], np.ndarray]:
    policy, _ = load_policy(path)
    if policy.architecture.kind != "tolerance_guided":
        return policy.bind()
    return policy.bind(encode(socket))

"""Policies named on a command line, ready to act: ``observation (8,) -> action (4,)``."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tolins.geometry.specs import SocketSpec
from tolins.learning.agents.external import ALLOWED
from tolins.learning.embedding.encoding import encode
from tolins.learning.imitation.policy import load_policy
from tolins.policies import EXPERTS

#: The policy file in the folder of a ``tolins train`` run.
POLICY_FILE = "policy.pt"


@dataclass(frozen=True)
class PolicyRef:
    """A policy named by a program: an expert, or a trained policy and its file (what a
    command line writes as ``NAME`` or ``NAME=PATH``).

    Attributes:
        name: The expert's name (``safe``, ``efficient``) when ``path`` is ``None``, else
            the trained policy's name (a label, e.g. ``pi_n_safe``).
        path: A policy file saved by ``tolins train`` (or its run's folder) or an SB3
            ``PATH.zip``; ``None`` for an expert.
    """

    name: str
    path: Path | None = None


def make_actor(entry: str | PolicyRef, socket: SocketSpec) -> Callable[[np.ndarray], np.ndarray]:
    """The policy ``entry``: a :class:`PolicyRef`; or, as a command line names it, an
    expert by name (``safe``, ``efficient``); a policy file saved by ``tolins train``
    (``PATH`` or ``NAME=PATH``; ``PATH`` may be the run's folder, holding ``policy.pt``; a
    tolerance-guided policy gets the embedding of ``socket``); a stable-baselines3 model
    (``PATH.zip``, :func:`tolins.learning.agents.external.load_sb3`); or ``MODULE:NAME``
    (:func:`tolins.learning.agents.external.import_policy`).

    Raises ``ValueError`` (one line: what was wrong, what is allowed).
    """
    if isinstance(entry, PolicyRef):
        return _referenced(entry, socket)
    if entry in EXPERTS:
        return EXPERTS[entry]()
    name, sep, rest = entry.partition("=")
    path = _policy_path(Path(rest if sep and name.isidentifier() else entry))
    if path.suffix == ".zip" or path.is_file():
        return _saved(path, entry, socket)
    if ":" in entry and not sep:
        from tolins.learning.agents.external import import_policy

        return import_policy(entry)
    if path.is_dir():
        raise ValueError(f"policy {entry!r}: a folder without {POLICY_FILE}; allowed: {ALLOWED}")
    missing = f"no such file {str(path)!r}" if path.suffix or "/" in entry else "unknown"
    raise ValueError(f"policy {entry!r}: {missing}; allowed: {ALLOWED}")


def _referenced(ref: PolicyRef, socket: SocketSpec) -> Callable[[np.ndarray], np.ndarray]:
    """The policy ``ref`` names: its expert, or its file loaded."""
    if ref.path is None:
        if ref.name not in EXPERTS:
            allowed = ", ".join(EXPERTS)
            raise ValueError(f"policy {ref.name!r}: no such expert; allowed: {allowed}")
        return EXPERTS[ref.name]()
    return _saved(_policy_path(Path(ref.path)), f"{ref.name}={ref.path}", socket)


def _policy_path(path: Path) -> Path:
    """``path``, or its ``policy.pt`` when ``path`` is a run's folder holding one."""
    if path.is_dir() and (path / POLICY_FILE).is_file():
        return path / POLICY_FILE
    return path


def _saved(path: Path, entry: str, socket: SocketSpec) -> Callable[[np.ndarray], np.ndarray]:
    """The policy in the file ``path`` (named ``entry`` in errors): an SB3 ``.zip`` or a
    ``tolins train`` policy file."""
    if not path.is_file():
        raise ValueError(f"policy {entry!r}: no such file {str(path)!r}")
    if path.suffix == ".zip":
        from tolins.learning.agents.external import load_sb3

        return load_sb3(path)
    return _policy_file(path, socket)


def _policy_file(path: Path, socket: SocketSpec) -> Callable[[np.ndarray], np.ndarray]:
    policy, _ = load_policy(path)
    if policy.architecture.kind != "tolerance_guided":
        return policy.bind()
    return policy.bind(encode(socket))

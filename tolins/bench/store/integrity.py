"""Checked reads of what a bench reads back: stage files by digest, JSON and arrays that
name the file when they are unreadable, and episodes within what an episode can be.

Nothing read here runs code (docs/security.md): JSON with :mod:`json`, arrays with
``np.load(allow_pickle=False)``.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from pathlib import Path
from typing import Any

import numpy as np

from tolins.paper import HORIZON, SUCCESS_REWARD
from tolins.rollouts.episodes import Episode, episode_from_dict
from tolins.rollouts.forces import FORCE_FIGURES

#: The bounds of one episode's sparse reward: −1 per step at most (every step colliding),
#: c(1 − 1/k_max) at best (success at the first step).
REWARD_RANGE = (-float(HORIZON), SUCCESS_REWARD * (1 - 1 / HORIZON))


class StageFileError(ValueError):
    """A file of a finished stage that is missing, unreadable or not what was written."""


def file_digest(path: str | os.PathLike) -> str:
    """The SHA-256 (hex) of the file at ``path``."""
    digest = hashlib.sha256()
    with open(path, "rb") as file:
        for block in iter(lambda: file.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def folder_digests(folder: Path, skip: tuple[str, ...] = ()) -> dict[str, str]:
    """``relative path -> SHA-256`` of every file under ``folder`` but ``skip`` and hidden
    (temporary) files."""
    return {
        path.relative_to(folder).as_posix(): file_digest(path)
        for path in sorted(folder.rglob("*"))
        if path.is_file()
        and path.name not in skip
        and not any(part.startswith(".") for part in path.relative_to(folder).parts)
    }


def digest_problem(folder: Path, recorded: Any) -> str | None:
    """Why the files of ``folder`` are not the ones whose digests are ``recorded``
    (``None`` when they are)."""
    if not isinstance(recorded, dict) or not recorded:
        return "its stage.json lists no file digests (written by tolins ≤ 0.3, or edited)"
    for name, digest in sorted(recorded.items()):
        path = folder / name
        if not path.is_file():
            return f"{name} is missing"
        if file_digest(path) != digest:
            return f"{name} is not the file the stage wrote (its digest differs)"
    return None


def read_json(path: str | os.PathLike) -> Any:
    """The JSON document at ``path``; ``ValueError`` naming the file when it is missing,
    truncated or not JSON."""
    path = Path(path)
    try:
        return json.loads(path.read_text())
    except FileNotFoundError:
        raise StageFileError(f"{path}: missing") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as error:
        raise StageFileError(f"{path}: not JSON, perhaps truncated ({error})") from error


def read_array(path: str | os.PathLike) -> np.ndarray:
    """The ``.npy`` array at ``path`` (never unpickled); ``ValueError`` naming the file."""
    try:
        return np.load(Path(path), allow_pickle=False)
    except FileNotFoundError:
        raise StageFileError(f"{path}: missing") from None
    except (ValueError, OSError, EOFError) as error:
        raise StageFileError(f"{path}: not a numeric .npy array ({error})") from error


def checked_episodes(path: Path, rows: Any, count: int) -> list[Episode]:
    """The ``count`` episodes of the JSON ``rows`` read from ``path``; ``ValueError``
    naming the file and the first episode that is not one an episode can be."""
    if not isinstance(rows, list) or len(rows) != count:
        found = len(rows) if isinstance(rows, list) else type(rows).__name__
        raise StageFileError(f"{path}: {found} episodes; allowed: the stage's {count}")
    episodes = []
    for i, row in enumerate(rows):
        problem = _episode_problem(row)
        if problem:
            raise StageFileError(f"{path}: episode {i}: {problem}")
        episodes.append(episode_from_dict(row))
    return episodes


def _finite_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def _forces_problem(forces: Any, steps: Any) -> str | None:
    """What is wrong with an episode's ``forces`` (:class:`~tolins.rollouts.forces.
    ForceScores` as JSON): its five scores, finite and ≥ 0, ``jams`` a count ≤ ``steps``."""
    if not isinstance(forces, dict) or set(forces) != set(FORCE_FIGURES):
        keys = sorted(forces) if isinstance(forces, dict) else type(forces).__name__
        return f"forces {keys}; allowed: {sorted(FORCE_FIGURES)}"
    for name in FORCE_FIGURES:
        value = forces[name]
        if not isinstance(value, int | float) or isinstance(value, bool):
            return f"forces.{name} {value!r} is not a number"
        if not math.isfinite(value) or value < 0:
            return f"forces.{name} {value!r}; allowed: finite, ≥ 0"
    jams = forces["jams"]
    if not isinstance(jams, int) or (isinstance(steps, int) and jams > steps):
        return f"forces.jams {jams!r}; allowed: an integer 0 … steps"
    return None


def _episode_problem(row: Any) -> str | None:
    fields = {"reward", "success", "steps", "collisions", "error"}
    optional = {"forces", "profile"}  # absent from episodes recorded without force scores
    if not isinstance(row, dict) or set(row) - optional != fields:
        keys = sorted(row) if isinstance(row, dict) else type(row).__name__
        return f"fields {keys}; allowed: {sorted(fields)}, forces and profile"
    if row.get("forces") is not None:
        problem = _forces_problem(row["forces"], row["steps"])
        if problem:
            return problem
    profile = row.get("profile")
    if profile is not None and not (
        isinstance(profile, list)
        and len(profile) <= HORIZON
        and all(
            isinstance(p, list) and len(p) == 2 and all(_finite_number(v) for v in p)
            for p in profile
        )
    ):
        return f"profile is not ≤ {HORIZON} [depth, force] pairs of finite numbers (one a step)"
    reward, steps, collisions = row["reward"], row["steps"], row["collisions"]
    low, high = REWARD_RANGE
    if not isinstance(reward, int | float) or isinstance(reward, bool):
        return f"reward {reward!r} is not a number"
    if not math.isfinite(reward) or not low <= reward <= high:
        return f"reward {reward!r}; allowed: finite, {low:g} … {high:g}"
    if not isinstance(row["success"], bool):
        return f"success {row['success']!r}; allowed: true or false"
    for name, value, top in (("steps", steps, HORIZON), ("collisions", collisions, steps)):
        if not isinstance(value, int) or isinstance(value, bool) or not 0 <= value <= top:
            return f"{name} {value!r}; allowed: an integer 0 … {top}"
    if row["error"] is not None and not isinstance(row["error"], str):
        return f"error {row['error']!r}; allowed: null or a message"
    return None

"""Checked reads of what a bench reads back: stage files by digest, JSON, arrays and
curves that name the file when they are unreadable, and episodes within what an episode
can be.

Nothing read here runs code (docs/security.md): JSON with :mod:`json`, arrays with
``np.load(allow_pickle=False)``, policy files with ``torch.load(weights_only=True)``.
Every stage file the bench reads goes through a reader here or :func:`stage_file`, so
that a damaged one (even one whose digest was made to fit) is a :class:`StageFileError`:
one line naming the file and the remedy, never a stage that failed.
"""

from __future__ import annotations

import contextlib
import hashlib
import math
import os
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from tolins.bench.table.baselines import read_curves
from tolins.json_input import read_json_file
from tolins.paper import HORIZON, SUCCESS_REWARD
from tolins.rollouts.episodes import Episode, episode_from_dict
from tolins.rollouts.forces import FORCE_FIGURES

#: The bounds of one episode's sparse reward: −1 per step at most (every step colliding),
#: c(1 − 1/k_max) at best (success at the first step).
REWARD_RANGE = (-float(HORIZON), SUCCESS_REWARD * (1 - 1 / HORIZON))
#: The folder of a bench's stage folders, ``DIR/stages``.
STAGES = "stages"


class StageFileError(ValueError):
    """A file of a finished stage that is missing, unreadable or not what was written.

    Its message is one line: the file, what is wrong with it (:attr:`problem`) and the
    remedy, deleting the stage's folder (:func:`stage_folder`): the same command then runs
    that stage again.
    """

    def __init__(self, path: str | os.PathLike[str], problem: str) -> None:
        super().__init__(path, problem)
        self.path = Path(path)
        self.problem = " ".join(str(problem).split())

    def __str__(self) -> str:
        return (
            f"{self.path}: {self.problem}; delete its stage's folder "
            f"{stage_folder(self.path)} and the same command runs that stage again"
        )


def stage_folder(path: Path) -> Path:
    """The stage folder ``DIR/stages/NAME-KEY`` that holds ``path`` (else its folder)."""
    return next((p for p in path.parents if p.parent.name == STAGES), path.parent)


@contextlib.contextmanager
def stage_file(path: str | os.PathLike[str]) -> Iterator[None]:
    """Reading the stage file ``path`` inside: a ``ValueError`` or ``OSError`` of its
    loader (a policy file, an SB3 zip, a dataset) is raised as :class:`StageFileError`."""
    try:
        yield
    except StageFileError:
        raise
    except (ValueError, OSError) as error:
        text = str(error)
        problem = text.removeprefix(str(path)).removeprefix(":").strip() or type(error).__name__
        raise StageFileError(path, problem) from error


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
    """The JSON document at ``path``; :class:`StageFileError` when it is missing,
    truncated, not UTF-8 JSON or nested too deep."""
    path = Path(path)
    try:
        return read_json_file(path, "the JSON the stage wrote")
    except FileNotFoundError:
        raise StageFileError(path, "missing") from None
    except ValueError as error:
        raise StageFileError(path, str(error).removeprefix(f"{path}: ")) from error


def read_array(path: str | os.PathLike) -> np.ndarray:
    """The numeric ``.npy`` array at ``path`` (never unpickled); :class:`StageFileError`
    for anything else."""
    try:
        array = np.load(Path(path), allow_pickle=False)
    except FileNotFoundError:
        raise StageFileError(path, "missing") from None
    except (ValueError, OSError, EOFError) as error:
        raise StageFileError(path, f"not a numeric .npy array ({error})") from error
    if not isinstance(array, np.ndarray) or array.dtype.kind not in "fiu":
        if not isinstance(array, np.ndarray):
            array.close()  # an .npz archive
        raise StageFileError(path, "not a numeric .npy array")
    return array


def read_stage_curves(path: str | os.PathLike) -> list[dict[str, float]]:
    """The rows of a stage's ``curves.csv`` (:func:`~tolins.bench.table.baselines.
    read_curves`); :class:`StageFileError` when it is unreadable."""
    with stage_file(path):
        return read_curves(Path(path))


def checked_episodes(path: Path, rows: Any, count: int) -> list[Episode]:
    """The ``count`` episodes of the JSON ``rows`` read from ``path``;
    :class:`StageFileError` naming the file and the first episode that is not one an
    episode can be."""
    if not isinstance(rows, list) or len(rows) != count:
        found = len(rows) if isinstance(rows, list) else type(rows).__name__
        raise StageFileError(path, f"{found} episodes; allowed: the stage's {count}")
    episodes = []
    for i, row in enumerate(rows):
        problem = _episode_problem(row)
        if problem:
            raise StageFileError(path, f"episode {i}: {problem}")
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
    # forces and profile are absent from episodes recorded without force scores, damaged
    # from those of rigid pins
    optional = {"forces", "profile", "damaged"}
    if not isinstance(row, dict) or set(row) - optional != fields:
        keys = sorted(row) if isinstance(row, dict) else type(row).__name__
        return f"fields {keys}; allowed: {sorted(fields)}, forces, profile and damaged"
    if "damaged" in row and not isinstance(row["damaged"], bool):
        return f"damaged {row['damaged']!r}; allowed: true or false"
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

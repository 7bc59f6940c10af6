"""Run artefacts: atomic writes, checked loads, the metadata every artefact records, and
:class:`RunRefused`, what a training raises when it will not start or go on."""

from __future__ import annotations

import contextlib
import math
import os
import pickle
from collections.abc import Iterator
from dataclasses import asdict
from pathlib import Path
from typing import Any

import torch

from tolins.atomic import atomic_write


class RunRefused(Exception):
    """A training that will not start or go on: its checkpoint was written by another
    configuration or cannot be resumed, it has too little to learn from, or it diverged.
    The message is one line saying what to do instead (``tolins train`` prints it and exits
    with status 3); not a ``ValueError``, so a bug's ``ValueError`` is never taken for one."""


def atomic_torch_save(path: str | os.PathLike, payload: dict[str, Any]) -> Path:
    """``torch.save(payload)`` to ``path`` atomically."""
    return atomic_write(path, lambda file: torch.save(payload, file))


def load_payload(path: str | os.PathLike, fmt: str) -> dict[str, Any]:
    """The ``torch.load`` dict (``weights_only``) at ``path``; ``ValueError`` unless its
    ``format`` is ``fmt``."""
    try:
        payload = torch.load(Path(path), map_location="cpu", weights_only=True)
    except FileNotFoundError:
        raise
    except pickle.UnpicklingError as error:
        # torch's six lines advise weights_only=False, which would run code from the file
        text = str(error)
        if "Unsupported global" in text:
            raise ValueError(
                f"{path} holds objects other than tensors and plain values; not loaded (that "
                f"would run code from the file); allowed: a file tolins wrote in format {fmt!r}"
            ) from None
        detail = text.split("WeightsUnpickler error:", 1)[-1].strip().splitlines()
        raise ValueError(
            f"{path} is not a readable torch checkpoint (UnpicklingError: "
            f"{detail[0] if detail else ''}); allowed: a file tolins wrote in format {fmt!r}"
        ) from None
    except Exception as error:
        detail = _first(error)
        raise ValueError(
            f"{path} is not a readable torch checkpoint ({detail}); allowed: a file tolins "
            f"wrote in format {fmt!r}"
        ) from error
    found = payload.get("format") if isinstance(payload, dict) else type(payload).__name__
    if found != fmt:
        raise ValueError(f"{path} has format {found!r}; allowed: {fmt!r}")
    return payload


def _first(error: BaseException) -> str:
    """``Type: first line of the message`` (the type alone when it has none)."""
    lines = str(error).strip().splitlines()
    return f"{type(error).__name__}: {lines[0]}" if lines else type(error).__name__


def run_metadata(seed: int, **configs: Any) -> dict[str, Any]:
    """What every artefact records: each config (a dataclass or dict), the seed, the version."""
    import tolins

    return {
        "configs": {
            name: asdict(c) if hasattr(c, "__dataclass_fields__") else c
            for name, c in configs.items()
        },
        "seed": int(seed),
        "tolins_version": tolins.__version__,
    }


def check_finite_training(
    what: str, epoch: int, loss: float, network: torch.nn.Module, learning_rate: float
) -> None:
    """Raise :class:`RunRefused` when a training has diverged: ``loss`` (of ``epoch``) or a
    weight of ``network`` is NaN or infinite, so that no model of NaN weights is saved."""
    finite = math.isfinite(loss) and all(bool(p.isfinite().all()) for p in network.parameters())
    if not finite:
        raise RunRefused(
            f"{what} diverged: loss {loss:g} at epoch {epoch}, weights not all finite "
            f"(learning_rate={learning_rate:g}); nothing written; allowed: a smaller "
            "--learning-rate"
        )


@contextlib.contextmanager
def single_threaded_torch() -> Iterator[None]:
    """Run torch on one thread inside the block (restored after). The networks are tiny:
    intra-op threads only contend with the rollout threads (measured 20× slower on 2
    busy cores)."""
    before = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        yield
    finally:
        torch.set_num_threads(before)

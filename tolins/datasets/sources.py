"""Who acts in a dataset's episodes: a policy by name, or a named recipe of several.

A recipe deals its policies to the episodes in turn (episode ``i`` gets policy
``i mod k``), so the mix is exact and the same on every run:

=================  ==========================================================
recipe             policies
=================  ==========================================================
expert-safe        the safe scripted expert (``safe``)
expert-efficient   the efficient scripted expert (``efficient``)
bc                 a BC policy cloned here from the safe expert (``bc``)
random             uniform random actions in ``±a_max`` (``random``)
mixed              safe, efficient, bc, random in turn
=================  ==========================================================

The ``bc`` policy is :func:`tolins.learning.runs.run_bc`'s π_bc with the default configs
and the dataset's seed (50 safe-expert episodes, 200 epochs): the same policy as
``tolins train bc --env ID --seed SEED --backend BACKEND``. It is trained when its first
episode starts, so that a dataset's options are all checked before that work.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from tolins.geometry.specs import SocketSpec
from tolins.paper import A_MAX

Policy = Callable[[np.ndarray], np.ndarray]

#: What ``--policy`` takes, for error messages.
POLICY_FORMS = (
    "--policy takes a .zip/.pt file path (or a `tolins train` --out folder), MODULE:NAME "
    "(imports that module) or one of: safe, efficient, random, bc"
)

#: Recipe name -> the policy names dealt to its episodes in turn.
RECIPES: dict[str, tuple[str, ...]] = {
    "expert-safe": ("safe",),
    "expert-efficient": ("efficient",),
    "bc": ("bc",),
    "random": ("random",),
    "mixed": ("safe", "efficient", "bc", "random"),
}


@dataclass(frozen=True)
class Source:
    """One policy of a dataset: its name (each episode records it) and a maker of the
    policy for an episode's seed (only ``random`` uses the seed)."""

    name: str
    make: Callable[[int], Policy]


class RandomPolicy:
    """Uniform random actions in ``[-a_max, a_max]`` from a generator seeded by ``seed``."""

    def __init__(self, seed: int) -> None:
        self._rng = np.random.default_rng([seed, 0x5A4D])

    def __call__(self, observation: np.ndarray) -> np.ndarray:
        return self._rng.uniform(-A_MAX, A_MAX)


def _bc_policy(env_id: str, backend: str, seed: int) -> Policy:
    """π_bc of ``tolins train bc`` with the default configs (trained here, a few seconds)."""
    from tolins.learning.bc import behaviour_clone
    from tolins.learning.policy_config import BCConfig, TaskConfig
    from tolins.learning.runs import demonstrations

    task = TaskConfig(backend=backend, seed=seed)
    return behaviour_clone(demonstrations([env_id], task), BCConfig(), seed=seed).policy.bind()


def make_source(entry: str, socket: SocketSpec, *, env_id: str, backend: str, seed: int) -> Source:
    """The policy ``entry``: ``random``, ``bc`` (see the module docstring; trained on first
    use), or anything :func:`tolins.learning.actors.make_actor` takes (``safe``,
    ``efficient``, a policy file, an SB3 ``.zip``, ``MODULE:NAME``). Raises ``ValueError``
    for a bad entry."""
    if entry == "random":
        return Source("random", RandomPolicy)
    if entry == "bc":
        trained = functools.cache(lambda: _bc_policy(env_id, backend, seed))
        return Source("bc", lambda _: trained())
    from tolins.learning.actors import make_actor

    try:
        actor = make_actor(entry, socket)
    except ValueError as error:  # what was wrong, and every --policy form (random, bc too)
        problem = str(error).partition("; allowed: ")[0]
        raise ValueError(f"{problem}; {POLICY_FORMS}") from None
    return Source(entry, lambda _: actor)


def recipe_entries(recipe: str) -> tuple[str, ...]:
    """The policy names of ``recipe``; ``ValueError`` naming the recipes otherwise."""
    if recipe not in RECIPES:
        raise ValueError(f"recipe {recipe!r} is unknown; allowed: {', '.join(RECIPES)}")
    return RECIPES[recipe]

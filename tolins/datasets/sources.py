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

Datasets sit below learning, so the policies that need learning code come in from the
caller: ``make_actor`` turns a name or file into a policy, and ``train_bc`` makes the ``bc``
policy. ``tolins dataset`` passes :func:`tolins.learning.agents.actors.make_actor` and
:func:`tolins.learning.imitation.runs.trained_bc`, π_bc with the default configs and the dataset's
seed (50 safe-expert episodes, 200 epochs): the same policy as
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

#: Makes the policy a name or file stands for (``ValueError`` for a bad one).
ActorMaker = Callable[[str, SocketSpec], Policy]

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


def make_source(
    entry: str,
    socket: SocketSpec,
    *,
    make_actor: ActorMaker,
    train_bc: Callable[[], Policy],
) -> Source:
    """The policy ``entry``: ``random``; ``bc``, the policy ``train_bc()`` returns (called
    once, when the first ``bc`` episode starts); or ``make_actor(entry, socket)`` for
    anything else (an expert's name, a policy file, an SB3 ``.zip``, ``MODULE:NAME``).
    Raises ``ValueError`` for a bad entry, naming every ``--policy`` form."""
    if entry == "random":
        return Source("random", RandomPolicy)
    if entry == "bc":
        trained = functools.cache(train_bc)
        return Source("bc", lambda _: trained())
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

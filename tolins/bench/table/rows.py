"""The paper's Table 1: its 15 rows, what trains each policy, and the paper's figures."""

from __future__ import annotations

from dataclasses import dataclass

from tolins.names import comma_separated

#: The physics version every row trains and is evaluated on (the ids' ``-v2``).
PHYSICS_VERSION = 2


def seeded(name: str, seed: int) -> str:
    """A stage name: ``name`` for training seed ``seed``, e.g. ``pi_n_safe-seed0``."""
    return f"{name}-seed{seed}"


def unseeded(stage: str) -> str:
    """The name a stage name was :func:`seeded` from (a name without a seed itself)."""
    return stage.rpartition("-seed")[0] or stage


def seed_order(stage: str) -> tuple[str, int]:
    """A sort key of stage names: by :func:`unseeded` name, then by seed as a number
    (``-seed2`` before ``-seed10``; a name without a seed first)."""
    base, _, seed = stage.rpartition("-seed")
    return (base, int(seed)) if base and seed.isdigit() else (stage, -1)


def bench_id(name: str) -> str:
    """The id of the preset ``name`` in the bench's physics version."""
    return f"tolins/{name}-v{PHYSICS_VERSION}"


CIRCLE_2X1_DEFECTIVE = bench_id("Circle2x1Defective")
CIRCLE_2X2 = bench_id("Circle2x2")
CIRCLE_2X4 = bench_id("Circle2x4")
CIRCLE_2X8 = bench_id("Circle2x8")
SQUARE = bench_id("Square")
PENTAGON = bench_id("Pentagon")
HEXAGON = bench_id("Hexagon")


@dataclass(frozen=True)
class Training:
    """One trained policy of the pipeline.

    Attributes:
        name: Stage name, e.g. ``pi_n_safe``.
        method: ``bc``, ``rs-gail`` (π_n from the BC policy ``upstream``),
            ``tolerance-guided`` (φ2 over ``env_ids`` with φ1 from the π_n ``upstream``), or
            a deep-RL baseline from scratch, ``ppo`` or ``sac`` (stable-baselines3,
            :mod:`tolins.learning.agents.sb3`; ``expert`` unused).
        env_ids: Training environments.
        expert: The scripted expert imitated (``safe`` or ``efficient``).
        upstream: The training this one starts from, or ``None``.
        reward_mode: The reward a deep-RL baseline learns from (``sparse``: the paper's,
            ``dense``: :mod:`tolins.envs.reward`); ``None`` for imitation, which learns
            from the paper's sparse reward and its discriminator.
    """

    name: str
    method: str
    env_ids: tuple[str, ...]
    expert: str
    upstream: str | None = None
    reward_mode: str | None = None


#: Trainings by stable-baselines3 (deep RL from scratch, beyond the paper).
SB3_METHODS = ("ppo", "sac")
#: The rewards the deep-RL baselines learn from: the paper's, and a shaped one.
BASELINE_REWARDS = ("sparse", "dense")


def _chain(suffix: str, env_ids: tuple[str, ...], expert: str) -> tuple[Training, Training]:
    bc = Training(f"bc_{suffix}", "bc", env_ids, expert)
    return bc, Training(f"pi_n_{suffix}", "rs-gail", env_ids, expert, bc.name)


#: Every training, upstream first.
TRAININGS: dict[str, Training] = {
    t.name: t
    for t in (
        *_chain("efficient", (CIRCLE_2X2,), "efficient"),
        *_chain("safe", (CIRCLE_2X2,), "safe"),
        Training(
            "pi_phi_circle", "tolerance-guided", (CIRCLE_2X2, CIRCLE_2X8), "safe", "pi_n_safe"
        ),
        *_chain("square", (SQUARE,), "safe"),
        Training("pi_phi_polygon", "tolerance-guided", (SQUARE, HEXAGON), "safe", "pi_n_square"),
        *(
            Training(f"{algorithm}_{suffix}_{reward}", algorithm, (env_id,), "safe", None, reward)
            for reward in BASELINE_REWARDS
            for suffix, env_id in (("circle", CIRCLE_2X2), ("square", SQUARE))
            for algorithm in SB3_METHODS
        ),
    )
}


@dataclass(frozen=True)
class Row:
    """One row of Table 1.

    Attributes:
        id: The paper's id, e.g. ``C2.3``.
        policy: The paper's name of the policy (``π_e^safe``, ``π_bc``, ``π_n``, ...).
        agent: An expert name (``safe``, ``efficient``) or a :data:`TRAININGS` name.
        eval_env: The gymnasium id it is evaluated on.
        train_env: The paper's "Train env" column.
        inference: Wrap the policy in probabilistic inference (π_φ*).
    """

    id: str
    policy: str
    agent: str
    eval_env: str
    train_env: str
    inference: bool = False

    @property
    def trainings(self) -> list[Training]:
        """The trainings this row needs, upstream first."""
        chain, name = [], self.agent if self.agent in TRAININGS else None
        while name is not None:
            chain.insert(0, TRAININGS[name])
            name = TRAININGS[name].upstream
        return chain


ROWS: tuple[Row, ...] = (
    Row("C1.1", "π_e^eff", "efficient", CIRCLE_2X2, "2*2"),
    Row("C1.2", "π_bc", "bc_efficient", CIRCLE_2X2, "2*2"),
    Row("C1.3", "π_n", "pi_n_efficient", CIRCLE_2X2, "2*2"),
    Row("C2.1", "π_e^safe", "safe", CIRCLE_2X2, "2*2"),
    Row("C2.2", "π_bc", "bc_safe", CIRCLE_2X2, "2*2"),
    Row("C2.3", "π_n", "pi_n_safe", CIRCLE_2X2, "2*2"),
    Row("C3.1", "π_n", "pi_n_safe", CIRCLE_2X4, "2*2"),
    Row("C3.2", "π_φ", "pi_phi_circle", CIRCLE_2X4, "2*2, 2*8"),
    Row("C4.1", "π_φ", "pi_phi_circle", CIRCLE_2X1_DEFECTIVE, "2*2, 2*8"),
    Row("C4.2", "π_φ*", "pi_phi_circle", CIRCLE_2X1_DEFECTIVE, "-", inference=True),
    Row("P1.1", "π_e^safe", "safe", SQUARE, "square"),
    Row("P1.2", "π_bc", "bc_square", SQUARE, "square"),
    Row("P1.3", "π_n", "pi_n_square", SQUARE, "square"),
    Row("P2.1", "π_n", "pi_n_square", PENTAGON, "square"),
    Row("P2.2", "π_φ", "pi_phi_polygon", PENTAGON, "square, hexagon"),
)
ROW_IDS: tuple[str, ...] = tuple(row.id for row in ROWS)

#: Rows beyond the paper: deep-RL baselines trained from scratch within RS-GAIL's
#: env-step budget for π_n, evaluated like every row (sparse reward). R1: on the paper's
#: sparse reward (what its claim is about); R2: on the dense, shaped reward.
BASELINE_ROWS: tuple[Row, ...] = tuple(
    Row(
        f"R{group}.{index}",
        f"{algorithm.upper()} ({reward})",
        f"{algorithm}_{suffix}_{reward}",
        env_id,
        train_env,
    )
    for group, reward in enumerate(BASELINE_REWARDS, start=1)
    for index, (algorithm, suffix, env_id, train_env) in enumerate(
        (
            ("ppo", "circle", CIRCLE_2X2, "2*2"),
            ("sac", "circle", CIRCLE_2X2, "2*2"),
            ("ppo", "square", SQUARE, "square"),
            ("sac", "square", SQUARE, "square"),
        ),
        start=1,
    )
)
#: Table 1's rows, then the baselines: what ``tolins bench`` runs by default.
ALL_ROWS: tuple[Row, ...] = ROWS + BASELINE_ROWS
ALL_ROW_IDS: tuple[str, ...] = tuple(row.id for row in ALL_ROWS)

#: Table 1 of the paper: (mean, std) of reward, success rate, steps, collisions.
PAPER: dict[str, dict[str, tuple[float, float]]] = {
    row_id: dict(zip(("reward", "success", "steps", "collisions"), pairs, strict=True))
    for row_id, pairs in {
        "C1.1": ((13.76, 1.20), (0.75, 0.03), (29.65, 0.23), (6.11, 0.71)),
        "C1.2": ((6.57, 3.07), (0.68, 0.04), (30.91, 0.71), (8.15, 1.31)),
        "C1.3": ((20.82, 0.76), (0.94, 0.03), (31.05, 0.24), (1.69, 0.28)),
        "C2.1": ((11.28, 0.72), (0.77, 0.04), (35.49, 0.29), (0.0, 0.0)),
        "C2.2": ((4.94, 0.96), (0.58, 0.05), (37.69, 0.28), (0.83, 0.31)),
        "C2.3": ((20.58, 0.71), (0.90, 0.02), (31.40, 0.20), (0.91, 0.24)),
        "C3.1": ((16.38, 1.53), (0.84, 0.03), (33.37, 0.43), (2.74, 0.49)),
        "C3.2": ((20.47, 0.54), (0.92, 0.01), (31.42, 0.18), (0.98, 0.10)),
        "C4.1": ((6.04, 1.28), (0.30, 0.03), (35.03, 0.53), (6.42, 0.11)),
        "C4.2": ((12.44, 2.38), (0.41, 0.02), (32.80, 0.82), (5.60, 0.37)),
        "P1.1": ((12.36, 0.41), (0.82, 0.03), (35.05, 0.16), (0.0, 0.0)),
        "P1.2": ((7.46, 0.30), (0.68, 0.02), (37.02, 0.12), (0.0, 0.0)),
        "P1.3": ((15.47, 0.54), (0.87, 0.01), (33.96, 0.18), (2.14, 0.17)),
        "P2.1": ((15.82, 0.43), (0.87, 0.01), (32.91, 0.16), (1.90, 0.05)),
        "P2.2": ((16.01, 0.51), (0.89, 0.02), (32.84, 0.20), (1.88, 0.01)),
    }.items()
}


def select_rows(ids: str | list[str] | None, *, baselines: bool = True) -> list[Row]:
    """The rows named in ``ids`` (comma-separated or a list; ``None``: Table 1's, then the
    baselines' if ``baselines``), in table order."""
    if ids is None:
        return list(ALL_ROWS if baselines else ROWS)
    wanted = comma_separated(
        ids if isinstance(ids, str) else ",".join(ids), ALL_ROW_IDS, option="rows"
    )
    return [row for row in ALL_ROWS if row.id in wanted]

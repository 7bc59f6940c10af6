"""What ``tolins bench`` runs (:class:`BenchConfig`) and what a run produced (:class:`BenchRun`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tolins.bench.pipeline.executor import EXECUTORS, check_address
from tolins.bench.pipeline.profiles import PROFILES, Profile
from tolins.bench.table.claims import ClaimCheck
from tolins.bench.table.rows import select_rows
from tolins.physics import BACKENDS

if TYPE_CHECKING:
    from tolins.rollouts.episodes import Episode

#: The most training seeds of a bench: each is a whole training of every row (the paper
#: profile's five take 107 min on 2 cores).
SEEDS_MAX = 100


@dataclass(frozen=True)
class BenchConfig:
    """What ``tolins bench`` runs.

    Attributes:
        profile: ``quick`` (default, about 8 min on 2 cores), ``paper`` or ``tiny``.
        rows: Row ids (comma-separated), ``None`` for all 15.
        backend: ``mujoco`` (contact physics) or ``kinematic`` (the paper's simulator).
        seeds: Training seeds; ``None``: the profile's.
        out: Output folder.
        study: Run the inference study.
        robustness: Run the robustness table (:mod:`tolins.bench.table.robustness`).
        robot: Run the Panda's table (:mod:`tolins.bench.table.robot`; MuJoCo only, needs
            ``tolins[robot]``).
        delicate: Run the delicate-pins table (:mod:`tolins.bench.table.delicate`; MuJoCo
            only).
        figures: Draw the figures (the PNGs that results.md shows); without them a run
            writes its results, results.md and recordings only (a re-report of a finished
            bench takes seconds fewer) and removes an earlier run's figures.
        workers: Threads evaluating rows side by side (results do not depend on it).
        executor: ``local`` (this process) or ``ray`` (Ray tasks; ``tolins[ray]``): where
            the stages run (:mod:`tolins.bench.pipeline.executor`; results do not depend on it).
        address: With ``ray``: ``None`` starts Ray on this machine, ``auto`` or
            ``HOST:PORT`` connects to a running cluster.
    """

    profile: str = "quick"
    rows: str | None = None
    backend: str = "mujoco"
    seeds: int | None = None
    out: str = "bench"
    study: bool = True
    robustness: bool = True
    robot: bool = True
    delicate: bool = True
    figures: bool = True
    workers: int = 2
    executor: str = "local"
    address: str | None = None

    def __post_init__(self) -> None:
        if self.profile not in PROFILES:
            raise ValueError(f"profile={self.profile!r}; allowed: {', '.join(PROFILES)}")
        if self.backend not in BACKENDS:
            raise ValueError(f"backend={self.backend!r}; allowed: {', '.join(BACKENDS)}")
        if self.seeds is not None and (
            not isinstance(self.seeds, int) or not 1 <= self.seeds <= SEEDS_MAX
        ):
            raise ValueError(f"seeds={self.seeds!r}; allowed: an integer 1 … {SEEDS_MAX}")
        if not isinstance(self.workers, int) or self.workers < 1:
            raise ValueError(f"workers={self.workers!r}; allowed: an integer ≥ 1")
        if self.executor not in EXECUTORS:
            raise ValueError(f"executor={self.executor!r}; allowed: {', '.join(EXECUTORS)}")
        if self.address is not None and self.executor != "ray":
            raise ValueError(f"address={self.address!r} needs executor='ray' (--executor ray)")
        check_address(self.address)
        select_rows(self.rows)  # raises on unknown ids


@dataclass
class BenchRun:
    """What a run produced: the entries of ``results.json``, the claims, the study."""

    config: BenchConfig
    profile: Profile
    results: dict[str, dict[str, Any]]
    claims: list[ClaimCheck]
    study: dict[str, Any] | None
    wall_s: float
    stage_wall_s: dict[str, float] = field(default_factory=dict)
    cached: list[str] = field(default_factory=list)
    stage_folders: dict[str, Path] = field(default_factory=dict)
    stage_times: dict[str, dict[str, Any]] = field(default_factory=dict)
    """Per stage: ``started``/``finished`` (Unix time), ``wall_s``, ``cached``, and where it
    ran (``host``, ``pid``; ``node``: the Ray node id or ``None``; ``thread``)."""
    episodes: dict[str, list[list[Episode]]] = field(default_factory=dict)
    """Per row: its evaluation episodes, one list per training seed (read from its stages,
    checked)."""
    robustness: dict[str, Any] | None = None
    """``results.json["robustness"]`` (:func:`tolins.bench.jobs.robustness.robustness_results`)."""
    robot: dict[str, Any] | None = None
    """``results.json["robot"]``: the Panda's table (:mod:`tolins.bench.table.robot`)."""
    delicate: dict[str, Any] | None = None
    """``results.json["delicate"]``: the delicate-pins table, its claim and gentlest learned
    policy (:mod:`tolins.bench.table.delicate`)."""

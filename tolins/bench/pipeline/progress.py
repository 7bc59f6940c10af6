"""One progress bar over every stage of a bench run: how much of the run's work is done,
the stage running now, and an estimate of the time left.

Each stage has an expected cost in seconds (:func:`expected_cost`): the env steps its
profile budgets for it (episodes × horizon, RS-GAIL's candidates, a baseline's steps, BC's
epochs over its demonstrations, the study's workpieces) times what a step of that kind of
work took on 2 cores (:data:`STEP_SECONDS`, from an idle quick bench's stage times),
plus a fixed start-up cost. The bar's fraction is the expected cost of the
finished stages (cached ones included) over that of all of them.

The time left (:meth:`BenchProgress.remaining_s`) follows the stages as they finish: the
expected costs of a kind (:data:`KINDS`) are scaled by measured / expected over its
finished stages (over all finished stages while none of its own has finished), a running
stage is credited with the time it has run, and the cost left of each kind is divided by
how many of its stages ran at once (their measured wall time over the time they spanned:
the local executor's evaluation threads, a Ray cluster's tasks).
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Collection, Mapping
from dataclasses import dataclass
from typing import Any

from tqdm import tqdm

from tolins.bench.jobs import robustness, row_evaluation, study
from tolins.bench.jobs.robustness import PREFIX as ROBUST
from tolins.bench.jobs.trajectories import NAME as TRAJECTORIES
from tolins.bench.jobs.trajectories import POINTS as TRAJECTORY_EPISODES
from tolins.bench.pipeline import settings
from tolins.bench.pipeline.profiles import Profile
from tolins.bench.table.robot import ROBOT
from tolins.bench.table.robustness import ROBUSTNESS, ConditionTable
from tolins.bench.table.rows import ALL_ROWS, SB3_METHODS, TRAININGS, unseeded
from tolins.paper import HORIZON

#: The kinds of stages, in the order a run meets them.
KINDS = ("demonstrations", "training", "evaluation", "robustness", "robot", "study")
#: Seconds per budgeted env step (per BC sample and epoch, per study workpiece) of each
#: kind of work on the MuJoCo backend's ``-v2`` physics, two stages side by side on 2
#: cores: the quick bench of an idle fresh clone (2026-12-04, 7.7 min; benchmarks/README.md,
#: "``tolins bench`` wall time"), each kind's measured stage time over its budget; the
#: deep-RL baselines' from the ``-v2`` paper run's trainings (PPO 280 s and SAC 1,440 s
#: for 288,000 env steps, two side by side).
STEP_SECONDS = {
    "rollout": 1.06e-3,  # an evaluation, robustness or demonstration episode's step
    "panda-rollout": 17e-3,  # a step of the Panda's table
    "rs-gail": 1.1e-3,
    "tolerance-guided": 0.41e-3,
    "ppo": 0.97e-3,  # on 8 envs in one batch
    "sac": 5.0e-3,
    "bc": 1.9e-6,  # per demonstration step and epoch
    "study": 0.14,  # per workpiece, MuJoCo contact outcomes
    "study-model": 0.01,  # per workpiece, the tolerance model's outcomes (kinematic)
}
#: An inference-wrapped policy (π_φ*) costs this many times its policy's episodes.
INFERENCE_FACTOR = 3.0
#: A step of the kinematic backend costs this fraction of MuJoCo's.
KINEMATIC_FACTOR = 0.4
#: What a stage costs besides its budget (imports, setup, files).
STAGE_SECONDS = 0.5
#: What the inference study costs besides its workpieces (starting its processes).
STUDY_SECONDS = 5.0


def stage_kind(name: str) -> str:
    """The kind (:data:`KINDS`) of the stage called ``name``."""
    if name.startswith("demos-"):
        return "demonstrations"
    if name.startswith("eval-") or name == TRAJECTORIES:
        return "evaluation"
    if name.startswith(ROBUST):
        return "robustness"
    if name.startswith(ROBOT.prefix):
        return "robot"
    return "study" if name == study.NAME else "training"


def expected_cost(name: str, profile: Profile, backend: str) -> float:
    """The expected wall time (s) of the stage ``name`` under ``profile`` on ``backend``
    (a name the bench does not make costs :data:`STAGE_SECONDS`)."""
    steps, per_step = _budget(name, stage_kind(name), profile, backend)
    if per_step == "study" and backend == "kinematic":
        per_step = "study-model"
    elif per_step != "bc" and backend == "kinematic":
        steps *= KINEMATIC_FACTOR
    fixed = STUDY_SECONDS if per_step.startswith("study") else STAGE_SECONDS
    return fixed + steps * STEP_SECONDS.get(per_step, 0.0)


def _budget(name: str, kind: str, profile: Profile, backend: str) -> tuple[float, str]:
    """The budgeted work of the stage ``name`` of ``kind`` and its unit of cost."""
    base = unseeded(name)
    if kind == "demonstrations":
        return profile.demonstrations * HORIZON, "rollout"
    if kind == "study":
        config = settings.study_settings(profile, backend)
        return config.samples + (len(config.kinds) - 1) * config.kind_samples, "study"
    if kind == "evaluation" and name == TRAJECTORIES:
        return (TRAJECTORY_EPISODES + 1) * HORIZON, "rollout"
    if kind == "evaluation":
        same = (row for row in ALL_ROWS if unseeded(row_evaluation.stage_name(row, 0)) == base)
        row = next(same, None)
        factor = INFERENCE_FACTOR if row is not None and row.inference else 1.0
        return profile.eval_episodes * HORIZON * factor, "rollout"
    if kind in ("robustness", "robot"):
        table: ConditionTable = ROBUSTNESS if kind == "robustness" else ROBOT
        named = (p for p in table.policies if unseeded(robustness.stage_name(p, 0, table)) == base)
        policy = next(named, None)
        factor = INFERENCE_FACTOR if policy is not None and policy.inference else 1.0
        episodes = profile.robustness_episodes * len(table.conditions)
        return episodes * HORIZON * factor, "rollout" if kind == "robustness" else "panda-rollout"
    training = TRAININGS.get(base)
    if training is None:
        return 0.0, "rollout"
    envs = len(training.env_ids)
    if training.method in SB3_METHODS:
        return profile.deep_rl_env_steps, training.method
    if training.method == "bc":
        return profile.bc_epochs * profile.demonstrations * envs * HORIZON, "bc"
    if training.method == "tolerance-guided":
        steps = profile.residual_iterations * profile.iteration_episodes * HORIZON * envs
        return steps, training.method
    return profile.rs_gail_env_steps * envs, training.method


@dataclass
class _Stage:
    """What is known of one stage: expected cost, when it started (this progress's
    clock), its measured wall time and when it finished."""

    kind: str
    expected: float
    done: bool = False
    started: float | None = None
    wall_s: float | None = None
    finished: float | None = None


class BenchProgress:
    """The progress of a bench run's stages, shown as one tqdm bar.

    Args:
        expected: Every stage of the run: name -> expected cost (s, :func:`expected_cost`).
        done: The stages finished before (cached).
        show: Draw the bar (on stderr); without it only the figures are kept.
        clock: Seconds, monotonic (for tests).
        refresh_s: Redraw the bar this often (s) between stage events, so that the
            elapsed time and the estimate move during a long stage; ``None``: only at
            events.
    """

    def __init__(
        self,
        expected: Mapping[str, float],
        done: Collection[str] = (),
        *,
        show: bool = True,
        clock: Callable[[], float] = time.monotonic,
        refresh_s: float | None = 2.0,
    ) -> None:
        self._stages = {
            name: _Stage(stage_kind(name), float(cost), name in done)
            for name, cost in expected.items()
        }
        self._total = sum(stage.expected for stage in self._stages.values())
        self._clock = clock
        self._lock = threading.RLock()
        self._bar: Any = None
        self._stop = threading.Event()
        if show:
            self._bar = tqdm(
                total=max(self._total, 1e-9),
                desc="bench",
                bar_format="{desc}: {percentage:3.0f}%|{bar}| {elapsed}{postfix}",
            )
            self._draw()
            if refresh_s is not None:
                threading.Thread(target=self._tick, args=(refresh_s,), daemon=True).start()

    def __enter__(self) -> BenchProgress:
        return self

    def __exit__(self, *_: object) -> None:
        self.close()

    @property
    def total(self) -> int:
        """How many stages the run has (cached ones included)."""
        return len(self._stages)

    @property
    def finished(self) -> int:
        """How many of them have finished (cached ones included)."""
        return sum(stage.done for stage in self._stages.values())

    @property
    def fraction(self) -> float:
        """The expected cost of the finished stages over that of all of them."""
        done = sum(stage.expected for stage in self._stages.values() if stage.done)
        return done / self._total if self._total > 0 else 1.0

    def start(self, name: str) -> None:
        """Stage ``name`` has started."""
        with self._lock:
            self._stages[name].started = self._clock()
            self._draw()

    def finish(self, name: str, wall_s: float) -> None:
        """Stage ``name`` has finished, having taken ``wall_s`` seconds."""
        with self._lock:
            stage = self._stages[name]
            stage.done, stage.wall_s, stage.finished = True, float(wall_s), self._clock()
            self._draw()

    def current(self) -> str | None:
        """The stage running longest now, as ``kind name`` (``+N more`` running beside
        it); ``None`` when none runs."""
        with self._lock:
            running = sorted((s.started, n) for n, s in self._stages.items() if _running(s))
        if not running:
            return None
        name = running[0][1]
        more = f" (+{len(running) - 1} more)" if len(running) > 1 else ""
        return f"{self._stages[name].kind} {name}{more}"

    def remaining_s(self) -> float:
        """The estimated wall time (s) until every stage has finished."""
        with self._lock:
            now = self._clock()
            ran = [s for s in self._stages.values() if s.wall_s is not None]
            overall = _ratio(ran, 1.0)
            left = 0.0
            for kind in KINDS:
                stages = [s for s in self._stages.values() if s.kind == kind]
                ratio = _ratio([s for s in stages if s.wall_s is not None], overall)
                cost = sum(_left(s, ratio, now) for s in stages if not s.done)
                left += cost / _concurrency(stages, now) if cost else 0.0
            return left

    def close(self) -> None:
        """Stop redrawing and leave the bar as it is."""
        self._stop.set()
        with self._lock:
            if self._bar is not None:
                self._bar.close()
                self._bar = None

    def _tick(self, every: float) -> None:
        while not self._stop.wait(every):
            with self._lock:
                self._draw()

    def _draw(self) -> None:
        """Redraw the bar: the work done, the stages done, the one running, the time left."""
        if self._bar is None:
            return
        now = self.current()
        parts = [f"{self.finished}/{self.total} stages"]
        if now is not None:
            parts.append(now)
        if self.finished < self.total:
            parts.append(f"about {format_duration(self.remaining_s())} left")
        self._bar.n = self.fraction * self._bar.total
        self._bar.set_postfix_str(", ".join(parts), refresh=True)


def _ratio(stages: list[_Stage], default: float) -> float:
    """Measured over expected wall time of finished ``stages`` (``default`` without any)."""
    expected = sum(s.expected for s in stages)
    if not stages or expected <= 0:
        return default
    return sum(s.wall_s or 0.0 for s in stages) / expected


def _left(stage: _Stage, ratio: float, now: float) -> float:
    """What is left of an unfinished stage (s): its scaled cost less the time it has run."""
    cost = stage.expected * ratio
    return cost if stage.started is None else max(cost - (now - stage.started), 0.0)


def _concurrency(stages: list[_Stage], now: float) -> float:
    """How many of ``stages`` ran at once: their measured (or, while running, elapsed)
    wall time over the union of their intervals; 1 before any has run."""
    spans = sorted(_span(s, now) for s in stages if s.finished is not None or _running(s))
    busy = sum(end - start for start, end in spans)
    covered, reach = 0.0, -float("inf")
    for start, end in spans:
        covered += max(end - max(start, reach), 0.0)
        reach = max(reach, end)
    return max(busy / covered, 1.0) if covered > 0 else 1.0


def _running(stage: _Stage) -> bool:
    return stage.started is not None and not stage.done


def _span(stage: _Stage, now: float) -> tuple[float, float]:
    """When a stage ran (this progress's clock): to ``now`` if it still runs."""
    if stage.finished is not None and stage.wall_s is not None:
        return stage.finished - stage.wall_s, stage.finished
    return stage.started or now, now


def format_duration(seconds: float) -> str:
    """``seconds`` as ``45 s``, ``12 min`` or ``1 h 05 min``."""
    if seconds < 60:
        return f"{seconds:.0f} s"
    minutes = round(seconds / 60)
    if minutes < 60:
        return f"{minutes} min"
    return f"{minutes // 60} h {minutes % 60:02d} min"

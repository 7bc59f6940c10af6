"""One progress bar over every stage of a bench run: how much of the run's work is done,
the stage running now, and an estimate of the time left.

Each stage has an expected cost in seconds (:func:`expected_cost`): the env steps its
profile budgets for it (episodes × horizon, RS-GAIL's candidates, a baseline's steps, BC's
epochs over its demonstrations, the study's workpieces) times what a step of that kind of
work took on 2 cores (:data:`STEP_SECONDS`, from an idle quick bench's stage times),
plus a fixed start-up cost. The bar's fraction is the expected cost of the
finished stages (cached ones included) over that of all of them.

The time left (:func:`estimate_remaining`) is learnt from this machine: each stage will
take its expected cost times a speed factor, measured over expected time of the finished
stages like it (:func:`speed_factors`: its other seeds, its class, a typical class),
those of this run and those cached by an earlier run on this machine, the recent ones
weighing more (the machine's load changes); the stages left are then laid out
as the executor runs them, ``workers`` at a time, the costliest chain first
(:func:`schedule_length`), so that the estimate is at least the longest chain left and at
least the work left over the workers. Until enough has finished to tell the machine's
speed the bar says "estimating". Every estimate at a stage's start and end goes to a log
(``progress.jsonl`` in the bench's folder).
"""

from __future__ import annotations

import functools
import heapq
import json
import math
import threading
import time
from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tqdm import tqdm

from tolins.bench.jobs import robustness, row_evaluation, study
from tolins.bench.jobs.robustness import PREFIX as ROBUST
from tolins.bench.jobs.trajectories import NAME as TRAJECTORIES
from tolins.bench.jobs.trajectories import POINTS as TRAJECTORY_EPISODES
from tolins.bench.pipeline import settings
from tolins.bench.pipeline.executor import chain_costs
from tolins.bench.pipeline.profiles import Profile
from tolins.bench.table.delicate import DELICATE
from tolins.bench.table.robot import ROBOT
from tolins.bench.table.robustness import ROBUSTNESS, ConditionTable
from tolins.bench.table.rows import ALL_ROWS, SB3_METHODS, TRAININGS, unseeded
from tolins.paper import HORIZON

#: The kinds of stages, in the order a run meets them.
KINDS = ("demonstrations", "training", "evaluation", "robustness", "robot", "delicate", "study")
#: The kinds of stage that evaluate a table's policies under its conditions, and the table.
TABLES: dict[str, ConditionTable] = {
    "robustness": ROBUSTNESS,
    "robot": ROBOT,
    "delicate": DELICATE,
}
#: Seconds per budgeted env step (per BC sample and epoch, per study workpiece) of each
#: kind of work on the MuJoCo backend's ``-v2`` physics, two stages side by side on 2
#: cores: the quick bench of an idle fresh clone (2026-12-04, 7.7 min; benchmarks/README.md,
#: "``tolins bench`` wall time"), each kind's measured stage time over its budget, the
#: kinds' relative costs checked against ``reference:quick``'s run (2026-12-03) and quick
#: benches on a 2-core Zen 4 VM (2026-12-07; benchmarks/README.md, "How well the progress
#: bar foresees the time left"): the Panda's with its compiled law from the idle one, the
#: delicate table's as 1.01 times the robustness episodes' step, their ratio in an idle
#: fresh clone with free flight holding the pins (2026-12-07, ``239cf6c``; 3.18 and 3.14
#: ms there); the deep-RL baselines' from the ``-v2`` paper run's
#: trainings (PPO 280 s and SAC 1,440 s for 288,000 env steps, two side by side).
STEP_SECONDS = {
    "demo-rollout": 0.65e-3,  # a demonstration episode's step
    "eval-rollout": 0.4e-3,  # an evaluation episode's step
    "robust-rollout": 1.95e-3,  # a robustness episode's (finer grades step finer)
    "delicate-rollout": 1.97e-3,  # ... with pins that bend
    "panda-rollout": 4.5e-3,  # a step of the Panda's table (its law compiled)
    "rs-gail-safe": 0.6e-3,  # π_n imitating the safe expert
    "rs-gail-efficient": 2.1e-3,  # ... the efficient one: its failing candidates in contact
    "tolerance-guided": 0.41e-3,
    "ppo": 0.97e-3,  # on 8 envs in one batch
    "sac": 5.0e-3,
    "bc": 1.9e-6,  # per demonstration step and epoch
    "study": 0.14,  # per workpiece, MuJoCo contact outcomes
    "study-model": 0.01,  # per workpiece, the tolerance model's outcomes (kinematic)
}
#: An inference-wrapped policy (π_φ*) costs this many times its policy's episodes: in a
#: table's episodes, where it re-plans on a blocked attempt; on the Panda, whose step
#: costs more than the goal searches; on the bent-pin 2*1 of row C4.2, which blocks
#: attempt after attempt.
INFERENCE_FACTORS = {"table": 3.0, "robot": 2.0, "evaluation": 9.0}
#: A step of the kinematic backend costs this fraction of MuJoCo's.
KINEMATIC_FACTOR = 0.4
#: What a stage costs besides its budget (imports, setup, files).
STAGE_SECONDS = 0.5
#: What the inference study costs besides its workpieces (starting its processes).
STUDY_SECONDS = 5.0
#: The processes the study ran on where its cost per workpiece was measured (the local
#: executor's; a Ray task runs it on one).
STUDY_WORKERS = 2
#: The expected cost (s) the finished stages must hold before the time left is estimated.
MIN_SEEN_S = 10.0
#: The share of a group's (a class's) expected cost that its finished stages must hold to
#: weigh as much as the speed of the broader one it is pulled towards.
PRIOR_SHARE = 0.25
#: ... but at most this many of its stages' expected cost.
PRIOR_STAGES = 2.0
#: A finished stage's evidence of the machine's speed halves every this many seconds...
HALF_LIFE_S = 120.0
#: ... or this share of the run so far, whichever is longer.
HALF_LIFE_SHARE = 0.1
#: A running stage past its estimate is taken to need this share of the time it has run.
OVERRUN_SHARE = 0.1


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
    if name.startswith(DELICATE.prefix):
        return "delicate"
    return "study" if name == study.NAME else "training"


def expected_cost(
    name: str, profile: Profile, backend: str, study_workers: int = STUDY_WORKERS
) -> float:
    """The expected wall time (s) of the stage ``name`` under ``profile`` on ``backend``
    (a name the bench does not make costs :data:`STAGE_SECONDS`), the study on
    ``study_workers`` processes."""
    steps, per_step = _budget(name, stage_kind(name), profile, backend)
    if per_step == "study":
        steps *= STUDY_WORKERS / study_workers
        if backend == "kinematic":
            per_step = "study-model"
    elif per_step != "bc" and backend == "kinematic":
        steps *= KINEMATIC_FACTOR
    fixed = STUDY_SECONDS if per_step.startswith("study") else STAGE_SECONDS
    return fixed + steps * STEP_SECONDS.get(per_step, 0.0)


def _budget(name: str, kind: str, profile: Profile, backend: str) -> tuple[float, str]:
    """The budgeted work of the stage ``name`` of ``kind`` and its unit of cost."""
    base = unseeded(name)
    if kind == "demonstrations":
        return profile.demonstrations * HORIZON, "demo-rollout"
    if kind == "study":
        return settings.study_settings(profile, backend).workpieces, "study"
    if kind == "evaluation" and name == TRAJECTORIES:
        return (TRAJECTORY_EPISODES + 1) * HORIZON, "eval-rollout"
    factor = 1.0
    if _with_inference(name, kind):
        factor = INFERENCE_FACTORS.get(kind, INFERENCE_FACTORS["table"])
    if kind == "evaluation":
        return profile.eval_episodes * HORIZON * factor, "eval-rollout"
    if kind in TABLES:
        table = TABLES[kind]
        episodes = profile.robustness_episodes * len(table.conditions)
        unit = {"robot": "panda-rollout", "delicate": "delicate-rollout"}.get(
            kind, "robust-rollout"
        )
        return episodes * HORIZON * factor, unit
    training = TRAININGS.get(base)
    if training is None:
        return 0.0, "eval-rollout"
    envs = len(training.env_ids)
    if training.method in SB3_METHODS:
        return profile.deep_rl_env_steps, training.method
    if training.method == "bc":
        return profile.bc_epochs * profile.demonstrations * envs * HORIZON, "bc"
    if training.method == "tolerance-guided":
        steps = profile.residual_iterations * profile.iteration_episodes * HORIZON * envs
        return steps, training.method
    return profile.rs_gail_env_steps * envs, f"{training.method}-{training.expert}"


@functools.cache
def speed_class(name: str) -> str:
    """The class of stages whose speed on a machine goes together: the kind of stage
    (:func:`stage_kind`), a training's by its method (RS-GAIL, BC, PPO, ...), an
    evaluation's by whether its policy runs inference (π_φ*)."""
    kind = stage_kind(name)
    training = TRAININGS.get(unseeded(name)) if kind == "training" else None
    if training is not None:
        return f"training {training.method}"
    return f"{kind} with inference" if _with_inference(name, kind) else kind


def speed_factors(
    expected: Mapping[str, float],
    walls: Mapping[str, float],
    ages: Mapping[str, float] | None = None,
) -> Callable[[str], float] | None:
    """How many times its expected cost each stage will take, learnt from the finished
    stages' measured ``walls`` (s, by name; ``expected``: every stage's expected cost).

    A stage's factor is the measured over expected time of the finished stages of its
    group (its other seeds), pulled towards that of its class (:func:`speed_class`), as
    if :data:`PRIOR_SHARE` of the group's expected cost (at most :data:`PRIOR_STAGES` of
    its stages) had run at the class's speed; the class's is pulled towards that of a
    typical class (:func:`_typical`) in the same way. A finished stage weighs half as much
    for every :data:`HALF_LIFE_S`, or :data:`HALF_LIFE_SHARE` of the oldest of its
    ``ages`` (s since each ended), whichever is longer, that has passed since it ended:
    the factors follow the machine as its load changes. ``None`` while the finished
    stages hold less than :data:`MIN_SEEN_S` seconds of expected cost: too little to tell
    this machine's speed.
    """
    planned: dict[str, list[float]] = {}
    for name, cost in expected.items():
        for level in _levels(name):
            total = planned.setdefault(level, [0.0, 0.0])
            total[0] += cost
            total[1] += 1
    seen = sum(expected.get(name, 0.0) for name in walls)
    if seen < MIN_SEEN_S:
        return None
    ages = ages or {}
    life = max(HALF_LIFE_S, HALF_LIFE_SHARE * max(ages.values(), default=0.0))
    sums: dict[str, list[float]] = {}
    for name, wall in walls.items():
        if expected.get(name, 0.0) > 0:
            weight = 0.5 ** (ages.get(name, 0.0) / life)
            for level in _levels(name):
                total = sums.setdefault(level, [0.0, 0.0])
                total[0] += weight * wall
                total[1] += weight * expected[name]
    overall = _typical(
        [(wall, cost) for level, (wall, cost) in sums.items() if level.startswith("class ")]
    )

    def factor(name: str) -> float:
        value = overall
        for level in _levels(name):
            wall, cost = sums.get(level, (0.0, 0.0))
            cost_all, count = planned.get(level, (0.0, 1))
            prior = cost_all * min(PRIOR_SHARE, PRIOR_STAGES / count)
            value = (wall + prior * value) / (cost + prior) if cost + prior > 0 else value
        return value

    return factor


def _typical(classes: list[tuple[float, float]]) -> float:
    """The speed factor of a typical class of stages: the geometric mean of the classes'
    measured over expected times (``(wall, cost)`` each), a class weighing less the less
    of its expected cost has finished (half at :data:`MIN_SEEN_S`), so that the costliest
    kind of work does not set the speed of every other."""
    weights = [cost / (cost + MIN_SEEN_S) for _, cost in classes]
    logs = [math.log(max(wall, 1e-9) / cost) for wall, cost in classes]
    return math.exp(sum(w * x for w, x in zip(weights, logs, strict=True)) / sum(weights))


def _levels(name: str) -> tuple[str, str]:
    """The class and the group of the stage ``name``, from broad to narrow."""
    return f"class {speed_class(name)}", f"group {unseeded(name)}"


def estimate_remaining(
    todo: Mapping[str, Sequence[str]],
    expected: Mapping[str, float],
    walls: Mapping[str, float],
    running: Mapping[str, float],
    workers: int,
    ages: Mapping[str, float] | None = None,
) -> float | None:
    """The wall time (s) until every stage of ``todo`` has finished; ``None`` while too
    little has finished to tell (:func:`speed_factors`).

    Args:
        todo: The stages not finished, each with the stages it needs (a stage after those
            it needs; names outside ``todo`` have finished).
        expected: Every stage's expected cost (s, :func:`expected_cost`), finished or not.
        walls: The measured wall time (s) of finished stages that ran on this machine.
        running: The stages of ``todo`` running now, each with the time (s) it has run.
        workers: How many stages run at once.
        ages: How long ago (s) each stage of ``walls`` ended (:func:`speed_factors`);
            ``None``: all just now.

    Each stage of ``todo`` takes its expected cost times its factor, less the time it has
    run (one that has run longer than that: :data:`OVERRUN_SHARE` of the time it has run
    more); they are then laid out as the executor runs them (:func:`schedule_length`).
    """
    if not todo:
        return 0.0
    factor = speed_factors(expected, walls, ages)
    if factor is None:
        return None
    left = {}
    for name in todo:
        cost, ran = expected.get(name, STAGE_SECONDS) * factor(name), running.get(name)
        if ran is None:
            left[name] = cost
        else:
            left[name] = cost - ran if ran < cost else OVERRUN_SHARE * ran
    return schedule_length(todo, left, expected, set(running), workers)


def schedule_length(
    todo: Mapping[str, Sequence[str]],
    left: Mapping[str, float],
    expected: Mapping[str, float],
    running: Collection[str],
    workers: int,
) -> float:
    """When the last stage of ``todo`` ends (s from now) if each takes ``left`` and they
    run as the executors run them: ``running`` ones now, then, as ``workers`` come free, the
    ready stage with the costliest chain behind it by ``expected`` cost first
    (:func:`~tolins.bench.pipeline.executor.chain_costs`, the executor's order)."""
    priority = chain_costs(todo, expected)
    order = {name: i for i, name in enumerate(todo)}
    waiting = {name: {d for d in deps if d in todo} for name, deps in todo.items()}
    needed_by: dict[str, list[str]] = {name: [] for name in todo}
    for name, deps in waiting.items():
        for dep in deps:
            needed_by[dep].append(name)
    ready = [(-priority[n], order[n], n) for n, w in waiting.items() if not w and n not in running]
    heapq.heapify(ready)
    ends = [(left[name], name) for name in running]
    heapq.heapify(ends)
    now = 0.0
    while ready or ends:
        while ready and len(ends) < workers:
            name = heapq.heappop(ready)[2]
            heapq.heappush(ends, (now + left[name], name))
        now, name = heapq.heappop(ends)
        for later in needed_by[name]:
            waiting[later].discard(name)
            if not waiting[later]:
                heapq.heappush(ready, (-priority[later], order[later], later))
    return now


def _with_inference(name: str, kind: str) -> bool:
    """Whether the evaluation (robustness, Panda) stage ``name`` runs an inference-wrapped
    policy (π_φ*)."""
    base = unseeded(name)
    if kind == "evaluation":
        rows = (row for row in ALL_ROWS if unseeded(row_evaluation.stage_name(row, 0)) == base)
        return any(row.inference for row in rows)
    if kind in TABLES:
        table = TABLES[kind]
        names = ((p, unseeded(robustness.stage_name(p, 0, table))) for p in table.policies)
        return any(policy.inference for policy, stage in names if stage == base)
    return False


@dataclass
class _Stage:
    """What is known of one stage: expected cost, when it started (this progress's
    clock) and its measured wall time once finished."""

    kind: str
    expected: float
    done: bool = False
    started: float | None = None
    wall_s: float | None = None


class BenchProgress:
    """The progress of a bench run's stages, shown as one tqdm bar, and logged to a file.

    Args:
        expected: Every stage of the run: name -> expected cost (s, :func:`expected_cost`).
        done: The stages finished before (cached).
        needs: The stages to run, each with the stages it needs (in the order planned);
            ``None``: every stage not ``done``, needing none.
        walls: The measured wall time (s) of ``done`` stages that ran on this machine
            (their markers say so): they tell its speed before a stage of this run ends.
        workers: How many stages run at once (the executor's workers, a cluster's CPUs).
        log: A file to write a JSON line to at the start and at every stage's start and
            end: the time since the start (``t``, s), the event, the stage, how many
            stages have finished, and the estimate of the time left (``remaining_s``;
            ``null`` while estimating).
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
        needs: Mapping[str, Sequence[str]] | None = None,
        walls: Mapping[str, float] | None = None,
        workers: int = 1,
        log: str | Path | None = None,
        show: bool = True,
        clock: Callable[[], float] = time.monotonic,
        refresh_s: float | None = 2.0,
    ) -> None:
        self._stages = {
            name: _Stage(stage_kind(name), float(cost), name in done)
            for name, cost in expected.items()
        }
        self._expected = {name: stage.expected for name, stage in self._stages.items()}
        if needs is None:
            needs = {name: () for name, stage in self._stages.items() if not stage.done}
        self._needs = {name: tuple(deps) for name, deps in needs.items()}
        self._walls = {name: float(wall) for name, wall in (walls or {}).items()}
        self._workers = workers
        self._total = sum(self._expected.values())
        self._clock = clock
        self._began = clock()
        self._ended = dict.fromkeys(self._walls, self._began)  # cached: at the run's start
        self._lock = threading.RLock()
        self._log = None if log is None else open(log, "w", encoding="utf-8")  # noqa: SIM115
        self._bar: Any = None
        self._stop = threading.Event()
        self._event("begin", None)
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
            self._event("start", name)
            self._draw()

    def finish(self, name: str, wall_s: float) -> None:
        """Stage ``name`` has finished, having taken ``wall_s`` seconds."""
        with self._lock:
            stage = self._stages[name]
            stage.done, stage.wall_s = True, float(wall_s)
            self._walls[name] = stage.wall_s
            self._ended[name] = self._clock()
            self._event("finish", name)
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

    def remaining_s(self) -> float | None:
        """The estimated wall time (s) until every stage has finished
        (:func:`estimate_remaining`); ``None`` while too little has finished to tell."""
        with self._lock:
            now = self._clock()
            todo = {n: d for n, d in self._needs.items() if not self._stages[n].done}
            running = {
                name: now - stage.started
                for name, stage in self._stages.items()
                if _running(stage) and stage.started is not None
            }
            ages = {name: now - ended for name, ended in self._ended.items()}
            return estimate_remaining(
                todo, self._expected, self._walls, running, self._workers, ages
            )

    def close(self) -> None:
        """Stop redrawing and leave the bar as it is; close the log."""
        self._stop.set()
        with self._lock:
            if self._bar is not None:
                self._bar.close()
                self._bar = None
            if self._log is not None:
                self._log.close()
                self._log = None

    def _event(self, event: str, name: str | None) -> None:
        """A line of the log (if any) for ``event`` of stage ``name``."""
        if self._log is None:
            return
        line = {"t": self._clock() - self._began, "event": event, "stage": name}
        line |= {"finished": self.finished, "total": self.total}
        line["remaining_s"] = self.remaining_s()
        self._log.write(json.dumps(line) + "\n")
        self._log.flush()

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
            left = self.remaining_s()
            parts.append(
                "estimating the time left"
                if left is None
                else f"about {format_duration(left)} left"
            )
        self._bar.n = self.fraction * self._bar.total
        self._bar.set_postfix_str(", ".join(parts), refresh=True)


def _running(stage: _Stage) -> bool:
    return stage.started is not None and not stage.done


def format_duration(seconds: float) -> str:
    """``seconds`` as ``45 s``, ``12 min`` or ``1 h 05 min``."""
    if seconds < 60:
        return f"{seconds:.0f} s"
    minutes = round(seconds / 60)
    if minutes < 60:
        return f"{minutes} min"
    return f"{minutes // 60} h {minutes % 60:02d} min"

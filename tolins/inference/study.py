"""The paper's numerical study of probabilistic inference on a bent-pin 2*1 socket.

Workpieces: ``CircularSocket(2, 1, row_pitch=5.0)`` (pins 0.3 mm, holes 0.5 mm) with every
pin offset by ``N(0, SIGMA² I)``. Control and measurement are perfect: attempt ``j`` at goal
``s̄_j`` inserts iff ``s̄_j ∈ T(ε)``. Each method gets up to ``max_attempts`` attempts:

* ``inference``: the nominal goal, then CMA-ES on ``g_{m+1}`` (:func:`.goal.next_goal`).
* ``inference_blocked``: the same with the failed attempts' blocked pins (a pin is blocked
  iff it is outside its hole at the goal) in the likelihood.
* ``inference_contact``: the blocked pins and where each touched the board: the bearing of
  its touch point from its hole's centre (the direction of the pin's gap ``gap``, exact in
  the tolerance model; MuJoCo's touch points with ``physics``).
* ``random``: the nominal goal, then goals drawn without replacement from :data:`RANDOM_GOALS`.
* ``nominal``: the nominal goal only.
* ``oracle``: the centre goal of the true workpiece (:func:`.goal.centre_goals`).

Per defect kind (``StudyConfig.kinds``): besides these bent workpieces,
``kind_samples`` workpieces per kind that are bent *and* have a pitch error, burrs or a
blocked hole (:func:`kind_workpieces`); their inference methods use the defect model
(:data:`DEFECT_MODEL`) and stop when it says not insertable
(:meth:`StudyResult.kind_summary`).
"""

from __future__ import annotations

import dataclasses
import itertools
import multiprocessing
import multiprocessing.pool
from collections.abc import Callable, Generator, Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

from tolins.geometry.defects import sample_defects
from tolins.geometry.delicate import DEFAULT_MATERIAL, ElasticPins, bent_beyond, check_pins
from tolins.geometry.specs import CircularSocket
from tolins.geometry.tolerance import gaps_inside, pin_gaps, pins_inside
from tolins.geometry.validation import check_seed
from tolins.inference.goal import DISCARD_THRESHOLD, centre_goals, next_goal
from tolins.inference.history import History
from tolins.inference.posterior import DefectModel
from tolins.names import comma_separated
from tolins.stopping import wait_unless_stopped

#: The study's socket: 2*1, pins 0.3 mm, holes 0.5 mm, 5 mm apart.
SOCKET = CircularSocket(2, 1, pin_radius=0.3, hole_radius=0.5, row_pitch=5.0)
#: Defect std per pin and axis (mm): 60.9 % insert at the nominal goal, 1.4 % nowhere
#: (400,000 draws). No isotropic sigma gives the paper's 60 % and 0.8 % together
#: (0.105 mm: 70 % and 0.7 %); the nominal fraction was matched.
SIGMA = 0.115
#: The methods; a method's random stream is keyed by its place here, so new ones go last.
METHODS = ("inference", "inference_contact", "random", "nominal", "oracle", "inference_blocked")
#: The evidence each inference method records: (blocked pins, touch bearings).
EVIDENCE = {
    "inference": (False, False),
    "inference_blocked": (True, False),
    "inference_contact": (True, True),
}
#: The random baseline's predefined goals: x, y in {-0.15, 0, 0.15} mm, theta in
#: {-0.04, 0, 0.04} rad (0.1 mm at the pins), nominal first.
RANDOM_GOALS = np.array(
    sorted(
        itertools.product((-0.15, 0.0, 0.15), (-0.15, 0.0, 0.15), (-0.04, 0.0, 0.04)),
        key=lambda g: np.abs(g).sum(),
    )
)
#: The defect kinds of the per-kind study (:data:`~tolins.geometry.defects.DEFECT_KINDS`
#: less ``short``: a short pin meets the board later but its tolerance is a full pin's, so
#: it changes no outcome of the tolerance model). ``bent`` is the main study's workpieces
#: and methods; every other kind's workpieces are bent (``SIGMA``) *and* have that defect,
#: and its inference methods use the defect model (:data:`DEFECT_MODEL`).
STUDY_KINDS = ("bent", "pitch", "burr", "blocked")
#: The defect scales of the per-kind workpieces (:func:`~tolins.geometry.sample_defects`):
#: row/col pitch ``1 + N(0, 0.02²)`` (±0.05 mm at the pins), burrs ``|N(0, 0.08²)|`` mm
#: per pin (clearance 0.2 mm), one blocked hole.
KIND_SIGMAS = {"pitch": 0.02, "burr": 0.08, "blocked": None}
#: The prior of the per-kind inference: bends, pitch error, burrs and a blocked hole.
DEFECT_MODEL = DefectModel(SIGMA, pitch_sigma=0.02, burr_sigma=0.08, blocked_prior=0.1)
#: With pins that bend, the runs simulated side by side, each in a simulation (a model
#: copy and its data) of its own.
PART_SLOTS = 192
#: Paper's figures: fraction inserted within 10 attempts, mean attempts of those.
PAPER = {"inference": (0.902, 1.836), "random": (0.782, 2.796)}


@dataclass(frozen=True)
class StudyConfig:
    """Settings of :func:`run_study`.

    Attributes:
        samples: Workpieces.
        seed: Seed of the defects and of every method's draws.
        max_attempts: Attempts per workpiece and method.
        particles: Posterior samples per goal query.
        workers: Processes, each running its share of the workpieces (the result does
            not depend on it).
        methods: Methods to run, from :data:`METHODS`.
        physics: Outcomes, blocked pins and touch bearings from MuJoCo contact physics
            (:func:`.physics.physics_attempt`, batched: :class:`.physics.AttemptBatch`)
            instead of the tolerance model.
        discard_below: The inference methods give up on a workpiece (the paper's discard)
            when the best expected success ``g_{m+1}`` falls below this; 0: never.
        kinds: Defect kinds reported separately (:data:`STUDY_KINDS`); ``bent`` is the
            main study, each other kind adds ``kind_samples`` workpieces of its own.
        kind_samples: Workpieces per kind other than ``bent``.
        not_insertable_below: The defect model's inference stops and reports a workpiece
            not insertable when its best expected success falls below this.
        pins: ``"elastic-plastic"``: the workpieces' pins bend and stay bent (``physics``
            only, the bent workpieces only: ``kinds`` at most ``("bent",)``), and each
            method's attempts on a workpiece meet the part as its earlier attempts left
            it; ``"rigid"`` (default).
        pin_material: The bending pins' material
            (:data:`~tolins.geometry.materials.MATERIALS`).
    """

    samples: int = 500
    seed: int = 0
    max_attempts: int = 10
    particles: int = 1000
    workers: int = 2
    methods: tuple[str, ...] = METHODS
    discard_below: float = 0.0
    physics: bool = False
    kinds: tuple[str, ...] = STUDY_KINDS
    kind_samples: int = 12
    not_insertable_below: float = DISCARD_THRESHOLD
    pins: str = "rigid"
    pin_material: str = DEFAULT_MATERIAL

    def __post_init__(self) -> None:
        for name, least in (("samples", 1), ("max_attempts", 1), ("particles", 2), ("workers", 1)):
            if getattr(self, name) < least:
                raise ValueError(f"{name}={getattr(self, name)!r}; allowed: ≥ {least}")
        check_seed("seed", self.seed)
        if not 0.0 <= self.discard_below < 1.0:
            raise ValueError(f"discard_below={self.discard_below!r}; allowed: 0 ≤ value < 1")
        unknown = set(self.methods) - set(METHODS)
        if unknown or not self.methods:
            raise ValueError(f"methods={self.methods!r}; allowed: a subset of {METHODS}")
        if set(self.kinds) - set(STUDY_KINDS):
            raise ValueError(f"kinds={self.kinds!r}; allowed: a subset of {STUDY_KINDS}")
        if self.kind_samples < 1:
            raise ValueError(f"kind_samples={self.kind_samples!r}; allowed: ≥ 1")
        if not 0.0 <= self.not_insertable_below < 1.0:
            raise ValueError(
                f"not_insertable_below={self.not_insertable_below!r}; allowed: 0 ≤ value < 1"
            )
        if self.elastic_pins() is not None:
            if not self.physics:
                raise ValueError(
                    "pins='elastic-plastic' bends pins in the physics; allowed: physics=True, "
                    "or pins='rigid'"
                )
            if set(self.kinds) - {"bent"}:
                raise ValueError(
                    f"kinds={self.kinds!r} with pins='elastic-plastic'; allowed: () or ('bent',)"
                )

    @property
    def workpieces(self) -> int:
        """Workpieces the study runs: ``samples`` bent ones, and ``kind_samples`` of each
        other kind of ``kinds``."""
        return self.samples + self.kind_samples * sum(kind != "bent" for kind in self.kinds)

    def elastic_pins(self) -> ElasticPins | None:
        """The workpieces' bending pins (damaged beyond half the radial clearance), or
        ``None`` for rigid ones."""
        material = None if self.pins == "rigid" else self.pin_material
        return check_pins(SOCKET, self.pins, material, None)


def parse_methods(text: str) -> tuple[str, ...]:
    """The methods named by ``tolins infer-study --methods TEXT``: comma-separated names
    of :data:`METHODS`, each at most once, at least one (:func:`tolins.names.comma_separated`)."""
    return comma_separated(text, METHODS, option="--methods")


@dataclass(frozen=True)
class StudyResult:
    """Per-workpiece outcomes: ``attempts[method][k]`` = attempt that inserted, 0 if none;
    ``damaged[method][k]``: the part was bent beyond the damage threshold when the method
    was done with it (pins that bend only).

    ``kinds[kind]`` (each kind but ``bent``): ``{"attempts": {method: (K,)}, "not_insertable":
    {method: (K,) bool}, "insertable": (K,) bool}`` of that kind's workpieces.
    """

    config: StudyConfig
    nominal_insertable: float
    impossible: float
    attempts: dict[str, np.ndarray]
    kinds: dict[str, dict] = dataclasses.field(default_factory=dict)
    damaged: dict[str, np.ndarray] = dataclasses.field(default_factory=dict)

    def summary(self, method: str) -> dict[str, float]:
        """``success_within_10`` (of all workpieces) and ``mean_attempts`` of inserted ones;
        with pins that bend ``damaged`` (the share of parts left damaged) and
        ``success_undamaged`` (inserted within 10 and not damaged)."""
        a = self.attempts[method]
        done = a[a > 0]
        mean = float(done.mean()) if len(done) else 0.0
        figures = {"success_within_10": float(len(done) / len(a)), "mean_attempts": mean}
        if self.config.pins != "rigid":
            damaged = self.damaged[method]
            figures["damaged"] = float(damaged.mean())
            figures["success_undamaged"] = float(np.mean((a > 0) & ~damaged))
        return figures

    def kind_summary(self, kind: str) -> dict:
        """Per method on the ``kind`` workpieces: ``success_within_10``, ``mean_attempts``,
        ``not_insertable`` (share reported not insertable) and the kind's ``workpieces``
        and ``impossible`` share. ``bent``: the main study (never reported not insertable)."""
        if kind == "bent":
            methods = {m: {**self.summary(m), "not_insertable": 0.0} for m in self.config.methods}
            return {
                "workpieces": self.config.samples,
                "impossible": self.impossible,
                "methods": methods,
            }
        runs = self.kinds[kind]
        methods = {}
        for m in self.config.methods:
            a = runs["attempts"][m]
            done = a[a > 0]
            methods[m] = {
                "success_within_10": float(len(done) / len(a)),
                "mean_attempts": float(done.mean()) if len(done) else 0.0,
                "not_insertable": float(np.mean(runs["not_insertable"][m])),
            }
        insertable = runs["insertable"]
        return {
            "workpieces": len(insertable),
            "impossible": float(1 - insertable.mean()),
            "methods": methods,
        }

    def to_json(self) -> dict:
        """The issue's schema; ``kinds``: :meth:`kind_summary` of each kind."""
        summary = {
            "nominal_insertable": self.nominal_insertable,
            "impossible": self.impossible,
            "methods": {m: self.summary(m) for m in self.config.methods},
        }
        if self.config.pins != "rigid":
            summary["pins"] = {"model": self.config.pins, "material": self.config.pin_material}
        if self.config.kinds:
            summary["kinds"] = {k: self.kind_summary(k) for k in self.config.kinds}
        return summary


def draw_workpieces(samples: int, seed: int) -> np.ndarray:
    """Pin offsets ``(samples, 2, 2)`` of the study's workpieces."""
    rng = np.random.default_rng([seed, 0])
    return rng.normal(0.0, SIGMA, size=(samples, SOCKET.n_pins, 2))


def run_study(
    config: StudyConfig, on_workpiece: Callable[[int], None] | None = None
) -> StudyResult:
    """Run every method on every workpiece (``on_workpiece(k)`` after each), the workpieces
    split into ``config.workers`` chunks run in processes. With ``physics`` a chunk's
    methods run in lockstep: every pending attempt of every workpiece is one downward push
    in a :class:`~tolins.inference.physics.AttemptBatch`."""
    offsets = draw_workpieces(config.samples, config.seed)
    chunks = np.array_split(np.arange(config.samples), min(config.workers, config.samples))
    jobs = [(config, chunk, offsets[chunk]) for chunk in chunks]
    kinds = [kind for kind in config.kinds if kind != "bent"]
    pieces = {kind: kind_workpieces(kind, config.kind_samples, config.seed) for kind in kinds}
    kind_jobs = [
        (config, kind, part, pieces[kind][part[0] : part[-1] + 1])
        for kind in kinds
        for part in np.array_split(np.arange(config.kind_samples), config.workers)
        if len(part)
    ]
    rows, kind_rows = [], {kind: [] for kind in kinds}
    pool = None
    if config.workers == 1:
        done, kind_done = map(_chunk, jobs), map(_kind_chunk, kind_jobs)
    else:
        # Spawned: a bench runs the study on a thread beside others, and forking a process
        # with threads running is unsafe.
        pool = multiprocessing.get_context("spawn").Pool(config.workers)
        done, kind_done = (
            _results(pool.imap(_chunk, jobs)),
            _results(pool.imap(_kind_chunk, kind_jobs)),
        )
    try:
        for chunk_rows in done:
            for row in chunk_rows:
                rows.append(row)
                if on_workpiece:
                    on_workpiece(len(rows) - 1)
        for (_, kind, _, _), chunk_rows in zip(kind_jobs, kind_done, strict=True):
            kind_rows[kind] += chunk_rows
    finally:
        if pool is not None:  # idle when all went well; else its chunks left are ended
            pool.terminate()
            pool.join()
    inside = pins_inside(SOCKET, offsets, np.zeros(3)).all(-1)
    possible = pins_inside(SOCKET, offsets, centre_goals(SOCKET, offsets)).all(-1)
    attempts = {m: np.array([row[m][0] for row in rows]) for m in config.methods}
    damaged = {m: np.array([row[m][1] for row in rows]) for m in config.methods}
    by_kind = {
        kind: {
            "attempts": {m: np.array([r[m][0] for r in kind_rows[kind]]) for m in config.methods},
            "not_insertable": {
                m: np.array([r[m][1] for r in kind_rows[kind]]) for m in config.methods
            },
            "insertable": np.array([insertable(spec) for spec in pieces[kind]]),
        }
        for kind in kinds
    }
    return StudyResult(
        config, float(inside.mean()), float(1 - possible.mean()), attempts, by_kind, damaged
    )


def _results(results: multiprocessing.pool.IMapIterator) -> Iterator[Any]:
    """The results of a pool's ``imap`` in order, raising
    :class:`~tolins.stopping.Stopped` while waiting once a stop is requested."""
    while True:
        try:
            yield wait_unless_stopped(results.next)
        except StopIteration:
            return


def kind_workpieces(kind: str, samples: int, seed: int) -> list[CircularSocket]:
    """The per-kind study's workpieces: bent pins (``SIGMA``) and a ``kind`` defect
    (:data:`KIND_SIGMAS`), from their own stream ``[seed, 1, kind]``."""
    rng = np.random.default_rng([seed, 1, STUDY_KINDS.index(kind)])
    return [
        sample_defects(sample_defects(SOCKET, SIGMA, rng), KIND_SIGMAS[kind], rng, kind=kind)
        for _ in range(samples)
    ]


def insertable(spec: CircularSocket) -> bool:
    """Whether some goal inserts workpiece ``spec``: :func:`insertion_margin` ``≥ 0``."""
    return insertion_margin(spec) >= 0


def insertion_margin(spec: CircularSocket) -> float:
    """The largest ``min_i(c_i - |gap_i|)`` over poses (mm; ``-inf`` for a blocked hole):
    Nelder-Mead from the centre goal, which is the deepest pose when the clearances are
    equal. ``≥ 0``: some goal inserts the workpiece."""
    from scipy.optimize import minimize

    if spec.blocked_holes:
        return -np.inf
    start = centre_goals(spec, (spec.pin_centers - spec.hole_centers)[None])[0]
    scale = np.array([1.0, 1.0, max(float(np.max(np.hypot(*spec.hole_centers.T))), 1.0)])

    def excess(x: np.ndarray) -> float:
        gaps = pin_gaps(spec, spec.offsets, x / scale)
        return float(np.max(np.hypot(gaps[:, 0], gaps[:, 1]) - spec.pin_clearances))

    options = {"xatol": 1e-9, "fatol": 1e-12}
    best = minimize(excess, start * scale, method="Nelder-Mead", options=options)
    return -min(float(best.fun), excess(start * scale))


#: An attempt at a goal: which pins are in their holes, and each blocked pin's bearing
#: (rad, NaN for the pins inside).
Outcome = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]
#: A method's run on one workpiece: yields each goal, is sent the attempt's ``Outcome``
#: result, returns the attempt (1-based) that inserted, 0 if none.
Attempts = Generator[np.ndarray, tuple[np.ndarray, np.ndarray], int]


def _chunk(job: tuple[StudyConfig, np.ndarray, np.ndarray]) -> list[dict[str, tuple[int, bool]]]:
    """Every method's ``(attempt that inserted, part damaged)`` on each workpiece of a
    chunk (``job``: config, indices, offsets)."""
    config, indices, offsets = job
    runs = {
        (k, m): _attempt_goals(m, eps, config, _method_rng(config.seed, int(index), m))
        for k, (index, eps) in enumerate(zip(indices, offsets, strict=True))
        for m in config.methods
    }
    if config.physics:
        results, damaged = _lockstep_physics(runs, offsets, pins=config.elastic_pins())
    else:
        results = {key: _drive(run, geometry_outcome(offsets[key[0]])) for key, run in runs.items()}
        damaged = dict.fromkeys(runs, False)
    return [
        {m: (results[(k, m)], damaged[(k, m)]) for m in config.methods} for k in range(len(indices))
    ]


def _kind_chunk(job: tuple[StudyConfig, str, np.ndarray, list[CircularSocket]]) -> list[dict]:
    """Every method's ``(attempt, not_insertable)`` on each workpiece of a kind's chunk
    (``job``: config, kind, indices, workpieces)."""
    config, kind, indices, specs = job
    runs = {}
    for (k, spec), index in zip(enumerate(specs), indices, strict=True):
        for m in config.methods:
            rng = np.random.default_rng(
                [config.seed, 1, STUDY_KINDS.index(kind), int(index), METHODS.index(m)]
            )
            eps = spec.pin_centers - spec.hole_centers
            runs[(k, m)] = _defect_attempt_goals(m, eps, config, rng)
    if config.physics:
        results, _ = _lockstep_physics(runs, None, specs)
    else:
        results = {
            key: _drive(run, geometry_outcome(specs[key[0]].offsets, specs[key[0]]))
            for key, run in runs.items()
        }
    return [{m: results[(k, m)] for m in config.methods} for k in range(len(specs))]


def _defect_attempt_goals(
    method: str, eps: np.ndarray, config: StudyConfig, rng: np.random.Generator
) -> Generator[np.ndarray, tuple[np.ndarray, np.ndarray], tuple[int, bool]]:
    """:func:`_attempt_goals` with the defect model (:data:`DEFECT_MODEL`); returns the
    attempt that inserted (0: none) and whether the inference reported it not insertable.
    ``eps``: the workpiece's effective pin offsets (bends and pitch error) for ``oracle``."""
    goals = _fixed_goals(method, eps, config.max_attempts, rng)
    if goals is not None:
        for attempt, goal in enumerate(goals, start=1):
            inside, _ = yield goal
            if inside.all():
                return attempt, False
        return 0, False
    with_blocked, with_bearings = EVIDENCE[method]
    history = History.empty()
    for attempt in range(1, config.max_attempts + 1):
        found = next_goal(
            SOCKET,
            history,
            SIGMA,
            rng,
            n_samples=config.particles,
            threshold=config.discard_below,
            model=DEFECT_MODEL,
            not_insertable_below=config.not_insertable_below,
        )
        if found.not_insertable:
            return 0, True
        if found.discard:
            return 0, False
        inside, bearings = yield found.goal
        if inside.all():
            return attempt, False
        history = history.append(
            found.goal,
            False,
            ~inside if with_blocked else None,
            bearings if with_bearings else None,
        )
    return 0, False


def _drive(run: Attempts, outcome: Outcome) -> int:
    """Run one method's attempts, each answered by ``outcome``."""
    try:
        goal = next(run)
        while True:
            goal = run.send(outcome(goal))
    except StopIteration as stop:
        return stop.value


def _lockstep_physics(
    runs: dict[tuple[int, str], Attempts],
    offsets: np.ndarray | None,
    specs: list[CircularSocket] | None = None,
    pins: ElasticPins | None = None,
) -> tuple[dict, dict]:
    """Advance every run by one attempt per round, all of a round's pushes in one batch
    (workpiece ``k``: ``SOCKET`` with ``offsets[k]``, or ``specs[k]``); each run's result
    and whether it left its part damaged. With ``pins`` that bend every run has a slot of
    its own, where each attempt meets the part as the run's last one left it, and the runs
    go :data:`PART_SLOTS` at a time (a simulation each; the results do not depend on it)."""
    from tolins.inference.physics import AttemptBatch

    if pins is not None and len(runs) > PART_SLOTS:
        keys, results, damaged = list(runs), {}, {}
        for first in range(0, len(keys), PART_SLOTS):
            group = {key: runs[key] for key in keys[first : first + PART_SLOTS]}
            done, bent = _lockstep_physics(group, offsets, specs, pins)
            results.update(done)
            damaged.update(bent)
        return results, damaged
    layout = SOCKET  # a kind's own workpiece layout (a plug, burrs) for ``specs``
    if specs is None:
        specs = [dataclasses.replace(SOCKET, pin_offsets=eps) for eps in offsets]
    else:
        layout = specs[0]
    slots = len(runs) if pins is not None else min(64, len(runs))
    batch = AttemptBatch(layout, slots=slots, num_threads=1, pins=pins)
    slot = {key: i for i, key in enumerate(runs)}
    results, pending, tried = {}, {}, set()
    for key, run in runs.items():
        try:
            pending[key] = next(run)
        except StopIteration as stop:
            results[key] = stop.value
    try:
        while pending:
            keys = list(pending)
            jobs = [(specs[key[0]], pending[key]) for key in keys]
            if pins is None:
                outcomes = batch.attempts(jobs)
            else:
                keep = [key in tried for key in keys]
                outcomes = batch.attempts(jobs, slots=[slot[k] for k in keys], keep_part=keep)
                tried.update(keys)
            for key, (_, blocked, bearings) in zip(keys, outcomes, strict=True):
                try:
                    pending[key] = runs[key].send((~blocked, bearings))
                except StopIteration as stop:
                    results[key] = stop.value
                    del pending[key]
        damaged = {
            key: pins is not None and bent_beyond(batch.bend(slot[key]), pins.damage_threshold)
            for key in runs
        }
    finally:
        batch.close()
    return results, damaged


def _method_rng(seed: int, index: int, method: str) -> np.random.Generator:
    """The draws of ``method`` on workpiece ``index``."""
    return np.random.default_rng([seed, index, METHODS.index(method) + 1])


def geometry_outcome(eps: np.ndarray, spec: CircularSocket = SOCKET) -> Outcome:
    """Which pins are in their holes at a goal, and the bearings, by the tolerance model
    (``spec``: the workpiece's other defects, pitch error, burrs, blocked holes)."""

    def attempt(goal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        gaps = pin_gaps(spec, eps, goal)
        inside = gaps_inside(spec, gaps)
        return inside, np.where(inside, np.nan, np.arctan2(gaps[:, 1], gaps[:, 0]))

    return attempt


def _attempt_goals(
    method: str, eps: np.ndarray, config: StudyConfig, rng: np.random.Generator
) -> Attempts:
    """The attempts of ``method`` on workpiece ``eps`` (:data:`Attempts`)."""
    goals = _fixed_goals(method, eps, config.max_attempts, rng)
    if goals is not None:
        for attempt, goal in enumerate(goals, start=1):
            inside, _ = yield goal
            if inside.all():
                return attempt
        return 0
    with_blocked, with_bearings = EVIDENCE[method]
    history = History.empty()
    for attempt in range(1, config.max_attempts + 1):
        found = next_goal(
            SOCKET, history, SIGMA, rng, n_samples=config.particles, threshold=config.discard_below
        )
        if found.discard:
            return 0
        inside, bearings = yield found.goal
        if inside.all():
            return attempt
        history = history.append(
            found.goal,
            False,
            ~inside if with_blocked else None,
            bearings if with_bearings else None,
        )
    return 0


def _fixed_goals(
    method: str, eps: np.ndarray, max_attempts: int, rng: np.random.Generator
) -> np.ndarray | None:
    """The goals of the methods that do not learn from failures (None for inference)."""
    if method == "nominal":
        return np.zeros((1, 3))
    if method == "oracle":
        return centre_goals(SOCKET, eps)[None]
    if method == "random":
        rest = rng.permutation(np.arange(1, len(RANDOM_GOALS)))[: max_attempts - 1]
        return RANDOM_GOALS[np.concatenate([[0], rest])]
    return None

"""The dm_control suite of tolins: one domain per preset of the task table, task ``insert``."""

from __future__ import annotations

from typing import Any

from dm_control.rl import control
from dm_control.utils import containers

from tolins.dmc.physics import InsertionPhysics
from tolins.dmc.task import Insert
from tolins.envs.task_settings import keywords_of
from tolins.envs.tasks import GYM_TASKS, Task
from tolins.paper import CONTROL_DT

TASK_NAME = "insert"
#: Keywords of :class:`Insert` that the suite sets itself: the domain's socket, and the
#: control period, which is ``environment_kwargs["control_timestep"]`` (dm_control's name).
_SET_BY_THE_SUITE = ("socket", "control_dt")
#: Keywords ``task_kwargs`` may hold: those of :class:`Insert` (its own, then the task's
#: settings) but the ones the suite sets.
TASK_KWARGS = tuple(name for name in keywords_of(Insert) if name not in _SET_BY_THE_SUITE)


def make_environment(
    task: Task,
    task_kwargs: dict[str, Any] | None = None,
    environment_kwargs: dict[str, Any] | None = None,
) -> control.Environment:
    """A ``control.Environment`` of ``task`` (a row of the task table), 0.25 s control steps
    unless ``environment_kwargs["control_timestep"]`` says otherwise (validated by the task's
    settings, as the gym env's ``control_dt``)."""
    task_kwargs = dict(task_kwargs or {})
    unknown = sorted(set(task_kwargs) - set(TASK_KWARGS))
    if unknown:
        raise ValueError(f"task_kwargs {unknown} are unknown; allowed: {list(TASK_KWARGS)}")
    if task.defect_sigma is not None:
        task_kwargs.setdefault("defect_sigma", task.defect_sigma)
    if task.robot != "free":
        task_kwargs.setdefault("robot", task.robot)
    if task.versions is not None:
        task_kwargs.setdefault("physics_version", max(task.physics_versions))
    if task.pins != "rigid":
        task_kwargs.setdefault("pins", task.pins)
    environment_kwargs = {"control_timestep": CONTROL_DT, **(environment_kwargs or {})}
    insert = Insert(task.socket, control_dt=environment_kwargs["control_timestep"], **task_kwargs)
    environment_kwargs["control_timestep"] = insert.settings.control_dt
    settings = insert.settings
    physics = InsertionPhysics.from_spec(
        task.socket, settings.version, settings.robot, settings.elastic
    )
    return control.Environment(physics, insert, **environment_kwargs)


def _domain_suite(task: Task) -> containers.TaggedTasks:
    """A domain's ``TaggedTasks``: its one task ``insert``, tagged with the table's tags."""
    suite = containers.TaggedTasks()

    def insert(environment_kwargs: dict[str, Any] | None = None, **task_kwargs: Any):
        return make_environment(task, task_kwargs, environment_kwargs)

    gym_id = task.gym_id_of(max(task.physics_versions)) if task.versions else task.gym_id
    insert.__doc__ = f"Insert the {task.domain} workpiece (gym id {gym_id})."
    suite.add(*task.tags)(insert)
    return suite


#: Domain name -> its ``TaggedTasks`` (as the modules of ``dm_control.suite`` have ``SUITE``),
#: one per task with gymnasium ids: the presets', then the robot tasks' (``circle2x2_panda``,
#: …, on the robot's newest physics, ``-v3``), the delicate ones' (``circle2x2_delicate``)
#: and the delicate ones held by the robot (``circle2x2_delicate_panda``).
SUITES: dict[str, containers.TaggedTasks] = {t.domain: _domain_suite(t) for t in GYM_TASKS}


def get_tasks(tag: str | None = None) -> tuple[tuple[str, str], ...]:
    """``(domain, task)`` pairs, in the task table's order, having ``tag`` (all if ``None``)."""
    return tuple(
        (domain, name)
        for domain, suite in SUITES.items()
        for name in (suite if tag is None else suite.tagged(tag))
    )


ALL_TASKS = get_tasks()
PAPER = get_tasks("paper")
CIRCLE = get_tasks("circle")
POLYGON = get_tasks("polygon")
GRADE = get_tasks("grade")
DEFECTIVE = get_tasks("defective")
ROBOT = get_tasks("robot")
DELICATE = get_tasks("delicate")
#: Domain -> its task names.
TASKS_BY_DOMAIN = {domain: tuple(suite) for domain, suite in SUITES.items()}


def load(
    domain_name: str,
    task_name: str,
    task_kwargs: dict[str, Any] | None = None,
    environment_kwargs: dict[str, Any] | None = None,
) -> control.Environment:
    """An environment of the suite, like ``dm_control.suite.load``.

    Args:
        domain_name: One of :data:`TASKS_BY_DOMAIN`, e.g. ``"circle2x2"``.
        task_name: ``"insert"``.
        task_kwargs: Keywords of :class:`Insert` (``random`` seed, ``measurement_noise``,
            ``goal``, ``pose``, ``horizon``, ...).
        environment_kwargs: Keywords of ``control.Environment`` (``control_timestep``
            defaults to 0.25 s).
    """
    if domain_name not in SUITES:
        raise ValueError(f"domain_name={domain_name!r} is unknown; allowed: {list(SUITES)}")
    suite = SUITES[domain_name]
    if task_name not in suite:
        raise ValueError(
            f"task_name={task_name!r} is unknown in domain {domain_name!r}; allowed: {list(suite)}"
        )
    return suite[task_name](environment_kwargs=environment_kwargs, **(task_kwargs or {}))

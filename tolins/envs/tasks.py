"""The task table: every preset workpiece, feeding the gymnasium ids and the dm_control suite."""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

import gymnasium as gym

from tolins.geometry.specs import (
    GRADES_UM,
    CircularSocket,
    PolygonSocket,
    SocketSpec,
    with_clearance,
)
from tolins.physics.versions import LATEST, VERSIONS, versions_of

ENTRY_POINT = "tolins.envs.insertion_env:InsertionEnv"
#: The batched env of every id (``gymnasium.make_vec(..., vectorization_mode=
#: "vector_entry_point")``).
VECTOR_ENTRY_POINT = "tolins.envs.vector:InsertionVectorEnv"
#: Bent-pin std (mm) of the defective preset: about 60 % of its workpieces insert at
#: the nominal goal (two pins, each inside a 0.2 mm clearance with probability √0.6).
DEFECT_SIGMA = 0.12


@dataclass(frozen=True)
class Task:
    """One preset workpiece.

    Attributes:
        name: Gymnasium name, ``tolins/{name}-v1`` and ``tolins/{name}-v2`` (the physics
            versions, :mod:`tolins.physics.versions`).
        domain: dm_control domain name (task ``insert``).
        socket: The (nominal) socket.
        tags: Suite tags, e.g. ``paper``, ``circle``, ``polygon``, ``defective``, ``robot``.
        defect_sigma: Bent-pin std (mm) re-sampled at every reset, or ``None``.
        robot: What holds the workpiece (``"free"``, the paper's servos, or ``"panda"``).
        versions: The physics versions it is registered in (``None``: every one its robot
            has, :func:`~tolins.physics.versions.versions_of`).
        pins: ``"rigid"`` or ``"elastic-plastic"`` (the ``delicate`` tasks).
    """

    name: str
    domain: str
    socket: SocketSpec
    tags: tuple[str, ...]
    defect_sigma: float | None = None
    robot: str = "free"
    versions: tuple[int, ...] | None = None
    pins: str = "rigid"

    @property
    def physics_versions(self) -> tuple[int, ...]:
        """The physics versions whose ids it has."""
        return versions_of(self.robot) if self.versions is None else self.versions

    @property
    def gym_id(self) -> str:
        """The ``-v1`` id."""
        return self.gym_id_of(1)

    def gym_id_of(self, version: int) -> str:
        """The id of a physics version, ``tolins/{name}-v{version}``."""
        return f"tolins/{self.name}-v{version}"

    def env_kwargs_of(self, version: int) -> dict[str, Any]:
        """The env's keywords under its id of a physics version."""
        kwargs: dict[str, Any] = {"socket": self.socket}
        if self.defect_sigma is not None:
            kwargs["defect_sigma"] = self.defect_sigma
        if version != 1:
            kwargs["physics_version"] = version
        if self.robot != "free":
            kwargs["robot"] = self.robot
        if self.pins != "rigid":
            kwargs["pins"] = self.pins
        return kwargs

    @property
    def env_kwargs(self) -> dict[str, Any]:
        """The ``-v1`` id's keywords."""
        return self.env_kwargs_of(1)


def _circle(cols: int, *tags: str, defect_sigma: float | None = None) -> Task:
    suffix = "Defective" if defect_sigma else ""
    return Task(
        name=f"Circle2x{cols}{suffix}",
        domain=f"circle2x{cols}{'_defective' if defect_sigma else ''}",
        socket=CircularSocket(rows=2, cols=cols),
        tags=("paper", "circle", *tags),
        defect_sigma=defect_sigma,
    )


def _polygon(name: str, sides: int, pin: float, hole: float) -> Task:
    return Task(name, name.lower(), PolygonSocket(sides, pin, hole), ("paper", "polygon"))


#: Table 1's workpieces (sizes from its caption).
TASKS: tuple[Task, ...] = (
    _circle(1),
    _circle(2),
    _circle(4),
    _circle(8),
    _circle(1, "defective", defect_sigma=DEFECT_SIGMA),
    _polygon("Square", 4, 1.5, 1.65),
    _polygon("Pentagon", 5, 1.5, 1.65),
    _polygon("Hexagon", 6, 1.2, 1.26),
)


def _grade(task: Task, clearance_um: int) -> Task:
    """``task``'s workpiece with its holes resized to a radial clearance of
    ``clearance_um`` µm (:func:`~tolins.geometry.specs.with_clearance`, pins unchanged)."""
    family = task.socket.family
    return Task(
        name=f"{task.name}Fit{clearance_um}",
        domain=f"{task.domain}_fit{clearance_um}",
        socket=with_clearance(task.socket, clearance_um * 1e-3),
        tags=("grade", family, f"fit{clearance_um}"),
    )


#: Tolerance grades: the 2*2 and 2*8 sockets and the square and hexagon pegs at
#: radial clearances of 100, 50 and 20 µm (the paper's are 200, 200, 106 and 52 µm), the
#: physics step following the grade (:data:`~tolins.mjcf.model.GRADE_TIMESTEPS`).
GRADE_TASKS: tuple[Task, ...] = tuple(
    _grade(task, um)
    for task in TASKS
    if task.name in ("Circle2x2", "Circle2x8", "Square", "Hexagon")
    for um in GRADES_UM[1:]
)
#: Every preset: the paper's (``TASKS``), then the grades; gymnasium ids and dm_control
#: domains are registered for each.
PRESETS: tuple[Task, ...] = TASKS + GRADE_TASKS


def _on_panda(task: Task, versions: tuple[int, ...] = (2, LATEST)) -> Task:
    """``task`` with a Franka Panda holding the part (:mod:`tolins.physics.panda`), its pins
    as ``task``'s, on the physics ``versions`` (default: 2 and the Panda's newest), tagged
    ``robot`` (not ``paper`` or ``grade``: those suites stay the free body's)."""
    return Task(
        name=f"{task.name}Panda",
        domain=f"{task.domain}_panda",
        socket=task.socket,
        tags=("robot", *(t for t in task.tags if t not in ("paper", "grade"))),
        defect_sigma=task.defect_sigma,
        robot="panda",
        versions=versions,
        pins=task.pins,
    )


#: The paper's workpieces and the 50 µm grades held by a Franka Panda: gymnasium ids
#: ``tolins/{name}Panda-v2`` and ``-v3`` (:mod:`tolins.physics.versions`).
ROBOT_TASKS: tuple[Task, ...] = tuple(
    _on_panda(task) for task in TASKS + GRADE_TASKS if task in TASKS or "fit50" in task.tags
)


def _delicate(task: Task) -> Task:
    """``task`` with pins that bend and stay bent (``pins="elastic-plastic"``, phosphor
    bronze, docs/delicate.md), on physics version 2, tagged ``delicate`` (not ``paper`` or
    ``grade``: those suites stay the rigid pins')."""
    return Task(
        name=f"{task.name}Delicate",
        domain=f"{task.domain}_delicate",
        socket=task.socket,
        tags=("delicate", *(t for t in task.tags if t not in ("paper", "grade"))),
        versions=(2,),
        pins="elastic-plastic",
    )


#: The paper's round-pin workpieces and their 50 µm grades with delicate pins: gymnasium
#: ids ``tolins/{name}Delicate-v2``.
DELICATE_TASKS: tuple[Task, ...] = tuple(
    _delicate(task)
    for task in TASKS + GRADE_TASKS
    if task.socket.family == "circle"
    and task.defect_sigma is None
    and (task in TASKS or "fit50" in task.tags)
)
#: The delicate workpieces held by a Franka Panda, on its newest physics: gymnasium ids
#: ``tolins/{name}DelicatePanda-v3``, tagged ``robot`` and ``delicate``.
DELICATE_ROBOT_TASKS: tuple[Task, ...] = tuple(
    _on_panda(task, versions=(LATEST,)) for task in DELICATE_TASKS
)
#: Every task that has gymnasium ids (and a dm_control domain), in the order of their ids.
GYM_TASKS: tuple[Task, ...] = PRESETS + ROBOT_TASKS + DELICATE_TASKS + DELICATE_ROBOT_TASKS
#: The generic ids by physics version; pass ``socket=`` (and any other keyword) to
#: ``gymnasium.make``.
GENERIC_IDS = {version: f"tolins/Insert-v{version}" for version in versions_of("free")}
GENERIC_ID = GENERIC_IDS[1]


def env_ids(*, generic: bool = True) -> tuple[str, ...]:
    """Every tolins gymnasium id, version by version: the presets' (the paper's, then the
    grades), the robot tasks', then the generic one (left out with ``generic=False``)."""
    ids = []
    for version in VERSIONS:
        ids += [task.gym_id_of(version) for task in GYM_TASKS if version in task.physics_versions]
        if generic and version in GENERIC_IDS:
            ids.append(GENERIC_IDS[version])
    return tuple(ids)


def task_of(env_id: str) -> Task:
    """The preset task (or robot task) of a tolins id of any physics version it has;
    ``ValueError`` otherwise."""
    name, _, version = env_id.removeprefix("tolins/").rpartition("-v")
    for task in GYM_TASKS:
        if task.name == name and version.isdigit() and int(version) in task.physics_versions:
            return task
    raise ValueError(f"{env_id!r} is not a preset id; allowed: {', '.join(env_ids(generic=False))}")


def env_label(env_id: str) -> str:
    """``env_id`` without ``tolins/`` and its version, e.g. ``Circle2x2`` (for tables)."""
    return re.sub(r"-v\d+$", "", env_id.removeprefix("tolins/"))


def check_env_id(env_id: str) -> str:
    """``env_id`` if it is a tolins id (:func:`env_ids`); else ``ValueError`` listing them."""
    allowed = env_ids()
    if env_id not in allowed:
        raise ValueError(f"unknown env {env_id!r}; allowed: {', '.join(allowed)}")
    return env_id


def register_envs() -> None:
    """Register every preset (and the generic id) with gymnasium; safe to call twice."""
    entry_points = {"entry_point": ENTRY_POINT, "vector_entry_point": VECTOR_ENTRY_POINT}
    for version in VERSIONS:
        for task in GYM_TASKS:
            if version in task.physics_versions and task.gym_id_of(version) not in gym.registry:
                kwargs = task.env_kwargs_of(version)
                gym.register(id=task.gym_id_of(version), kwargs=kwargs, **entry_points)
        if version in GENERIC_IDS and GENERIC_IDS[version] not in gym.registry:
            kwargs = {} if version == 1 else {"physics_version": version}
            gym.register(id=GENERIC_IDS[version], kwargs=kwargs, **entry_points)


def make_vec(env_id: str, num_envs: int = 1, **kwargs: Any) -> gym.vector.VectorEnv:
    """``gymnasium.make_vec(env_id, num_envs, vectorization_mode="vector_entry_point",
    **kwargs)``: the batched :class:`~tolins.envs.vector.InsertionVectorEnv` of a tolins id
    (``backend=``, ``num_threads=``, ``autoreset_mode=`` and every ``InsertionEnv``
    keyword)."""
    return gym.make_vec(
        check_env_id(env_id), num_envs=num_envs, vectorization_mode="vector_entry_point", **kwargs
    )

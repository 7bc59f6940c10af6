"""The simulators by name: the one table the single env, the vector env and the bench read.

Each :class:`Simulator` pairs a single-env backend (``None`` where there is none) with a
batch of the vector env; what each can do is declared on its classes
(:class:`~tolins.physics.protocol.Capabilities`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from tolins.geometry.delicate import ElasticPins
from tolins.geometry.specs import SocketSpec
from tolins.physics.kinematic import KinematicBackend, KinematicBatch
from tolins.physics.mujoco import MujocoBackend, MujocoBatch
from tolins.physics.panda import PandaBackend, PandaBatch
from tolins.physics.protocol import Backend, BatchPhysics
from tolins.physics.versions import PhysicsVersion
from tolins.physics.warp import WarpBatch


@dataclass(frozen=True)
class Simulator:
    """One simulator.

    Attributes:
        name: Its ``backend=`` name.
        batch: The vector env's batch class: ``batch(socket, num_envs, control_dt,
            physics_version=..., **options)`` with the options of its ``batch_options``.
        single: The single env's backend class, ``single(spec, control_dt,
            physics_version=...)``; ``None`` for a simulator that only runs batches.
    """

    name: str
    batch: type[Any]
    single: type[Any] | None = None


#: Every simulator, by name, in the order they are listed to users.
SIMULATORS: dict[str, Simulator] = {
    s.name: s
    for s in (
        Simulator("mujoco", MujocoBatch, MujocoBackend),
        Simulator("kinematic", KinematicBatch, KinematicBackend),
        Simulator("warp", WarpBatch),  # needs pip install 'tolins[warp]'
    )
}
#: The simulators of the single env (and of everything built on it, such as the bench).
BACKENDS = tuple(name for name, s in SIMULATORS.items() if s.single is not None)
#: The simulators of the vector env.
BATCH_BACKENDS = tuple(SIMULATORS)
#: What holds the workpiece, and its simulators by name: ``"free"``, the paper's ideal
#: servos on a free-floating body (every simulator above); ``"panda"``, a Franka Panda
#: holding it (:mod:`tolins.physics.panda`, MuJoCo only).
ROBOTS: dict[str, dict[str, Simulator]] = {
    "free": SIMULATORS,
    "panda": {"mujoco": Simulator("mujoco", PandaBatch, PandaBackend)},
}


#: Why a robot runs on its simulators alone.
ROBOT_ONLY_ON = {
    "panda": "the arm's law is compiled for the CPU and runs between MuJoCo's physics steps, "
    "where MuJoCo Warp's kernels cannot call it; the kinematic simulator has no arm",
}


def check_robot(robot: object) -> str:
    """``robot`` if it is one of :data:`ROBOTS`; ``ValueError`` naming them otherwise."""
    if not isinstance(robot, str) or robot not in ROBOTS:
        raise ValueError(f"robot={robot!r}; allowed: {', '.join(map(repr, ROBOTS))}")
    return robot


def simulator(name: object, *, single: bool = False, robot: str = "free") -> Simulator:
    """The simulator ``name`` (of the single env with ``single``) of ``robot``; ``ValueError``
    naming the allowed ones otherwise."""
    if check_robot(robot) != "free":
        names = tuple(n for n, s in ROBOTS[robot].items() if s.single is not None or not single)
        if name not in names:
            on = ", ".join(map(repr, names))
            raise ValueError(
                f"backend={name!r} with robot={robot!r}; allowed: {on} ({ROBOT_ONLY_ON[robot]})"
            )
        return ROBOTS[robot][name]
    names = BACKENDS if single else BATCH_BACKENDS
    if not isinstance(name, str) or name not in names:
        allowed = sorted(names) if single else ", ".join(map(repr, names))
        raise ValueError(f"backend={name!r}; allowed: {allowed}")
    return SIMULATORS[name]


def with_capability(capability: str) -> tuple[str, ...]:
    """The names of the simulators whose batch has ``capability`` (a flag of
    :class:`~tolins.physics.protocol.Capabilities`) set."""
    return tuple(name for name, s in SIMULATORS.items() if getattr(s.batch, capability))


def taking(option: str) -> tuple[str, ...]:
    """The names of the simulators whose batch takes the keyword ``option``."""
    return tuple(name for name, s in SIMULATORS.items() if option in s.batch.batch_options)


def taking_defect(kind: str) -> tuple[str, ...]:
    """The names of the simulators whose batch simulates the defect ``kind``."""
    return tuple(name for name, s in SIMULATORS.items() if kind in s.batch.defect_kinds)


#: Where pins that bend are simulated: the ``allowed`` of every refusal of them.
ELASTIC_PINS_ON = (
    "allowed: backend='mujoco', the free body's or the Panda's (the single env, the vector env "
    "and dm_control; the kinematic and Warp simulators have no bending pins)"
)


def check_elastic_pins(cls: type, on: str) -> None:
    """``ValueError`` unless the simulator class ``cls`` simulates pins that bend (its
    ``supports_elastic_pins``); ``on`` names where they were asked for, e.g.
    ``backend='kinematic'``."""
    if not cls.supports_elastic_pins:
        raise ValueError(f"pins='elastic-plastic' is not supported on {on}; {ELASTIC_PINS_ON}")


def make_backend(
    name: str,
    spec: SocketSpec,
    control_dt: float,
    physics_version: int | PhysicsVersion = 1,
    robot: str = "free",
    pins: ElasticPins | None = None,
) -> Backend:
    """The single env's backend ``name`` for ``spec`` in a physics version (its number or the
    :class:`~tolins.physics.versions.PhysicsVersion` the task's settings resolved) with
    ``robot`` holding the workpiece; ``pins``: elastic-plastic pins (a simulator with
    ``supports_elastic_pins`` only), ``None``: rigid."""
    chosen = simulator(name, single=True, robot=robot)
    if pins is None:
        return chosen.single(spec, control_dt, physics_version=physics_version)
    check_elastic_pins(chosen.single, simulator_place(name, robot))
    return chosen.single(spec, control_dt, physics_version=physics_version, pins=pins)


def simulator_place(name: str, robot: str, vector: bool = False) -> str:
    """The simulator ``name`` with ``robot`` as an error names it, e.g. ``backend='mujoco',
    robot='panda'`` (the free body unnamed), ``in the vector env`` added for its batch."""
    robot_part = "" if robot == "free" else f", robot={robot!r}"
    return f"backend={name!r}{robot_part}" + (" in the vector env" if vector else "")


def make_batch(
    name: str,
    socket: SocketSpec,
    num_envs: int,
    control_dt: float,
    *,
    physics_version: int | PhysicsVersion = 1,
    num_threads: int | None = None,
    device: str | None = None,
    persistent: bool = False,
    robot: str = "free",
    pins: ElasticPins | None = None,
) -> BatchPhysics:
    """The batch ``name`` of ``num_envs`` copies of ``socket``, ``robot`` holding each.

    ``num_threads`` and ``persistent`` (every simulation's whole data kept, for drawing)
    are hints that a simulator without threads or without per-simulation data ignores;
    ``device`` names hardware, so a simulator that runs on none refuses it. ``pins``:
    elastic-plastic pins (a simulator with ``supports_elastic_pins`` only), ``None``: rigid.
    """
    cls = simulator(name, robot=robot).batch
    if device is not None and "device" not in cls.batch_options:
        on = " or ".join(map(repr, taking("device")))
        raise ValueError(f"device={device!r} is for backend={on} only; got backend={name!r}")
    given = {"num_threads": num_threads, "device": device, "persistent": persistent}
    options = {k: v for k, v in given.items() if k in cls.batch_options and v is not None}
    if pins is not None:
        check_elastic_pins(cls, simulator_place(name, robot, vector=True))
        options["pins"] = pins
    return cls(socket, num_envs, control_dt, physics_version=physics_version, **options)

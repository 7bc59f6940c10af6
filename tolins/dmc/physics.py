"""``InsertionPhysics``: a dm_control ``Physics`` whose ``step`` is the env's control step."""

from __future__ import annotations

import contextlib
from collections.abc import Iterator

import mujoco
import numpy as np
from dm_control import mujoco as dm_mujoco

from tolins.geometry.delicate import ElasticPins
from tolins.geometry.specs import SocketSpec
from tolins.paper import CONTROL_DT
from tolins.physics.compiled import compile_model
from tolins.physics.panda import PandaStepper, compile_panda_world, default_gains, split_draw
from tolins.physics.protocol import BackendState
from tolins.physics.randomization import PhysicsDraw, apply_draw, nominal_fields
from tolins.physics.registry import check_elastic_pins, check_robot, simulator
from tolins.physics.servo import ServoStepper
from tolins.physics.versions import VERSIONS, PhysicsVersion, check_version_robot
from tolins.physics.versions import physics_version as physics_version_of


class InsertionPhysics(dm_mujoco.Physics):
    """A socket model (:func:`tolins.make_mjcf`) stepped by the gym backend's :class:`ServoStepper`.

    ``step(nstep)`` is one control step: it re-anchors the servos, runs ``nstep`` physics
    steps under the velocity last given to :meth:`command`, reading the pins' contact
    force after each of 5 chunks (:class:`ServoStepper`; evenly sized at the default
    0.25 s), and stores the result in
    :attr:`last_state` (a simulator fault is reported there as ``error`` instead of a
    ``PhysicsError``). ``legacy_step`` is ignored. A reset whose task raises changes
    nothing: :meth:`reset_context` puts the data back as it was. Everything else,
    ``named``, ``render``, ``get_state``/``set_state``, is plain dm_control.
    """

    #: The physics version (:mod:`tolins.physics.versions`); :meth:`from_spec` sets it.
    version: PhysicsVersion = VERSIONS[1]
    #: Elastic-plastic pins (``pins="elastic-plastic"``), or ``None`` (rigid); :meth:`from_spec`
    #: sets it.
    pins: ElasticPins | None = None

    def _reload_from_data(self, data: dm_mujoco.wrapper.MjData) -> None:
        super()._reload_from_data(data)
        self._bind_stepper()

    #: What holds the workpiece (``"free"`` here; :class:`PandaInsertionPhysics`: ``"panda"``).
    robot = "free"

    def _bind_stepper(self) -> None:
        free_flight = self.version.free_flight
        self.stepper = ServoStepper(self.model.ptr, self.data.ptr, free_flight=free_flight)
        self._bound()

    def _bound(self) -> None:
        self.last_state = self.stepper.state(self.stepper.contact_force())
        self._saved: mujoco.MjData | None = None

    @contextlib.contextmanager
    def reset_context(self) -> Iterator[InsertionPhysics]:
        """dm_control's reset context (reset the data, then the task places the workpiece);
        an exception inside it restores the data, and the last state, as they were."""
        model, data = self.model.ptr, self.data.ptr
        if self._saved is None:
            self._saved = mujoco.MjData(model)
        mujoco.mj_copyData(self._saved, model, data)
        last_state = self.last_state
        try:
            with super().reset_context():
                yield self
        except BaseException:
            if self.model.ptr is model:
                mujoco.mj_copyData(data, model, self._saved)
                self.last_state = last_state
            raise

    @classmethod
    def from_spec(
        cls,
        spec: SocketSpec,
        physics_version: int | PhysicsVersion = 1,
        robot: str = "free",
        pins: ElasticPins | None = None,
    ) -> InsertionPhysics:
        """The physics of ``spec``'s board and workpiece in a physics version (its number, or
        the :class:`PhysicsVersion` the task's settings resolved), ``robot`` holding the part
        (``"panda"``: a :class:`PandaInsertionPhysics`), with elastic-plastic ``pins`` (the
        task's ``settings.elastic``; ``None``: rigid)."""
        if check_robot(robot) != cls.robot:
            return ROBOT_PHYSICS[robot].from_spec(spec, physics_version, robot, pins)
        version = physics_version_of(physics_version)
        check_version_robot(version, robot)
        if pins is not None:
            check_elastic_pins(
                simulator("mujoco", single=True, robot=robot).single, f"robot={robot!r}"
            )
        physics = cls.from_model(cls.compile(spec, version, pins))
        if version is not physics.version or pins is not None:
            physics.version, physics.pins = version, pins
            physics._bind_stepper()
        return physics

    @classmethod
    def compile(
        cls, spec: SocketSpec, version: PhysicsVersion, pins: ElasticPins | None = None
    ) -> dm_mujoco.wrapper.MjModel:
        """The model of ``spec`` in ``version`` (with elastic-plastic ``pins``)."""
        return dm_mujoco.wrapper.MjModel(compile_model(spec, version, pins))

    def reload_from_spec(self, spec: SocketSpec) -> None:
        """Replace the model by ``spec``'s (e.g. a new bent-pin workpiece)."""
        self._reload_from_model(self.compile(spec, self.version, self.pins))

    def set_grasp(self, offset: np.ndarray) -> None:
        """Hold the part off by ``offset`` from the next reset on (a robot's only)."""
        raise ValueError(f"a grasp error needs a robot; this physics' robot={self.robot!r}")

    def set_physics(self, draw: PhysicsDraw | None) -> None:
        """Apply a randomised-physics ``draw`` to the model from its nominal values
        (``None``: nominal; :mod:`tolins.physics.randomization`)."""
        model = self.model.ptr
        if getattr(self, "_nominal_of", None) is not model:
            if draw is None:
                return
            self._nominal_of, self._nominal = model, nominal_fields(model)
        apply_draw(model, self._nominal, draw or PhysicsDraw())

    def set_pose(self, pose: np.ndarray) -> BackendState:
        """Reset the data and place the workpiece at ``pose`` ``[x, y, theta, z]`` at rest
        (elastic-plastic pins straight)."""
        self.last_state = self.stepper.reset(pose)
        return self.last_state

    def command(self, velocity: np.ndarray) -> None:
        """Set the velocity ``[ux, uy, utheta, uz]`` (mm/s, rad/s) of the next steps."""
        self.stepper.command(velocity)

    def step(self, nstep: int = 1) -> None:
        """One control step of ``nstep`` physics steps (see the class docstring)."""
        self.last_state = self.stepper.advance(nstep)

    def pose(self) -> np.ndarray:
        """True pose ``[x, y, theta, z]`` (mm, rad) now."""
        return self.stepper.state(0.0).pose


class PandaInsertionPhysics(InsertionPhysics):
    """A Franka Panda holding the workpiece (:mod:`tolins.physics.panda`): the same physics
    whose ``step(nstep)`` is the arm's control step (:class:`PandaStepper`)."""

    robot = "panda"
    version: PhysicsVersion = VERSIONS[2]

    def _bind_stepper(self) -> None:
        gains = default_gains(self.version)
        self.stepper = PandaStepper(self.model.ptr, self.data.ptr, CONTROL_DT, gains)
        self._bound()

    @classmethod
    def compile(
        cls, spec: SocketSpec, version: PhysicsVersion, pins: ElasticPins | None = None
    ) -> dm_mujoco.wrapper.MjModel:
        return dm_mujoco.wrapper.MjModel(compile_panda_world(spec, version, pins))

    def set_grasp(self, offset: np.ndarray) -> None:
        self.stepper.set_grasp(offset)

    def set_physics(self, draw: PhysicsDraw | None) -> None:
        """A randomised-physics ``draw``: its contact terms on the model, its servo terms on
        the law (:func:`~tolins.physics.panda.split_draw`)."""
        if draw is None:
            super().set_physics(None)
            self.stepper.set_gains(None)
            return
        contact, gains = split_draw(draw, self.stepper.arm.gains)
        super().set_physics(contact)
        self.stepper.set_gains(gains)


#: The physics class of each robot.
ROBOT_PHYSICS: dict[str, type[InsertionPhysics]] = {
    "free": InsertionPhysics,
    "panda": PandaInsertionPhysics,
}

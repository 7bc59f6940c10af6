"""Where a compiled socket model keeps what the simulators read and write.

:func:`model_layout` reads, once per model, the addresses that every simulator of a model
made by :func:`~tolins.mjcf.model.make_mjcf` needs: the pins' touch sensors and the
force/torque sensor in ``sensordata``, the pin geoms, and the order of the workpiece's
joints (``qpos``, ``act`` and ``ctrl``) against the pose ``[x, y, theta, z]``.
:data:`BEND_FIELDS` names the compiled fields that moving the pins can change.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from tolins.geometry.specs import CircularSocket, SocketSpec
from tolins.mjcf.elastic_pins import (
    HINGES,
    LENGTH,
    YIELD_ROTATION,
    equality_name,
    hinge_name,
)
from tolins.mjcf.model import (
    FORCE_SENSOR,
    POSE_JOINTS,
    TORQUE_SENSOR,
    pin_geom_name,
    touch_sensor_name,
)

if TYPE_CHECKING:
    import mujoco

#: Model units (mN, µN·m) to the API's N and N·mm.
FORCE_SCALE = 1e-3

#: The compiled model's array fields that moving the pins (``pin_offsets``, a bend) can
#: change. From the pin positions the MJCF writes the pins' geoms and sites, the carrier and
#: the board boxes (sized to the pins' reach: positions, sizes, bounds), and the scene's
#: extent; MuJoCo then derives the board body's mass and inertia from its pieces, the camera
#: and light from the extent, and the bounding-volume trees, joint length scales and
#: same-frame flags from the rest.
BEND_FIELDS = (
    "body_inertia",
    "body_ipos",
    "body_mass",
    "body_subtreemass",
    "bvh_aabb",
    "bvh_nodeid",
    "cam_pos",
    "cam_pos0",
    "cam_poscom0",
    "dof_length",
    "geom_aabb",
    "geom_pos",
    "geom_rbound",
    "geom_size",
    "light_poscom0",
    "site_pos",
    "site_sameframe",
    "site_size",
)


def bend_fields(spec: SocketSpec) -> tuple[str, ...]:
    """The compiled fields a bent workpiece of ``spec``'s family can change:
    :data:`BEND_FIELDS` for round pins, none for a polygon peg (it does not bend)."""
    return BEND_FIELDS if isinstance(spec, CircularSocket) else ()


@dataclass(frozen=True, eq=False)
class ElasticPinLayout:
    """Where a model's elastic-plastic pins (:mod:`tolins.mjcf.elastic_pins`) are
    (:func:`elastic_pin_layout`).

    Attributes:
        hinges: ``qpos`` address of each pin's root hinges ``(n_pins, 2)`` ``[bx, by]``.
        equalities: Id of the joint equality holding each of those hinges ``(n_pins, 2)``.
        yield_rotation: Each pin's root rotation at first yield ``(n_pins,)`` (rad).
        length: Each pin's free length ``(n_pins,)`` (mm).
    """

    hinges: np.ndarray
    equalities: np.ndarray
    yield_rotation: np.ndarray
    length: np.ndarray


@dataclass(frozen=True, eq=False)
class ModelLayout:
    """The addresses of one compiled socket model (:func:`model_layout`).

    Attributes:
        n_pins: Number of pins.
        touch: ``sensordata`` of the pins' touch sensors, pin by pin (model units).
        force: ``sensordata`` of the force sensor, ``[fx, fy, fz]`` in workpiece axes.
        torque_z: ``sensordata`` address of the torque sensor's z component.
        pin_geoms: Geom id of each pin.
        joint_pose: The pose index of each joint, in joint order (``qpos``, ``act`` and
            ``ctrl`` alike): ``qpos = pose[joint_pose]``.
        pose_joint: The joint of each pose component: ``pose = qpos[pose_joint]``.
        pin_by_geom: Pin index by geom id (of the pins only).
        elastic: Where its elastic-plastic pins' hinges are (:func:`elastic_pin_layout`),
            or ``None`` (rigid pins).
    """

    n_pins: int
    touch: slice
    force: slice
    torque_z: int
    pin_geoms: tuple[int, ...]
    joint_pose: np.ndarray
    pose_joint: np.ndarray
    elastic: ElasticPinLayout | None = None
    pin_by_geom: dict[int, int] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self.joint_pose.flags.writeable = False
        self.pose_joint.flags.writeable = False
        pins = {geom: pin for pin, geom in enumerate(self.pin_geoms)}
        object.__setattr__(self, "pin_by_geom", pins)


def touch_addresses(model: mujoco.MjModel) -> list[int]:
    """``sensordata`` address of each pin's touch sensor, pin by pin."""
    addresses = []
    while True:
        try:
            addresses.append(int(model.sensor(touch_sensor_name(len(addresses))).adr[0]))
        except KeyError:
            return addresses


def model_layout(model: mujoco.MjModel) -> ModelLayout:
    """The layout of ``model``, a model made by :func:`~tolins.mjcf.model.make_mjcf`;
    ``RuntimeError`` if it is not one (touch sensors missing or not contiguous, or the
    servos not in joint order)."""
    touch = touch_addresses(model)
    if not touch or touch != list(range(touch[0], touch[0] + len(touch))):
        raise RuntimeError("the pins' touch sensors are missing or not stored contiguously")
    pose_joint = np.array([model.joint(name).qposadr[0] for name in POSE_JOINTS], dtype=np.intp)
    joints = np.array([model.joint(name).id for name in POSE_JOINTS])
    elastic = elastic_pin_layout(model)
    # One actuator per joint, in joint order, each with one activation (act = qpos[:nu]),
    # the workpiece's joints first (then any pin hinges).
    n_pose = len(POSE_JOINTS)
    servos_in_order = (
        model.nu == model.na == n_pose
        and model.nq == n_pose + (0 if elastic is None else elastic.hinges.size)
        and np.array_equal(model.actuator_trnid[:, 0], np.sort(joints))
        and np.array_equal(model.jnt_qposadr[np.sort(joints)], np.arange(n_pose))
        and np.array_equal(model.actuator_actadr, np.arange(model.nu))
    )
    if not servos_in_order:
        raise RuntimeError("the workpiece's servos are not one per joint in joint order")
    force = int(model.sensor(FORCE_SENSOR).adr[0])
    return ModelLayout(
        n_pins=len(touch),
        touch=slice(touch[0], touch[0] + len(touch)),
        force=slice(force, force + 3),
        torque_z=int(model.sensor(TORQUE_SENSOR).adr[0]) + 2,
        pin_geoms=tuple(int(model.geom(pin_geom_name(i)).id) for i in range(len(touch))),
        joint_pose=np.argsort(pose_joint),
        pose_joint=pose_joint,
        elastic=elastic,
    )


def _numeric(model: mujoco.MjModel, name: str) -> np.ndarray:
    """The model's ``<custom>`` numeric ``name`` (a copy)."""
    numeric = model.numeric(name)
    return np.array(model.numeric_data[numeric.adr[0] : numeric.adr[0] + numeric.size[0]])


def elastic_pin_layout(model: mujoco.MjModel) -> ElasticPinLayout | None:
    """Where the elastic-plastic pins of ``model`` are, or ``None`` if its pins are rigid:
    a socket model of :func:`~tolins.mjcf.model.make_mjcf` or a world that holds one (the
    Panda's), by the names the pins' hinges, equalities and numerics have there."""
    try:
        model.joint(hinge_name(0, HINGES[0][0]))
    except KeyError:
        return None
    pins = range(len(touch_addresses(model)))
    suffixes = [s for s, _ in HINGES]
    joints = [[model.joint(hinge_name(i, s)).id for s in suffixes] for i in pins]
    equalities = [[model.equality(equality_name(i, s)).id for s in suffixes] for i in pins]
    return ElasticPinLayout(
        hinges=model.jnt_qposadr[np.array(joints, dtype=np.intp)].astype(np.intp),
        equalities=np.array(equalities, dtype=np.intp),
        yield_rotation=_numeric(model, YIELD_ROTATION),
        length=_numeric(model, LENGTH),
    )

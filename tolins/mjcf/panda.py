"""The Franka Panda arm and hand as an ``MjSpec`` in tolins' units (mm, kg, s), torque-driven.

The model is read as package data of gymnasium-robotics (``tolins[robot]``): its
``kitchen_franka/franka_assets`` (MIT; the Franka model of Vikash Kumar's ``franka``,
Apache-2.0), without importing that package. Its limits are the Franka's published ones:
joint ranges, torque limits of 87 N·m (joints 1–4) and 12 N·m (5–7), 70 N per finger.

tolins' socket models are in mm (:mod:`tolins.mjcf.model`), the Panda's files in metres, so
:func:`scale_to_mm` rescales every length-carrying field: positions and sizes by 1000,
inertias, hinge damping, armature, friction loss and torques by 1000², slide ranges and
forces by 1000 (a force is kg·mm/s², a mN), gravity to −9810 mm/s². Forward kinematics,
masses and the gravity torques of the scaled model are the metre model's in those units
(tested). The position servos of the files become motors (``ctrl`` = torque in model
units, ``ctrlrange`` = the torque limit), so that a task-space controller commands joint
torques. The hand is moved into a body of its own at the flange, so that a wrist
force/torque sensor there reads what a real one does. :func:`panda_world` puts the arm
beside a socket, holding its workpiece.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import mujoco
import numpy as np

from tolins.geometry.delicate import ElasticPins
from tolins.geometry.specs import SocketSpec
from tolins.geometry.workspace import PIN_LENGTH
from tolins.mjcf.model import CARRIER_THICKNESS, SOLIMP, SOLREF, make_mjcf

#: Model units per metre.
MM_PER_M = 1000.0
#: The seven arm joints and the two finger joints of the model, in order.
ARM_JOINTS = tuple(f"robot:panda0_joint{i}" for i in range(1, 8))
FINGER_JOINTS = ("robot:panda0_finger_joint1", "robot:panda0_finger_joint2")
#: The site between the fingertips (the hand's tool frame), 210 mm along link 7.
GRIP_SITE = "end_effector"
#: The hand's body, mounted at the flange, and the flange's site (the wrist sensor's).
HAND = "panda0_hand"
FLANGE = "flange"
#: Gravity in model units (mm/s²).
GRAVITY = np.array([0.0, 0.0, -9.81 * MM_PER_M])

#: The prefix of the arm's element names in a world of :func:`panda_world`.
PREFIX = "panda/"
#: Half sizes (mm) of the handle on the carrier that the fingers close on.
HANDLE = np.array([6.0, 8.0, 10.0])
HANDLE_MASS = 0.05
#: The arm's base relative to the board's top centre (mm).
BASE = (-450.0, 0.0, -60.0)
#: Friction of the finger pads on the handle (tangential; torsional and rolling in mm).
GRIP_FRICTION = (1.0, 0.005, 0.0001)
#: Half sizes (mm) of the flat pad on each finger's inner face (along the pads, across
#: them, along the finger); the inner face is the finger's centre line, so the pads meet
#: the handle with the fingers :data:`HANDLE`\ [1] open.
PAD = np.array([9.0, 1.0, 9.0])
#: The wrist's force/torque sensors at the flange (model units, the flange's frame): what
#: the link holds of the hand, the fingers and the part (a real wrist sensor's reading).
WRIST_FORCE, WRIST_TORQUE = "wrist_force", "wrist_torque"
#: The arm's motors, joint 1 to 7, in a world of :func:`panda_world`.
ARM_MOTORS = tuple(f"{PREFIX}panda0_joint{i}" for i in range(1, 8))
#: The finger motors (closing: negative force).
FINGER_ACTUATORS = (PREFIX + "r_gripper_finger_joint", PREFIX + "l_gripper_finger_joint")

#: The impedance of the pads' contacts with the handle in a firm grip (``panda_world(...,
#: firm_grip=True)``), from the first µm of penetration (the task's contacts ramp from 0.99
#: to 0.999 over 0.01 mm): the friction that holds the part yields about ten times less,
#: and the part creeps about 12 µm per episode in the hand instead of 90.
FIRM_GRIP_IMPEDANCE = 0.999

_SOLREF = [float(v) for v in SOLREF.split()]
_SOLIMP = [*(float(v) for v in SOLIMP.split()), 0.5, 2.0]  # MuJoCo's midpoint, power
_PACKAGE = "gymnasium_robotics"
_ASSETS = Path("envs", "assets", "kitchen_franka", "franka_assets")


def panda_assets() -> Path:
    """The folder of the Panda's MJCF files and meshes (``ImportError`` naming the extra
    when gymnasium-robotics is not installed)."""
    found = importlib.util.find_spec(_PACKAGE)
    if found is None or not found.submodule_search_locations:
        raise ImportError(
            "the Panda model is read from gymnasium-robotics' package data: "
            "pip install 'tolins[robot]'"
        )
    folder = Path(next(iter(found.submodule_search_locations))) / _ASSETS
    if not (folder / "chain.xml").is_file():
        raise ImportError(f"{folder}: no chain.xml; allowed: gymnasium-robotics 1.4")
    return folder


def require_panda(user: str) -> None:
    """Raise ``ImportError`` (``user`` needs the Panda model, and how to install it) unless
    :func:`panda_assets` finds it; ``user`` names what needs it."""
    try:
        panda_assets()
    except ImportError as error:
        raise ImportError(f"{user} needs the Panda model ({error})") from None


def _inner(text: str) -> str:
    """The content of a ``<mujocoinclude>`` file."""
    start, end = text.index("<mujocoinclude>"), text.rindex("</mujocoinclude>")
    return text[start + len("<mujocoinclude>") : end]


def _replace_once(text: str, old: str, new: str) -> str:
    if text.count(old) != 1:
        raise ImportError(
            f"the Panda's chain.xml is not the one expected ({old!r}); "
            "allowed: gymnasium-robotics 1.4.2"
        )
    return text.replace(old, new)


def _chain_with_hand(chain: str) -> str:
    """``chain.xml`` with the hand in a body of its own, ``panda0_hand`` at the flange
    (107 mm along link 7), so that a force/torque sensor there reads what a wrist sensor
    reads: the hand, the fingers and what they hold. Positions inside move with it; the
    kinematics are the same."""
    hand_geom = '<geom pos="0 0 0.107" quat="0.92388 0 0 -0.382683" class="panda_viz"'
    chain = _replace_once(
        chain,
        hand_geom,
        f'<body name="{HAND}" pos="0 0 0.107"><site name="{FLANGE}" size="0.005"/>'
        + hand_geom.replace("0 0 0.107", "0 0 0"),
    )
    chain = _replace_once(
        chain,
        '<geom pos="0 0 0.107" quat="0.92388 0 0 -0.382683" class="panda_col"',
        '<geom pos="0 0 0" quat="0.92388 0 0 -0.382683" class="panda_col"',
    )
    chain = _replace_once(chain, "pos='0 0 .210'", "pos='0 0 .103'")
    for finger in ("leftfinger", "rightfinger"):
        chain = _replace_once(
            chain,
            f'name="panda0_{finger}" pos="0 0 0.1654"',
            f'name="panda0_{finger}" pos="0 0 0.0584"',
        )
    end = chain.index("</body>", chain.index('name="panda0_rightfinger"'))
    return chain[: end + len("</body>")] + "</body>" + chain[end + len("</body>") :]


def panda_spec_in_metres() -> mujoco.MjSpec:
    """The Panda's files in one model (metres, position servos), the hand in its own body
    (:func:`_chain_with_hand`)."""
    folder = panda_assets()
    assets = _inner((folder / "assets.xml").read_text())
    assets = _replace_once(
        assets, 'meshdir="franka_assets/meshes"', f'meshdir="{folder / "meshes"}"'
    )
    chain = _chain_with_hand(_inner((folder / "chain.xml").read_text()))
    actuators = _inner((folder / "actuator.xml").read_text())
    xml = f'<mujoco model="panda">{assets}<worldbody>{chain}</worldbody>{actuators}</mujoco>'
    return mujoco.MjSpec.from_string(xml)


def scale_to_mm(spec: mujoco.MjSpec) -> mujoco.MjSpec:
    """``spec`` (in metres) rescaled in place to mm, kg, s; returned."""
    mm, mm2 = MM_PER_M, MM_PER_M**2
    for body in spec.bodies:
        body.pos, body.ipos = body.pos * mm, body.ipos * mm
        body.inertia, body.fullinertia = body.inertia * mm2, body.fullinertia * mm2
    for geom in spec.geoms:
        geom.pos = geom.pos * mm
        geom.margin, geom.gap = geom.margin * mm, geom.gap * mm
        if geom.type != mujoco.mjtGeom.mjGEOM_MESH:
            geom.size = geom.size * mm
        if not np.isnan(geom.fromto[0]):
            geom.fromto = geom.fromto * mm
        geom.solimp = np.array(geom.solimp) * [1, 1, mm, 1, 1]  # its width is a length
        geom.friction = np.array(geom.friction) * [1, mm, mm]  # torsional, rolling: lengths
    for mesh in spec.meshes:
        mesh.scale = np.array(mesh.scale) * mm
    for site in spec.sites:
        site.pos, site.size = site.pos * mm, site.size * mm
    for joint in spec.joints:
        if joint.type == mujoco.mjtJoint.mjJNT_HINGE:  # N·m·s, kg·m², N·m
            joint.damping, joint.armature = joint.damping * mm2, joint.armature * mm2
            joint.frictionloss *= mm2
        else:  # slides: N·s/m and kg keep their numbers; metres and newtons do not
            joint.range, joint.frictionloss = np.array(joint.range) * mm, joint.frictionloss * mm
    for actuator in spec.actuators:
        hinge = spec.joint(actuator.target).type == mujoco.mjtJoint.mjJNT_HINGE
        gain, bias = np.array(actuator.gainprm), np.array(actuator.biasprm)
        if hinge:  # kp in N·m/rad, kv in N·m·s/rad
            gain[0], bias[1], bias[2] = gain[0] * mm2, bias[1] * mm2, bias[2] * mm2
        else:
            actuator.ctrlrange = np.array(actuator.ctrlrange) * mm
        actuator.gainprm, actuator.biasprm = gain, bias
        actuator.forcerange = np.array(actuator.forcerange) * (mm2 if hinge else mm)
    spec.option.gravity = GRAVITY
    return spec


def torque_motors(spec: mujoco.MjSpec) -> mujoco.MjSpec:
    """Every actuator of ``spec`` turned into a motor on its joint whose control is the
    force or torque itself, limited to the actuator's force range; returned."""
    for actuator in spec.actuators:
        limit = np.array(actuator.forcerange)
        actuator.set_to_motor()
        actuator.ctrllimited = mujoco.mjtLimited.mjLIMITED_TRUE
        actuator.ctrlrange = limit
    return spec


def panda_spec() -> mujoco.MjSpec:
    """The Panda arm and hand in mm, kg, s, torque-driven (seven arm motors, two finger
    motors)."""
    return torque_motors(scale_to_mm(panda_spec_in_metres()))


def handle_centre_height() -> float:
    """Height (mm) of the handle's centre above the pin tips: where the grip site goes."""
    return PIN_LENGTH + CARRIER_THICKNESS + float(HANDLE[2])


def add_pad(arm: mujoco.MjSpec, finger: mujoco.MjsBody) -> mujoco.MjsGeom:
    """A flat pad (:data:`PAD` half sizes, mm) on ``finger``'s inner face, centred at the
    grip site's height: what touches the handle, with the task's stiff contacts and no
    margin. The files' fingers collide through stacked capsules that are rounded, tapered
    and active 1 mm before touching: they held the handle by its bottom edge and pushed
    the part up and along the pads after a reset."""
    site = arm.site(GRIP_SITE)
    rotation = np.zeros(9)
    mujoco.mju_quat2Mat(rotation, np.asarray(finger.quat, dtype=float))
    height = (rotation.reshape(3, 3).T @ (np.asarray(site.pos) - finger.pos))[2]
    side = float(np.sign(finger.joints[0].axis[1]))  # the finger opens towards +y or -y
    return finger.add_geom(
        name=f"{finger.name}_pad",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=PAD,
        pos=[0.0, side * PAD[1], height],
        contype=1,
        conaffinity=2,
        condim=3,
        margin=0.0,
        gap=0.0,
        friction=GRIP_FRICTION,
        solref=_SOLREF,
        solimp=_SOLIMP,
        group=3,
    )


def panda_world(
    socket: SocketSpec,
    base: tuple[float, float, float] = BASE,
    *,
    board_body: bool = True,
    firm_grip: bool = False,
    elastic: ElasticPins | None = None,
) -> mujoco.MjSpec:
    """``socket``'s board and workpiece with the Panda holding the part: the workpiece on a
    free joint (its servos gone) with a handle on its carrier, gravity on, and the arm at
    ``base``.
    The arm's links collide with nothing of the task; the fingers with the part only (the
    board cannot be reached by them with a part in the hand). The sensors
    :data:`WRIST_FORCE` and :data:`WRIST_TORQUE` sit at the flange, beside the model's own
    ``force``/``torque`` at the pins (the true contact wrench on the part). ``board_body``
    as :func:`~tolins.mjcf.model.make_mjcf`'s. ``firm_grip``: the pads touch the handle
    alone, through contact pairs of :data:`FIRM_GRIP_IMPEDANCE` (:func:`grip_firmly`).
    ``elastic``: elastic-plastic pins, as :func:`~tolins.mjcf.model.make_mjcf`'s."""
    world = mujoco.MjSpec.from_string(make_mjcf(socket, board_body=board_body, elastic=elastic))
    workpiece = world.body("workpiece")
    for joint in list(workpiece.joints):
        world.delete(joint)
    for actuator in list(world.actuators):
        world.delete(actuator)
    workpiece.add_freejoint(name="workpiece")
    workpiece.add_geom(
        name="handle",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=HANDLE,
        pos=[0.0, 0.0, handle_centre_height()],
        contype=2,
        conaffinity=1,
        friction=GRIP_FRICTION,
    )
    workpiece.mass += HANDLE_MASS  # the body's explicit inertial: geoms add no mass to it
    world.option.gravity = GRAVITY
    # MuJoCo's default (dense rows for a world of this size): the arm's rows are dense, and
    # elastic-plastic pins' sparse ones (``make_mjcf``'s) cost 15 % more here.
    world.option.jacobian = mujoco.mjtJacobian.mjJAC_AUTO
    arm = panda_spec()
    arm.option.timestep = world.option.timestep
    for actuator in arm.actuators:  # the files' metadata for their own controllers
        actuator.userdata = []
    arm.nuser_actuator = -1
    for geom in arm.geoms:
        geom.contype, geom.conaffinity = 0, 0
    for finger in (arm.body("panda0_leftfinger"), arm.body("panda0_rightfinger")):
        add_pad(arm, finger)
    world.attach(arm, prefix=PREFIX, frame=world.worldbody.add_frame(pos=base))
    # The real gripper's fingers move as one (a rack on one motor): coupled, the part sits
    # midway between them instead of wherever the two fingers' pushes happen to balance.
    left, right = (PREFIX + name for name in FINGER_JOINTS)
    coupling = world.add_equality(
        type=mujoco.mjtEq.mjEQ_JOINT, name="fingers", name1=left, name2=right
    )
    coupling.data[:5] = [0.0, 1.0, 0.0, 0.0, 0.0]
    for name, kind in (
        (WRIST_FORCE, mujoco.mjtSensor.mjSENS_FORCE),
        (WRIST_TORQUE, mujoco.mjtSensor.mjSENS_TORQUE),
    ):
        world.add_sensor(
            name=name, type=kind, objtype=mujoco.mjtObj.mjOBJ_SITE, objname=PREFIX + FLANGE
        )
    if firm_grip:
        grip_firmly(world)
    return world


def grip_firmly(world: mujoco.MjSpec) -> None:
    """Make the finger pads of ``world`` touch the handle alone, each through an explicit
    contact pair with the pad's friction and stiffness and :data:`FIRM_GRIP_IMPEDANCE`."""
    slide, spin, roll = GRIP_FRICTION
    for side in ("left", "right"):
        pad = world.geom(f"{PREFIX}panda0_{side}finger_pad")
        pad.contype = pad.conaffinity = 0
        pair = world.add_pair(geomname1=pad.name, geomname2="handle", condim=3)
        pair.friction = [slide, slide, spin, roll, roll]
        pair.solref = pad.solref
        pair.solimp = [FIRM_GRIP_IMPEDANCE, FIRM_GRIP_IMPEDANCE, *pad.solimp[2:]]
        pair.margin = pair.gap = 0.0

"""``make_mjcf(spec)``: a socket spec as an MJCF model (units: mm, kg, s).

Model units: lengths in mm, so forces are in mN (kg·mm/s²) and torques in
µN·m = 1e-3 N·mm. The environment converts to N and N·mm.

Elements (every one named):

* ``board``: a static body (with ``board_body=False``: the world body) of convex pieces:
  ``hole{h}_wall{k}`` prisms (meshes ``wall{k}``) around each hole and ``board_box{i}``
  boxes elsewhere, then a ``plug{h}`` box filling each blocked hole ``h`` (flush with the
  top). Top at z = 0.
* ``workpiece``: the carriage, on joints ``x``, ``y``, ``z`` (slides) and ``theta``
  (hinge about z), driven by ``intvelocity`` servos ``ux``, ``uy``, ``uz``,
  ``utheta`` (control = velocity in mm/s or rad/s) with bounded force. The joints'
  ranges are the servo range of :mod:`tolins.geometry.workspace`, and the board covers
  every place a pin can reach within it. Its ``carrier`` plate above the pins collides
  with the board's top (at ``z = -PIN_LENGTH``, the lower end of the z range).
* ``pins``: a joint-free child of the carriage holding the pin geoms ``pin{i}``
  (tips at z = 0 in the workpiece frame), the sites ``pin{i}_tip`` and the
  force/torque site ``ft_site`` read by the sensors ``force`` and ``torque``, and per
  pin a box site ``pin{i}_zone`` read by the touch sensor ``pin{i}_touch`` (the summed
  normal force of that pin's contacts).
* ``<contact>`` (only with ``contact_pairs=True``): a ``<pair>`` of each pin with every
  board piece it can reach (:mod:`tolins.mjcf.contacts`); the pins then take no part in
  automatic collision.
"""

from __future__ import annotations

import math

import numpy as np

from tolins.geometry.delicate import ElasticPins
from tolins.geometry.specs import (
    CIRCLE_HOLE_SIDES,
    CircularSocket,
    PolygonSocket,
    SocketSpec,
    inradius,
    polygon_vertices,
)
from tolins.geometry.workspace import PIN_LENGTH, POSE_HIGH, POSE_LOW, reach
from tolins.mjcf.board import BOARD_MARGIN, board_boxes, hole_wall_pieces
from tolins.mjcf.contacts import pair_order, pin_reach_boxes, reachable
from tolins.mjcf.elastic_pins import elastic_pin_bodies
from tolins.mjcf.xml import num, nums
from tolins.paper import A_MAX

#: Physics step (s). A pin landing on a hole's edge sinks up to about one step's travel
#: (2.5 µm at 1 ms and full speed) before the contact holds it; where it overlaps a wall
#: piece by less than that, the contact resolves sideways and can ratchet it into the
#: hole. Measured on the 2*2 socket pushed down at 2.5 mm/s: with 2 ms steps (solref
#: 0.004) pins 7 µm beyond the clearance in x and 35 µm beyond it in rotation went in;
#: with 1 ms (solref 0.002) 2 µm and 2 µm (see docs/environments.md).
TIMESTEP = 0.001
#: The physics step of each tolerance grade, per family: ``(smallest radial clearance in
#: mm, step in s)`` rows, the first whose clearance the spec's nominal clearance reaches.
#: Capture beyond the clearance at 2.5 mm/s (``benchmarks/grades.py``, 2*2 socket): in x
#: about one step's travel, 2.0–2.4 µm at 1 ms, 1.0 µm at 0.5 ms, 0.2 µm at 0.25 ms; in
#: rotation at 1 ms it jumps with the clearance (2.9 µm at 200, 2.6 at 150, 7.0 at 110,
#: 2.4 at 100, 13.6 at 90, 8.4 at 50 µm: up to 17 % of it), at 0.5 ms 1.1–1.3 µm. So a
#: round-pin socket keeps 1 ms at the paper's 200 µm and up, 0.5 ms below, 0.25 ms below
#: 30 µm (0.5 ms: 5.0 % at 20 µm); polygon pegs keep 1 ms from 51 µm (the paper's hexagon,
#: 52 µm: rotation 0.2 µm) and take 0.25 ms below (at 0.5 ms the hexagon's rotation
#: capture is 2.3–2.4 µm: 5.8 % at 40 µm). Every paper preset keeps its 1 ms and its
#: bytes. Contact ``solref`` follows the step (:func:`contact_solref`).
GRADE_TIMESTEPS = {
    "circle": ((0.2 - 1e-9, TIMESTEP), (0.03, 0.0005), (0.0, 0.00025)),
    "polygon": ((0.051, TIMESTEP), (0.0, 0.00025)),
}
BOARD_THICKNESS = 3.0
#: Board (mm) beyond the farthest place a pin can reach.
BOARD_OVERHANG = 1.0
#: Width (mm) of a hole cell's wall ring when no neighbour limits it.
CELL_WALL = 1.0
#: Servo force limits in model units: 5 N on x, y, z; 0.02 N·m about z.
FORCE_LIMIT = 5000.0
TORQUE_LIMIT = 20000.0
#: Reflected robot inertia (armature): kg on the slides, kg·mm² on the hinge.
SLIDE_ARMATURE = 1.0
HINGE_ARMATURE = 1000.0
#: Servo stiffness (model units per mm or rad); damping is critical for the armature.
SLIDE_KP = 2.0e5
HINGE_KP = 2.0e8
#: Contact parameters (width in mm): stiff, nearly hard contacts with light friction.
SOLREF = "0.002 1"
SOLIMP = "0.99 0.999 0.01"
FRICTION = 0.3
#: Thickness (mm) of the carrier plate over the pins: a box on the pins' tops.
CARRIER_THICKNESS = 2.0
#: Colours (RGBA, 0–1) of the board, the pins and the half-transparent carrier.
BOARD_RGBA = (0.25, 0.45, 0.3, 1.0)
PIN_RGBA = (0.85, 0.7, 0.3, 1.0)
CARRIER_RGBA = (0.6, 0.6, 0.65, 0.5)


def physics_timestep(spec: SocketSpec) -> float:
    """The model's physics step (s) for ``spec``'s tolerance grade (:data:`GRADE_TIMESTEPS`,
    by the family and the nominal radial clearance); every preset of the paper keeps 1 ms."""
    clearance = spec.nominal().clearance if isinstance(spec, CircularSocket) else spec.clearance
    return next(step for minimum, step in GRADE_TIMESTEPS[spec.family] if clearance >= minimum)


def contact_solref(timestep: float) -> str:
    """Contact ``solref``: a time constant of two physics steps, critically damped
    (:data:`SOLREF` at the 1 ms step)."""
    return SOLREF if timestep == TIMESTEP else f"{num(2 * timestep)} 1"


def cell_half_width(spec: SocketSpec) -> float:
    """Half-width (mm) of the square board cell around each hole."""
    if isinstance(spec, PolygonSocket):
        return spec.hole_circumradius + CELL_WALL
    limits = [spec.hole_circumradius + CELL_WALL]
    if spec.rows > 1:
        limits.append(spec.row_pitch / 2)
    if spec.cols > 1:
        limits.append(spec.col_pitch / 2)
    return min(limits)


def board_margin(spec: SocketSpec) -> float:
    """Board (mm) beyond the outermost hole cells: enough to hold every pin over the board
    anywhere in the servo range."""
    cells = np.max(np.abs(spec.hole_centers), axis=0) + cell_half_width(spec)
    return max(BOARD_MARGIN, float(np.max(reach(spec) - cells)) + BOARD_OVERHANG)


def board_filler_boxes(spec: SocketSpec) -> list[tuple[np.ndarray, np.ndarray]]:
    """The board's boxes ``(center_xy, half_size_xy)`` outside the hole cells."""
    return board_boxes(spec.hole_centers, cell_half_width(spec), board_margin(spec))


def scene_extent(spec: SocketSpec) -> float:
    """Half-size (mm) of the scene around the board (the model's ``<statistic extent>``)."""
    return float(np.max(np.abs(spec.hole_centers))) + cell_half_width(spec) + board_margin(spec)


def hole_shape(spec: SocketSpec) -> tuple[int, float]:
    """Sides and circumradius of the polygon that models each hole."""
    if isinstance(spec, CircularSocket):
        return CIRCLE_HOLE_SIDES, spec.hole_circumradius
    return spec.sides, spec.hole_circumradius


def carrier_half_size(spec: SocketSpec) -> np.ndarray:
    """Horizontal half-size ``(2,)`` (mm) of the workpiece's carrier plate over the pins."""
    return np.max(np.abs(spec.pin_centers), axis=0) + spec.pin_reach + 1.0


def _prism_vertices(outline: np.ndarray, z_top: float, z_bottom: float) -> str:
    top = np.column_stack([outline, np.full(len(outline), z_top)])
    bottom = np.column_stack([outline, np.full(len(outline), z_bottom)])
    return nums(np.concatenate([top, bottom]).ravel())


def _board_xml(spec: SocketSpec, board_body: bool) -> tuple[list[str], list[str]]:
    sides, circumradius = hole_shape(spec)
    half_width = cell_half_width(spec)
    pieces = hole_wall_pieces(sides, circumradius, half_width)
    assets = [
        f'<mesh name="wall{k}" vertex="{_prism_vertices(p, 0.0, -BOARD_THICKNESS)}"/>'
        for k, p in enumerate(pieces)
    ]
    body = ['<body name="board">'] if board_body else []
    for h, (cx, cy) in enumerate(spec.hole_centers):
        body += [
            f'<geom name="hole{h}_wall{k}" class="board" type="mesh" mesh="wall{k}" '
            f'pos="{nums((cx, cy, 0.0))}"/>'
            for k in range(sides)
        ]
    for i, (center, half) in enumerate(board_filler_boxes(spec)):
        body.append(
            f'<geom name="board_box{i}" class="board" type="box" '
            f'pos="{nums((*center, -BOARD_THICKNESS / 2))}" '
            f'size="{nums((*half, BOARD_THICKNESS / 2))}"/>'
        )
    body += [
        f'<geom name="plug{h}" class="board" type="box" '
        f'pos="{nums((*center, -BOARD_THICKNESS / 2))}" '
        f'size="{nums((*half, BOARD_THICKNESS / 2))}"/>'
        for h, center, half in _plugs(spec)
    ]
    if board_body:
        body.append("</body>")
    return assets, body


def _plugs(spec: SocketSpec) -> list[tuple[int, np.ndarray, np.ndarray]]:
    """``(hole, center_xy, half_size_xy)`` of the box plugging each blocked hole: a square
    of half-width ``hole_radius``, which covers the hole's 16-gon (its vertices nearest an
    axis lie on the square) and stays inside its cell."""
    if not isinstance(spec, CircularSocket) or not spec.blocked_holes:
        return []
    half = np.full(2, spec.hole_radius)
    return [(h, spec.hole_centers[h], half) for h in spec.blocked_holes]


def _board_pieces(spec: SocketSpec) -> list[tuple[str, str, np.ndarray]]:
    """``(name, geom type, [[x_lo, y_lo], [x_hi, y_hi]])`` of every board geom, in model order."""
    sides, circumradius = hole_shape(spec)
    outlines = hole_wall_pieces(sides, circumradius, cell_half_width(spec))
    pieces = [
        (f"hole{h}_wall{k}", "mesh", np.array([p.min(axis=0), p.max(axis=0)]) + center)
        for h, center in enumerate(spec.hole_centers)
        for k, p in enumerate(outlines)
    ]
    for i, (center, half) in enumerate(board_filler_boxes(spec)):
        pieces.append((f"board_box{i}", "box", np.array([center - half, center + half])))
    for h, center, half in _plugs(spec):
        pieces.append((f"plug{h}", "box", np.array([center - half, center + half])))
    return pieces


def _pin_type(spec: SocketSpec) -> str:
    if isinstance(spec, CircularSocket):
        return "cylinder"
    return "box" if spec.sides == 4 else "mesh"


def _contact_pairs(spec: SocketSpec) -> list[str]:
    """The ``<pair>``s of every pin with every board piece it can reach
    (:mod:`tolins.mjcf.contacts`); the same for every spec of one family layout."""
    pieces = _board_pieces(spec)
    pins = [(pin_geom_name(i), _pin_type(spec)) for i in range(spec.n_pins)]
    mask = reachable(pin_reach_boxes(spec), np.array([box for _, _, box in pieces]))
    # Geom ids: the board's pieces, the carrier, then the pins.
    order = pair_order(pins, [(name, kind) for name, kind, _ in pieces], mask, len(pieces) + 1)
    return [f'<pair geom1="{board}" geom2="{pin}"/>' for board, pin in order]


def _pin_geoms(spec: SocketSpec) -> tuple[list[str], list[str]]:
    """Mesh assets and geoms of the pins, tips at z = 0 of the workpiece frame."""
    half = PIN_LENGTH / 2
    if isinstance(spec, CircularSocket):
        # A short pin lacks its tip: it spans z = shortening … PIN_LENGTH.
        levels = spec.shortenings
        geoms = [
            f'<geom name="{pin_geom_name(i)}" class="pin" type="cylinder" '
            f'pos="{nums((x, y, half + levels[i] / 2))}" '
            f'size="{nums((radius, half - levels[i] / 2))}"/>'
            for i, ((x, y), radius) in enumerate(zip(spec.pin_centers, spec.pin_radii, strict=True))
        ]
        return [], geoms
    if spec.sides == 4:
        side_half = inradius(4, spec.pin_circumradius)
        geom = (
            f'<geom name="{pin_geom_name(0)}" class="pin" type="box" pos="{nums((0, 0, half))}" '
            f'size="{nums((side_half, side_half, half))}"/>'
        )
        return [], [geom]
    outline = polygon_vertices(spec.sides, spec.pin_circumradius)
    asset = f'<mesh name="peg" vertex="{_prism_vertices(outline, PIN_LENGTH, 0.0)}"/>'
    return [asset], [f'<geom name="{pin_geom_name(0)}" class="pin" type="mesh" mesh="peg"/>']


def _zone_size(spec: SocketSpec) -> str:
    """Half-sizes of each pin's touch zone: around the pin, never overlapping a neighbour's."""
    centers = spec.pin_centers
    gaps = np.max(np.abs(centers[:, None] - centers[None]), axis=2)
    gaps[np.diag_indices(len(centers))] = np.inf
    reach = min(
        spec.pin_reach + 0.2, float(gaps.min()) / 2
    )  # zones of neighbouring pins never overlap
    return nums((reach, reach, PIN_LENGTH / 2 + 0.2))


def _pin_sites(spec: SocketSpec) -> tuple[list[str], list[str]]:
    """Per pin: a tip site, and a box zone around the pin read by a touch sensor (N summed
    over the pin's contacts, without cancellation)."""
    zone = _zone_size(spec)
    sites, sensors = [], []
    levels = spec.shortenings if isinstance(spec, CircularSocket) else np.zeros(1)
    for i, (x, y) in enumerate(spec.pin_centers):
        sites.append(f'<site name="pin{i}_tip" pos="{nums((x, y, levels[i]))}" size="0.05"/>')
        sites.append(
            f'<site name="pin{i}_zone" type="box" pos="{nums((x, y, PIN_LENGTH / 2))}" '
            f'size="{zone}" rgba="0 0 0 0"/>'
        )
        sensors.append(f'<touch name="{touch_sensor_name(i)}" site="pin{i}_zone"/>')
    return sites, sensors


#: The workpiece's joints in the order of the pose ``[x, y, theta, z]``.
POSE_JOINTS = ("x", "y", "theta", "z")
#: Joint name -> index in the pose ``[x, y, theta, z]``.
_POSE_INDEX = {joint: i for i, joint in enumerate(POSE_JOINTS)}
#: The force and torque sensors at ``ft_site`` (workpiece axes).
FORCE_SENSOR = "force"
TORQUE_SENSOR = "torque"


def pin_geom_name(pin: int) -> str:
    """Name of pin ``pin``'s geom."""
    return f"pin{pin}"


def touch_sensor_name(pin: int) -> str:
    """Name of the touch sensor that sums pin ``pin``'s normal contact force."""
    return f"pin{pin}_touch"


def _range(joint: str) -> str:
    """The joint's range: the servo range of :mod:`tolins.geometry.workspace`."""
    i = _POSE_INDEX[joint]
    return nums((POSE_LOW[i], POSE_HIGH[i]))


def _joint(joint: str, kind: str, axis: str, armature: float) -> str:
    return (
        f'<joint name="{joint}" type="{kind}" axis="{axis}" armature="{num(armature)}" '
        f'range="{_range(joint)}"/>'
    )


def _servo(name: str, joint: str, kp: float, inertia: float, limit: float, speed: float) -> str:
    """An integrated-velocity servo: control = velocity within ±speed, force within ±limit,
    set-point within the joint's range."""
    kv = 2 * math.sqrt(kp * inertia)
    return (
        f'<intvelocity name="{name}" joint="{joint}" kp="{num(kp)}" kv="{num(kv)}" '
        f'ctrlrange="{nums((-speed, speed))}" forcerange="{nums((-limit, limit))}" '
        f'actrange="{_range(joint)}"/>'
    )


def make_mjcf(
    spec: SocketSpec,
    *,
    contact_pairs: bool = False,
    board_body: bool = True,
    elastic: ElasticPins | None = None,
) -> str:
    """The MJCF model of ``spec``'s board and workpiece. Same spec, same bytes.

    ``board_body``: the board's pieces in a static body ``board`` (the default);
    ``False`` puts them in the world body, where MuJoCo's broadphase no longer recomputes
    the board's bounding box and covariance from every piece in every step (most of a
    free-flight step: 1.6× on the 2*2, 2.4× on the 2*20, ``benchmarks/README.md``). Not
    the default: the world body is paired with the workpiece in every step, so a contact
    at exactly zero distance that the broadphase skipped is found (the carrier resting on
    the board at the servo's lower end), which moved a pose by 4e-15 mm.

    ``contact_pairs``: the pins collide through explicit ``<pair>``s with the board
    pieces they can reach instead of MuJoCo's bounding-volume trees (the default). Both
    simulate the same contacts and trajectories bit for bit; the pairs are cheaper only
    while pins are pressed on the board and dearer everywhere else, because every pair is
    tested every step (``benchmarks/README.md``, "A cheaper contact step"), so they are
    not the default.

    ``elastic``: the round pins bend and stay bent (``pins="elastic-plastic"``): each pin its
    own body on two root hinges held by calibrated joint equalities
    (:mod:`tolins.mjcf.elastic_pins`); ``None`` (the default): rigid pins, the bytes as
    before.
    """
    if not isinstance(spec, (CircularSocket, PolygonSocket)):
        raise ValueError(f"spec={spec!r} is not a socket; allowed: CircularSocket, PolygonSocket")
    if elastic is not None and not isinstance(spec, CircularSocket):
        raise ValueError("elastic pins are round pins; allowed: a CircularSocket")
    board_assets, board_geoms = _board_xml(spec, board_body)
    pin_assets, pin_geoms = _pin_geoms(spec)
    pin_sites, touch_sensors = _pin_sites(spec)
    pairs = _contact_pairs(spec) if contact_pairs else []
    timestep = physics_timestep(spec)
    equalities: list[str] = []
    if elastic is not None:
        pin_geoms, equalities = elastic_pin_bodies(spec, elastic, timestep, _zone_size(spec))
        pin_sites = []
    solref = contact_solref(timestep)
    # A pin's hinges share constraint rows with nothing but the workpiece's four joints:
    # sparse rows solve its contacts and equalities in half the time of dense ones.
    jacobian = ' jacobian="sparse"' if elastic is not None else ""
    # With pairs, the pins take no part in automatic collision; a pair's contact
    # parameters are what the two geoms' defaults mix to (friction: the larger of each).
    pin_bits = 'contype="0" conaffinity="0"' if contact_pairs else 'contype="2" conaffinity="1"'
    pair_default = (
        [
            f'<pair condim="3" friction="{nums((FRICTION, FRICTION, 0.005, 0.0001, 0.0001))}" '
            f'solref="{solref}" solimp="{SOLIMP}" margin="0" gap="0"/>'
        ]
        if contact_pairs
        else []
    )
    extent = scene_extent(spec)
    carrier = carrier_half_size(spec)
    carrier_z = PIN_LENGTH + CARRIER_THICKNESS / 2  # the carrier's centre, over the pins
    slide_mass = SLIDE_ARMATURE + 0.1
    lines = [
        f'<mujoco model="tolins_{spec.family}">',
        '<compiler angle="radian" autolimits="true"/>',
        f'<option timestep="{num(timestep)}" integrator="implicitfast" solver="Newton" '
        f'tolerance="1e-10" cone="elliptic" gravity="0 0 0"{jacobian}>',
        '<flag multiccd="disable"/>',
        "</option>",
        f'<statistic center="0 0 2" extent="{num(extent)}"/>',
        '<visual><global offwidth="1280" offheight="960"/>'
        '<headlight ambient="0.35 0.35 0.35" diffuse="0.5 0.5 0.5"/></visual>',
        "<default>",
        f'<geom solref="{solref}" solimp="{SOLIMP}" friction="{num(FRICTION)} 0.005 0.0001" '
        'condim="3" margin="0" gap="0"/>',
        *pair_default,
        '<default class="board">',
        f'<geom contype="1" conaffinity="2" rgba="{nums(BOARD_RGBA)}"/>',
        "</default>",
        '<default class="pin">',
        f'<geom {pin_bits} rgba="{nums(PIN_RGBA)}"/>',
        "</default>",
        "</default>",
        "<asset>",
        *board_assets,
        *pin_assets,
        "</asset>",
        "<worldbody>",
        '<light name="key" pos="0 -30 60" dir="0 0.5 -1" directional="true"/>',
        f'<camera name="overview" pos="{nums((0, -1.6 * extent, 1.1 * extent))}" '
        'xyaxes="1 0 0 0 0.6 0.8"/>',
        *board_geoms,
        '<body name="workpiece">',
        _joint("x", "slide", "1 0 0", SLIDE_ARMATURE),
        _joint("y", "slide", "0 1 0", SLIDE_ARMATURE),
        _joint("z", "slide", "0 0 1", SLIDE_ARMATURE),
        _joint("theta", "hinge", "0 0 1", HINGE_ARMATURE),
        f'<inertial pos="0 0 {num(carrier_z)}" mass="0.1" diaginertia="10 10 10"/>',
        f'<geom name="carrier" type="box" pos="0 0 {num(carrier_z)}" '
        f'size="{nums((*carrier, CARRIER_THICKNESS / 2))}" contype="2" conaffinity="1" '
        f'rgba="{nums(CARRIER_RGBA)}"/>',
        '<body name="pins">',
        '<inertial pos="0 0 0" mass="0.001" diaginertia="0.001 0.001 0.001"/>',
        '<site name="ft_site" pos="0 0 0" size="0.1"/>',
        *pin_geoms,
        *pin_sites,
        "</body>",
        "</body>",
        "</worldbody>",
        *(["<contact>", *pairs, "</contact>"] if pairs else []),
        *equalities,
        "<actuator>",
        _servo("ux", "x", SLIDE_KP, slide_mass, FORCE_LIMIT, A_MAX[0]),
        _servo("uy", "y", SLIDE_KP, slide_mass, FORCE_LIMIT, A_MAX[1]),
        _servo("uz", "z", SLIDE_KP, slide_mass, FORCE_LIMIT, A_MAX[3]),
        _servo("utheta", "theta", HINGE_KP, HINGE_ARMATURE, TORQUE_LIMIT, A_MAX[2]),
        "</actuator>",
        "<sensor>",
        f'<force name="{FORCE_SENSOR}" site="ft_site"/>',
        f'<torque name="{TORQUE_SENSOR}" site="ft_site"/>',
        *touch_sensors,
        "</sensor>",
        "</mujoco>",
    ]
    return "\n".join(lines) + "\n"

"""Where the workpiece may be: the servos' range, valid poses and goals, and success.

Shared by both backends and both APIs, so they agree on what a valid pose is and on
what counts as an insertion. A pose is ``[x, y, theta, z]``: pins rotated by ``theta``
about the board's origin, then moved by ``(x, y)``; ``z`` is the height of the pin tips
over the board's top (``z = 0``).
"""

from __future__ import annotations

import math

import numpy as np

from tolins.geometry.specs import SocketSpec
from tolins.geometry.tolerance import contains, moved_pins
from tolins.geometry.validation import checked_array

#: Servo range of x and y (mm): ``|x|, |y| ≤ XY_RANGE`` about the board's origin. The
#: initial poses lie within 3 mm of the goal, goals within 2 mm of the nominal one.
XY_RANGE = 5.0
#: Servo range of theta (rad): ``|theta| ≤ THETA_RANGE``.
THETA_RANGE = 0.3
#: Length of the pins (mm): the carrier plate above them meets the board's top when the
#: pin tips are at ``z = -PIN_LENGTH``, the servo's lower end.
PIN_LENGTH = 4.0
#: Upper end of the z servo (mm of the pin tips over the board).
Z_MAX = 40.0
#: Largest goal offset from the nominal pose ``[0, 0, 0]`` (mm, mm, rad).
GOAL_RANGE = np.array([2.0, 2.0, 0.15])

POSE_LOW = np.array([-XY_RANGE, -XY_RANGE, -THETA_RANGE, -PIN_LENGTH])
POSE_HIGH = np.array([XY_RANGE, XY_RANGE, THETA_RANGE, Z_MAX])


def pin_axes(spec: SocketSpec, poses: object) -> np.ndarray:
    """World ``(x, y)`` of every pin's axis ``(..., n_pins, 2)`` for poses ``[..., >= 3]``."""
    return moved_pins(spec.pin_centers, np.asarray(poses, dtype=float))


def reach(spec: SocketSpec) -> np.ndarray:
    """Half-size ``(2,)`` (mm) of the box about the origin that every pin (bent ones where
    they are) stays inside over the servo range (the board covers it)."""
    pins = np.abs(spec.pin_centers)
    sin = math.sin(THETA_RANGE)
    # |R(theta) p|_x ≤ |p_x| + |p_y| sin(theta) for |theta| ≤ THETA_RANGE < π/2, and alike in y.
    moved = np.max(pins + pins[:, ::-1] * sin, axis=0)
    return moved + XY_RANGE + spec.pin_reach


def in_holes(spec: SocketSpec, poses: object, depth: float) -> np.ndarray:
    """Success: whether every pin is inside its own hole, ``depth`` (mm) below the top.

    Pin ``i`` is in when the pin tips are at ``z ≤ -depth`` and its axis lies within the
    circumradius of hole ``i`` (holes are further apart than two circumradii, so no pin
    can count in another's hole, nor beside the board). ``poses`` ``[..., 4]``. Never with a
    blocked hole (``blocked_holes``).
    """
    poses = np.asarray(poses, dtype=float)
    deep = poses[..., 3] <= -depth
    if getattr(spec, "blocked_holes", ()) or not deep.any():  # most steps: above the depth
        return np.zeros(poses.shape[:-1], dtype=bool)
    offsets = pin_axes(spec, poses) - spec.hole_centers
    inside = np.sum(offsets * offsets, axis=-1) <= spec.hole_circumradius**2
    return deep & np.all(inside, axis=-1)


def check_pose(spec: SocketSpec, pose: object, name: str = "pose") -> np.ndarray:
    """``pose`` ``[x, y, theta, z]`` as floats, if the servos can hold it and no pin is inside
    the board; else ``ValueError`` naming the pose and what is allowed."""
    pose = checked_array(name, pose, (4,), "[x, y, theta, z] in mm and rad")
    low, high = POSE_LOW, POSE_HIGH
    if np.any(pose < low) or np.any(pose > high):
        raise ValueError(
            f"{name}={pose.tolist()!r} is beyond the servo range; allowed: "
            f"|x|, |y| ≤ {XY_RANGE} mm, |theta| ≤ {THETA_RANGE} rad, "
            f"{-PIN_LENGTH} ≤ z ≤ {Z_MAX} mm"
        )
    if pose[3] < 0 and not contains(spec, pose[:3]):
        raise ValueError(
            f"{name}={pose.tolist()!r} puts a pin inside the board; allowed: z ≥ 0, or "
            "z < 0 with [x, y, theta] in the tolerance (every pin in its hole)"
        )
    return pose


def check_goal(goal: object, name: str = "goal") -> np.ndarray:
    """``goal`` ``[x*, y*, theta*]`` as floats, if within :data:`GOAL_RANGE` of the nominal."""
    goal = checked_array(name, goal, (3,), "[x*, y*, theta*] in mm and rad")
    if np.any(np.abs(goal) > GOAL_RANGE):
        raise ValueError(
            f"{name}={goal.tolist()!r} is too far from the nominal goal; allowed: "
            f"|x*|, |y*| ≤ {GOAL_RANGE[0]} mm, |theta*| ≤ {GOAL_RANGE[2]} rad"
        )
    return goal

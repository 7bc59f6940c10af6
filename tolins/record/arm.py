"""The robot in a recording: its links' meshes once per episode, their poses every step.

A robot's world (:func:`tolins.mjcf.panda.panda_world`) carries two meshes per link: the
visual one (6,000–12,000 vertices) and a coarse one (about 150). The recording draws the
coarse ones and the fingers (about 1,500 vertices in all), each under its link's entity,
whose transform is logged every control step from the simulation's data, and the handle
the fingers hold, on the workpiece.

The fingers are drawn in their file's proportions: the model files stretch the Franka's
finger mesh 1.75 times along the finger and along the pads (``scale='1.75 1.0 1.75'``), a
visual mesh that touches nothing and would reach 50 mm below the grip site, 34 mm below
the pins' tips: through the board. Unstretched, each finger ends where its pad (what
holds the handle) ends, as a Franka's does.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
import rerun as rr

from tolins.mjcf.panda import FLANGE, PREFIX
from tolins.record.geometry import TriangleMesh
from tolins.record.scene import shaded_mesh

ARM_COLOR = (235, 235, 240)
HANDLE_COLOR = (95, 110, 140)
#: MuJoCo's geom group of the model files' coarse meshes.
COARSE_GROUP = 3
#: The geom of the workpiece's handle in a robot's world.
HANDLE_GEOM = "handle"


@dataclass(frozen=True)
class ArmPiece:
    """One mesh of a link: its vertices and triangles in the mesh's frame, and where the
    mesh sits in its link's frame (``position``, ``quaternion`` as ``xyzw``)."""

    link: str
    vertices: np.ndarray
    triangles: np.ndarray
    position: np.ndarray
    quaternion: np.ndarray


@dataclass(frozen=True)
class ArmDrawing:
    """What a recording draws of a robot's world: the pieces, the links' body ids in the
    order of their names, the flange site (the wrist sensor's), and the handle the
    fingers hold (its centre, half sizes and ``xyzw`` rotation in the workpiece's frame,
    mm), if any."""

    pieces: tuple[ArmPiece, ...]
    links: tuple[str, ...]
    bodies: np.ndarray
    flange: int
    handle: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None

    def poses(self, data: mujoco.MjData) -> np.ndarray:
        """The links' world poses now, ``(links, 7)``: position (mm) and ``xyzw``."""
        wxyz = data.xquat[self.bodies]
        return np.column_stack([data.xpos[self.bodies], wxyz[:, 1:], wxyz[:, :1]])

    def flange_position(self, data: mujoco.MjData) -> np.ndarray:
        return data.site_xpos[self.flange].copy()


def _link(model: mujoco.MjModel, geom: int) -> str:
    return model.body(model.geom_bodyid[geom]).name


def _rotation(quaternion_wxyz: np.ndarray) -> np.ndarray:
    matrix = np.zeros(9)
    mujoco.mju_quat2Mat(matrix, quaternion_wxyz)
    return matrix.reshape(3, 3)


def _in_file_proportions(
    model: mujoco.MjModel, geom: int, vertices: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``geom``'s mesh ``vertices`` in its link's frame, scaled back to the proportions of
    its file where the model scales the file unequally along its axes (the fingers: the
    link's axes are the file's, about the link's origin); returned with the identity pose
    (position, ``xyzw``)."""
    in_link = vertices @ _rotation(model.geom_quat[geom]).T + model.geom_pos[geom]
    scale = model.mesh_scale[model.geom_dataid[geom]]
    return in_link / (scale / scale.min()), np.zeros(3), np.array([0.0, 0.0, 0.0, 1.0])


def _handle(model: mujoco.MjModel) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    geom = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, HANDLE_GEOM)
    if geom < 0 or model.geom_type[geom] != mujoco.mjtGeom.mjGEOM_BOX:
        return None
    w, x, y, z = model.geom_quat[geom]
    return model.geom_pos[geom].copy(), model.geom_size[geom].copy(), np.array([x, y, z, w])


def arm_drawing(model: mujoco.MjModel) -> ArmDrawing | None:
    """The drawing of ``model``'s robot, or ``None`` for a model without one."""
    pieces = []
    for geom in range(model.ngeom):
        link = _link(model, geom)
        is_mesh = model.geom_type[geom] == mujoco.mjtGeom.mjGEOM_MESH
        if not (link.startswith(PREFIX) and is_mesh):
            continue
        if model.geom_group[geom] != COARSE_GROUP and not link.endswith("finger"):
            continue
        mesh = model.geom_dataid[geom]
        start, count = model.mesh_vertadr[mesh], model.mesh_vertnum[mesh]
        first, faces = model.mesh_faceadr[mesh], model.mesh_facenum[mesh]
        vertices = model.mesh_vert[start : start + count].copy()
        triangles = model.mesh_face[first : first + faces].copy()
        w, x, y, z = model.geom_quat[geom]
        position, quaternion = model.geom_pos[geom].copy(), np.array([x, y, z, w])
        if np.ptp(model.mesh_scale[mesh]) > 0:
            vertices, position, quaternion = _in_file_proportions(model, geom, vertices)
        corners = vertices[triangles]
        edges = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        area = np.linalg.norm(edges, axis=1)
        pieces.append(
            ArmPiece(
                link=link.removeprefix(PREFIX),
                vertices=vertices,
                triangles=triangles[area > 0],  # a degenerate face has no normal
                position=position,
                quaternion=quaternion,
            )
        )
    if not pieces:
        return None
    links = tuple(dict.fromkeys(piece.link for piece in pieces))
    bodies = np.array([model.body(PREFIX + link).id for link in links])
    flange = model.site(PREFIX + FLANGE).id
    return ArmDrawing(tuple(pieces), links, bodies, flange, _handle(model))


def log_arm(stream: rr.RecordingStream, root: str, drawing: ArmDrawing) -> None:
    """Log the arm's meshes, static, under ``root/{link}/mesh_{i}``."""
    for i, piece in enumerate(drawing.pieces):
        path = f"{root}/{piece.link}/mesh_{i}"
        stream.log(
            path,
            rr.Transform3D(
                translation=piece.position, quaternion=rr.Quaternion(xyzw=piece.quaternion)
            ),
            shaded_mesh(TriangleMesh(piece.vertices, piece.triangles), ARM_COLOR),
            static=True,
        )


def log_handle(stream: rr.RecordingStream, path: str, drawing: ArmDrawing) -> None:
    """The handle the fingers hold, static, at ``path`` (an entity under the workpiece)."""
    if drawing.handle is not None:
        centre, half_size, quaternion = drawing.handle
        stream.log(
            path,
            rr.Boxes3D(
                centers=[centre],
                half_sizes=[half_size],
                quaternions=[rr.Quaternion(xyzw=quaternion)],
                colors=HANDLE_COLOR,
                fill_mode="solid",
            ),
            static=True,
        )

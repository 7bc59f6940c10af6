"""The robot in a recording: its links' meshes once per episode, their poses every step.

A robot's world (:func:`tolins.mjcf.panda.panda_world`) carries two meshes per link: the
visual one (6,000–12,000 vertices) and a coarse one (about 150). The recording draws the
coarse ones and the fingers (about 1,500 vertices in all), each under its link's entity,
whose transform is logged every control step from the simulation's data.
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
#: MuJoCo's geom group of the model files' coarse meshes.
COARSE_GROUP = 3


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
    order of their names, and the flange site (the wrist sensor's)."""

    pieces: tuple[ArmPiece, ...]
    links: tuple[str, ...]
    bodies: np.ndarray
    flange: int

    def poses(self, data: mujoco.MjData) -> np.ndarray:
        """The links' world poses now, ``(links, 7)``: position (mm) and ``xyzw``."""
        wxyz = data.xquat[self.bodies]
        return np.column_stack([data.xpos[self.bodies], wxyz[:, 1:], wxyz[:, :1]])

    def flange_position(self, data: mujoco.MjData) -> np.ndarray:
        return data.site_xpos[self.flange].copy()


def _link(model: mujoco.MjModel, geom: int) -> str:
    return model.body(model.geom_bodyid[geom]).name


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
        corners = vertices[triangles]
        edges = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
        area = np.linalg.norm(edges, axis=1)
        w, x, y, z = model.geom_quat[geom]
        pieces.append(
            ArmPiece(
                link=link.removeprefix(PREFIX),
                vertices=vertices,
                triangles=triangles[area > 0],  # a degenerate face has no normal
                position=model.geom_pos[geom].copy(),
                quaternion=np.array([x, y, z, w]),
            )
        )
    if not pieces:
        return None
    links = tuple(dict.fromkeys(piece.link for piece in pieces))
    bodies = np.array([model.body(PREFIX + link).id for link in links])
    return ArmDrawing(tuple(pieces), links, bodies, model.site(PREFIX + FLANGE).id)


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

"""A socket as a file other tools open: a mesh (STL, GLB) or its MJCF model.

* ``.stl``: the bodies of :func:`tolins.mjcf.mesh.socket_parts` as one binary STL, in mm
  (what slicers assume) with z up; each body is closed, a blocked hole is solid board.
* ``.glb``: a glTF scene of one named, coloured node per body (``board``, ``plug{h}``,
  ``pin{i}``, ``carrier``), in metres with y up, as glTF defines them.
* ``.xml``: :func:`tolins.mjcf.make_mjcf`'s bytes, unchanged.
"""

from __future__ import annotations

import numpy as np
import trimesh
from trimesh.visual.material import PBRMaterial

from tolins.geometry.specs import SocketSpec
from tolins.mjcf.mesh import Part, socket_parts
from tolins.mjcf.model import make_mjcf

EXPORT_SUFFIXES = (".stl", ".glb", ".xml")
#: glTF's frame from tolins's: mm to metres, and z up to y up (x stays, y becomes -z).
GLTF_FROM_TOLINS = np.array(
    [
        [1e-3, 0.0, 0.0, 0.0],
        [0.0, 0.0, 1e-3, 0.0],
        [0.0, -1e-3, 0.0, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ]
)


def _suffix(suffix: str) -> str:
    suffix = suffix.lower()
    if suffix not in EXPORT_SUFFIXES:
        raise ValueError(f"file type {suffix!r}; allowed: {', '.join(EXPORT_SUFFIXES)}")
    return suffix


def stl_bytes(parts: list[Part]) -> bytes:
    """``parts`` as one binary STL (mm)."""
    return trimesh.util.concatenate([p.mesh for p in parts]).export(file_type="stl")


def gltf_scene(parts: list[Part]) -> trimesh.Scene:
    """``parts`` as a scene of named, coloured nodes in glTF's frame (:data:`GLTF_FROM_TOLINS`)."""
    scene = trimesh.Scene()
    for part in parts:
        mesh = part.mesh.copy()
        mesh.apply_transform(GLTF_FROM_TOLINS)
        mesh.visual = trimesh.visual.TextureVisuals(
            material=PBRMaterial(
                name=part.name,
                baseColorFactor=[round(255 * c) for c in part.rgba],
                metallicFactor=0.0,
                roughnessFactor=0.8,
                alphaMode="BLEND" if part.rgba[3] < 1 else "OPAQUE",
            )
        )
        scene.add_geometry(mesh, node_name=part.name, geom_name=part.name)
    return scene


def export_bytes(spec: SocketSpec, suffix: str, part: str = "all") -> bytes:
    """``spec`` as the contents of a file ending in ``suffix`` (:data:`EXPORT_SUFFIXES`);
    ``part``: ``all``, ``board`` or ``workpiece`` (:func:`tolins.mjcf.mesh.socket_parts`),
    for a mesh only.

    Raises ``ValueError`` (one line) for another suffix or part, or a part with ``.xml``.
    """
    suffix = _suffix(suffix)
    if suffix == ".xml":
        if part != "all":
            raise ValueError(f"part={part!r} with .xml; allowed: all (the model holds both)")
        return make_mjcf(spec).encode()
    if suffix == ".stl":
        return stl_bytes(socket_parts(spec, part))
    return gltf_scene(socket_parts(spec, part, plugs_apart=True)).export(file_type="glb")

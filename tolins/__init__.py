"""tolins: a contact-physics benchmark for delicate industrial insertion.

Importing tolins registers its environments with gymnasium (``tolins/...-v1``).
"""

import os
from importlib.metadata import PackageNotFoundError, version

# Headless rendering: MuJoCo reads MUJOCO_GL when it is first imported.
if "MUJOCO_GL" not in os.environ and not os.environ.get("DISPLAY"):
    os.environ["MUJOCO_GL"] = "egl"


from tolins import tolerance
from tolins.envs import make_vec, register_envs
from tolins.geometry import CircularSocket, PolygonSocket, sample_defects
from tolins.mjcf import make_mjcf

try:
    __version__ = version("tolins")
except PackageNotFoundError:  # running from a source tree that is not installed
    __version__ = "0.0.0"

register_envs()


def __getattr__(name: str) -> object:
    # tolins.embedding needs torch: import it on first use, not with tolins.
    if name == "embedding":
        import importlib

        return importlib.import_module("tolins.embedding")
    raise AttributeError(f"module 'tolins' has no attribute {name!r}")


__all__ = [
    "CircularSocket",
    "PolygonSocket",
    "__version__",
    "make_mjcf",
    "make_vec",
    "sample_defects",
    "tolerance",
]

"""Import flow: geometry depends on nothing of tolins, mjcf not on the envs or policies,
and no layer (envs, learning, inference) on the ones above it or on record, dmc, the cli.

``import tolins.x`` runs ``tolins/__init__.py`` first, which registers the environments and
so imports everything. Each check therefore runs in a fresh interpreter that stands in an
empty ``tolins`` package (same ``__path__``, no ``__init__`` code) before importing the
subpackage, then reports which ``tolins`` modules got loaded.
"""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

_PROBE = """
import importlib.util, json, sys, types
if {bare}:
    spec = importlib.util.find_spec("tolins")
    package = types.ModuleType("tolins")
    package.__path__ = list(spec.submodule_search_locations)
    sys.modules["tolins"] = package
import {module}
prefixes = ("tolins.", "mujoco", "gymnasium", "torch")
names = [name for name in sys.modules if name == "tolins" or name.startswith(prefixes)]
print(json.dumps(sorted(names)))
"""


def _loaded(module: str, *, bare: bool = True) -> set[str]:
    """Names of tolins (and mujoco, gymnasium, torch) modules loaded by importing ``module``."""
    result = subprocess.run(
        [sys.executable, "-c", _PROBE.format(module=module, bare=bare)],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    return set(json.loads(result.stdout.strip().splitlines()[-1]))


def _tolins(names: set[str]) -> set[str]:
    return {name for name in names if name == "tolins" or name.startswith("tolins.")}


def test_probe_sees_what_a_plain_import_loads() -> None:
    """Sanity check of the probe: the real package pulls in the envs and mujoco."""
    loaded = _loaded("tolins", bare=False)
    assert {"tolins.envs", "tolins.geometry", "tolins.mjcf"} <= loaded
    assert "mujoco" in loaded
    assert "tolins.envs" in _loaded("tolins.geometry", bare=False)


@pytest.mark.parametrize(
    "module",
    [
        "tolins.geometry",
        "tolins.geometry.specs",
        "tolins.geometry.defects",
        "tolins.geometry.tolerance",
    ],
)
def test_geometry_imports_nothing_else_of_tolins(module: str) -> None:
    loaded = _loaded(module)
    assert module in loaded
    outside = {
        name
        for name in _tolins(loaded)
        if name not in ("tolins", "tolins.geometry") and not name.startswith("tolins.geometry.")
    }
    assert not outside, f"{module} imports {sorted(outside)}"
    # "numpy and shapely only": no simulator or gym either.
    assert not {name for name in loaded if name.startswith(("mujoco", "gymnasium"))}


@pytest.mark.parametrize("module", ["tolins.mjcf", "tolins.mjcf.model", "tolins.mjcf.board"])
def test_mjcf_does_not_import_envs_or_policies(module: str) -> None:
    loaded = _tolins(_loaded(module))
    assert module in loaded
    forbidden = {
        name
        for name in loaded
        if name.startswith(("tolins.envs", "tolins.policies"))
        or name.startswith("tolins.rollouts")
        or name in ("tolins.demo", "tolins.cli")
    }
    assert not forbidden, f"{module} imports {sorted(forbidden)}"
    assert "tolins.geometry" in loaded  # the probe does see tolins imports


_EDGES = ("tolins.record", "tolins.dmc", "tolins.cli", "tolins.bench")
_ABOVE_LEARNING = ("tolins.inference", *_EDGES)
_LATER_LAYERS = {
    # module: prefixes it must not load (layers above it, and the edges)
    "tolins.envs": ("tolins.rollouts", "tolins.learning", "tolins.inference", *_EDGES),
    # episodes are run below learning: policies come in as callables
    "tolins.rollouts": ("tolins.learning", "tolins.inference", *_EDGES),
    "tolins.rollouts.ray_pool": ("tolins.learning", "tolins.inference", *_EDGES),
    "tolins.learning.rs_gail": _ABOVE_LEARNING,
    "tolins.learning.autoencoder": _ABOVE_LEARNING,
    "tolins.learning.embedding_train": _ABOVE_LEARNING,
    "tolins.learning.embedding_eval": _ABOVE_LEARNING,
    "tolins.inference.posterior": _EDGES,
    "tolins.inference.adaptive": _EDGES,
    # the bench's cheap parts (the CLI parser) need neither torch nor the learning code
    "tolins.bench.cli": ("tolins.learning.rs_gail", "tolins.learning.bc", "tolins.record"),
}


@pytest.mark.parametrize("module", sorted(_LATER_LAYERS))
def test_layers_do_not_import_the_layers_above_them(module: str) -> None:
    loaded = _tolins(_loaded(module))
    assert module in loaded
    forbidden = {name for name in loaded if name.startswith(_LATER_LAYERS[module])}
    assert not forbidden, f"{module} imports {sorted(forbidden)}"


def test_importing_tolins_does_not_load_torch() -> None:
    """The embedding (torch) is imported on first use of ``tolins.embedding``."""
    loaded = _loaded("tolins", bare=False)
    assert "tolins.envs" in loaded
    assert not {name for name in loaded if name.startswith("torch")}


@pytest.mark.parametrize(
    "module", ["tolins.inference", "tolins.inference.study", "tolins.inference.report"]
)
def test_inference_imports_geometry_only(module: str) -> None:
    """``tolins.inference`` (its physics and adaptive helpers aside) needs no simulator."""
    loaded = _loaded(module)
    assert module in loaded
    allowed = ("tolins.geometry", "tolins.inference", "tolins.atomic")
    outside = {
        name for name in _tolins(loaded) if name != "tolins" and not name.startswith(allowed)
    }
    assert not outside, f"{module} imports {sorted(outside)}"
    assert not {name for name in loaded if name.startswith("mujoco")}


def test_only_the_warp_backend_imports_warp() -> None:
    """``import tolins`` loads no Warp; only ``tolins.envs.warp_batch`` imports it (when a
    ``backend="warp"`` batch is built), so tolins works without the ``warp`` extra."""
    assert "mujoco_warp" not in _loaded("tolins", bare=False)
    root = Path(__file__).resolve().parents[1] / "tolins"
    importing = {
        str(path.relative_to(root))
        for path in root.rglob("*.py")
        if re.search(r"^\s*(import|from)\s+(mujoco_)?warp\b", path.read_text(), re.MULTILINE)
    }
    assert importing == {"envs/warp_batch.py"}

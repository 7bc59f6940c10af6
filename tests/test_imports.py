"""Import flow: geometry depends on nothing of tolins, mjcf not on the envs or policies,
and no layer (envs, learning, inference) on the ones above it or on record, dmc, the cli.

Two ways of looking. The layer rule is read from the source (``tests/import_graph.py``):
every import at every depth, inside functions too, against the layer order ``LAYERS``; no
import may run up a layer, and no circle may join two parts or two files.

The probes import for real. ``import tolins.x`` runs ``tolins/__init__.py`` first, which
registers the environments and so imports everything. Each probe therefore runs in a fresh
interpreter that stands in an empty ``tolins`` package (same ``__path__``, no ``__init__``
code) before importing the subpackage, then reports which ``tolins`` modules got loaded.
The probes that look only at ``tolins`` modules run in children forked from one
interpreter that has loaded the third-party libraries they share (torch, pycma, MuJoCo,
gymnasium) once; those that look at the third-party libraries too start afresh.
"""

from __future__ import annotations

import functools
import json
import re
import subprocess
import sys
from pathlib import Path

import pytest
from import_graph import Import, circles, modules, part, read_imports

_ROOT = Path(__file__).resolve().parents[1] / "tolins"

#: Each top-level part of tolins and its layer. A file may import its own part and the
#: parts of its layer or a lower one, never a higher one, at any depth.
LAYERS: dict[str, int] = {
    # leaf utilities: the paper's constants, atomic file writes, lists of names, stop
    # requests, JSON handed in
    "tolins.paper": 0,
    "tolins.atomic": 0,
    "tolins.names": 0,
    "tolins.stopping": 0,
    "tolins.json_input": 0,
    # package data: the lookup (tolins.resources) and the embedding's checkpoints (no code)
    "tolins.resources": 0,
    "tolins.assets": 0,
    # specs, defects, the tolerance model (tolins.tolerance is its public name)
    "tolins.geometry": 1,
    "tolins.tolerance": 1,
    "tolins.mjcf": 2,
    # the simulators: MuJoCo, the kinematic model, MuJoCo Warp, behind one interface
    "tolins.physics": 3,
    # the task rules, the gym and the vector env
    "tolins.envs": 4,
    # the package root registers the env ids; the dm_control suite stands beside the envs
    "tolins": 5,
    "tolins.dmc": 5,
    "tolins.policies": 6,
    "tolins.rollouts": 7,
    "tolins.datasets": 8,
    # both experts in every preset env, as the table `tolins demo` prints
    "tolins.demo": 8,
    # tolins.embedding is the users' name for tolins.learning.embedding.encoding
    "tolins.learning": 9,
    "tolins.embedding": 9,
    "tolins.inference": 10,
    # at the edge: it imports only the simulation side (EDGE_IMPORTS), and only the bench
    # (which ships recordings of its evaluations) and the command line import it
    # (EDGE_IMPORTERS)
    "tolins.record": 11,
    "tolins.bench": 12,
    # the command line: every command in tolins/cli/, and `python -m tolins`
    "tolins.cli": 13,
    "tolins.__main__": 13,
}

#: The parts at the edge, and the only parts each may import.
EDGE_IMPORTS: dict[str, frozenset[str]] = {
    "tolins.record": frozenset(
        {
            "tolins.paper",
            "tolins.atomic",
            "tolins.geometry",
            "tolins.tolerance",
            "tolins.mjcf",
            "tolins.envs",
            "tolins.rollouts",
        }
    ),
}

#: The parts at the edge, and the only parts that may import each.
EDGE_IMPORTERS: dict[str, frozenset[str]] = {
    "tolins.record": frozenset({"tolins.bench", "tolins.cli"}),
}

#: The imports that break the rule today, by (importing file, imported part or module), each
#: with why. An entry that no import matches fails the suite, so the list only shrinks.
EXCEPTIONS: dict[tuple[str, str], str] = {
    ("__init__.py", "tolins.embedding"): (
        "tolins.embedding as a lazy attribute of the package (torch on first use); no module "
        "of tolins goes through it"
    ),
}

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


@functools.cache
def _loaded(module: str, *, bare: bool = True) -> frozenset[str]:
    """Names of tolins (and mujoco, gymnasium, torch) modules loaded by importing ``module``
    (a fresh interpreter each, once per module for the file)."""
    result = subprocess.run(
        [sys.executable, "-c", _PROBE.format(module=module, bare=bare)],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    return frozenset(json.loads(result.stdout.strip().splitlines()[-1]))


#: ``_PROBE`` (its argument) for each module named on stdin, in a child forked from an
#: interpreter that has loaded the libraries the probed layers share.
_FORKING_PROBE = """
import json, os, sys
import cma, gymnasium, mujoco, numpy, torch
for line in sys.stdin:
    pid = os.fork()
    if pid == 0:
        try:
            exec(sys.argv[1].format(module=line.strip(), bare=True))
        except BaseException as error:
            print(json.dumps(repr(error)))
        sys.stdout.flush()
        os._exit(0)
    os.waitpid(pid, 0)
"""


@pytest.fixture(scope="module")
def tolins_probe():
    """``probe(module)``: the ``tolins`` modules that importing ``module`` in a bare package
    loads (``_PROBE``), each in a child forked from one interpreter (checked to hold
    ``module``)."""
    server = subprocess.Popen(
        [sys.executable, "-c", _FORKING_PROBE, _PROBE],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )

    @functools.cache
    def probe(module: str) -> frozenset[str]:
        server.stdin.write(module + "\n")
        server.stdin.flush()
        answer = json.loads(server.stdout.readline())
        assert isinstance(answer, list), f"importing {module}: {answer}"
        loaded = _tolins(frozenset(answer))
        assert module in loaded
        return frozenset(loaded)

    yield probe
    server.stdin.close()
    server.wait(timeout=60)


def _probe(module: str) -> frozenset[str]:
    """What importing ``module`` in a bare package loads, checked to hold ``module``: the
    probe did see it imported."""
    loaded = _loaded(module)
    assert module in loaded
    return loaded


def _tolins(names: frozenset[str]) -> set[str]:
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
    loaded = _probe(module)
    outside = {
        name
        for name in _tolins(loaded)
        if name not in ("tolins", "tolins.geometry") and not name.startswith("tolins.geometry.")
    }
    assert not outside, f"{module} imports {sorted(outside)}"
    # "numpy and shapely only": no simulator or gym either.
    assert not {name for name in loaded if name.startswith(("mujoco", "gymnasium"))}


@pytest.mark.parametrize("module", ["tolins.mjcf", "tolins.mjcf.model", "tolins.mjcf.board"])
def test_mjcf_does_not_import_envs_or_policies(module: str, tolins_probe) -> None:
    loaded = tolins_probe(module)
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
    # the simulators need neither the task rules nor the envs above them
    "tolins.physics": (
        "tolins.envs",
        "tolins.rollouts",
        "tolins.learning",
        "tolins.inference",
        *_EDGES,
    ),
    "tolins.envs": ("tolins.rollouts", "tolins.learning", "tolins.inference", *_EDGES),
    # episodes are run below learning: policies come in as callables
    "tolins.rollouts": ("tolins.learning", "tolins.inference", *_EDGES),
    "tolins.rollouts.ray_pool": ("tolins.learning", "tolins.inference", *_EDGES),
    "tolins.learning.imitation.rs_gail": _ABOVE_LEARNING,
    "tolins.learning.embedding.autoencoder": _ABOVE_LEARNING,
    "tolins.learning.embedding.train": _ABOVE_LEARNING,
    "tolins.learning.embedding.evaluation": _ABOVE_LEARNING,
    "tolins.inference.posterior": _EDGES,
    "tolins.inference.adaptive": _EDGES,
    # the bench's command line (its parser) needs neither torch nor the learning code
    "tolins.cli.bench": (
        "tolins.learning.imitation.rs_gail",
        "tolins.learning.imitation.bc",
        "tolins.record",
    ),
}


@pytest.mark.parametrize("module", sorted(_LATER_LAYERS))
def test_layers_do_not_import_the_layers_above_them(module: str, tolins_probe) -> None:
    loaded = tolins_probe(module)
    forbidden = {name for name in loaded if name.startswith(_LATER_LAYERS[module])}
    assert not forbidden, f"{module} imports {sorted(forbidden)}"


def test_importing_tolins_does_not_load_torch() -> None:
    """The embedding (torch) is imported on first use of ``tolins.embedding``."""
    loaded = _loaded("tolins", bare=False)
    assert "tolins.envs" in loaded
    assert not {name for name in loaded if name.startswith("torch")}


@pytest.mark.parametrize(
    "module",
    [
        "tolins.learning.embedding.config",
        "tolins.learning.imitation.config",
        "tolins.learning.agents.sb3_config",
    ],
)
def test_run_configs_do_not_load_torch(module: str) -> None:
    """The command line builds its parsers from these configs without loading torch."""
    loaded = _probe(module)
    assert not {name for name in loaded if name.startswith("torch")}


_PARSERS = """
import contextlib, io, json, sys
from tolins.cli import main
with contextlib.redirect_stdout(io.StringIO()):
    try:
        main(["--help"])
    except SystemExit:
        pass
print(json.dumps(sorted(sys.modules)))
"""


def test_the_command_lines_parsers_load_no_learning_optimiser_or_plotting() -> None:
    """``tolins --help`` builds every command's parser without torch, pycma, scipy.stats or
    matplotlib (pycma alone loads the last two, 0.8 s): each is loaded where it is used."""
    result = subprocess.run(
        [sys.executable, "-c", _PARSERS], capture_output=True, text=True, timeout=60
    )
    assert result.returncode == 0, result.stderr
    loaded = set(json.loads(result.stdout.strip().splitlines()[-1]))
    assert "tolins.cli.infer_study" in loaded  # the probe did build the parsers
    heavy = ("torch", "cma", "scipy.stats", "matplotlib")
    assert not {name for name in loaded if name.split(".")[0] in heavy or name in heavy}


@pytest.mark.parametrize(
    "module", ["tolins.inference", "tolins.inference.study", "tolins.inference.report"]
)
def test_inference_imports_geometry_only(module: str) -> None:
    """``tolins.inference`` (its physics and adaptive helpers aside) needs no simulator."""
    loaded = _probe(module)
    allowed = ("tolins.geometry", "tolins.inference", "tolins.atomic", "tolins.names")
    allowed += ("tolins.stopping",)
    outside = {
        name for name in _tolins(loaded) if name != "tolins" and not name.startswith(allowed)
    }
    assert not outside, f"{module} imports {sorted(outside)}"
    assert not {name for name in loaded if name.startswith("mujoco")}


def test_only_the_warp_backend_imports_warp() -> None:
    """``import tolins`` loads no Warp; only ``tolins.physics.warp`` imports it (when a
    ``backend="warp"`` batch is built), so tolins works without the ``warp`` extra."""
    assert "mujoco_warp" not in _loaded("tolins", bare=False)
    root = Path(__file__).resolve().parents[1] / "tolins"
    importing = {
        str(path.relative_to(root))
        for path in root.rglob("*.py")
        if re.search(r"^\s*(import|from)\s+(mujoco_)?warp\b", path.read_text(), re.MULTILINE)
    }
    assert importing == {"physics/warp.py"}


@functools.cache
def _imports() -> tuple[Import, ...]:
    """Every import of a tolins module in tolins, at every depth."""
    return tuple(read_imports(_ROOT))


def _excepted(found: Import) -> bool:
    return (found.path, found.target) in EXCEPTIONS or (
        found.path,
        part(found.target),
    ) in EXCEPTIONS


def _ruled() -> list[Import]:
    """The imports the rule applies to: all but the listed exceptions."""
    return [found for found in _imports() if not _excepted(found)]


def test_the_graph_reads_every_depth(tmp_path: Path) -> None:
    """Sanity check of the reader on a small package: function-level, relative,
    ``TYPE_CHECKING`` and ``importlib.import_module`` imports are all seen."""
    root = tmp_path / "tolins"
    (root / "a").mkdir(parents=True)
    (root / "__init__.py").write_text(
        "import importlib\n\ndef f():\n    return importlib.import_module('tolins.b')\n"
    )
    (root / "a" / "__init__.py").write_text("from . import x\n")
    (root / "a" / "x.py").write_text(
        "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from ..b import Thing\n"
        "def g():\n    from tolins.a import x\n    import tolins.b\n"
    )
    (root / "b.py").write_text("import os\nfrom .a.x import g\n")
    seen = {(i.path, i.line, i.importer, i.target, i.typing_only) for i in read_imports(root)}
    assert seen == {
        ("__init__.py", 4, "tolins", "tolins.b", False),
        ("a/__init__.py", 1, "tolins.a", "tolins.a.x", False),
        ("a/x.py", 3, "tolins.a.x", "tolins.b", True),
        ("a/x.py", 5, "tolins.a.x", "tolins.a.x", False),
        ("a/x.py", 6, "tolins.a.x", "tolins.b", False),
        ("b.py", 2, "tolins.b", "tolins.a.x", False),
    }
    assert circles({"a": {"b"}, "b": {"a", "c"}, "c": set(), "d": {"d"}}) == [["a", "b"]]


def test_every_import_names_a_module_of_tolins() -> None:
    known = modules(_ROOT)
    unknown = [str(found) for found in _imports() if found.target not in known]
    assert not unknown, "imports of no module of tolins:\n" + "\n".join(unknown)


def test_every_part_has_a_layer() -> None:
    missing = sorted({part(name) for name in modules(_ROOT)} - LAYERS.keys())
    assert not missing, f"give {missing} a layer in LAYERS"


def test_no_import_runs_up_a_layer() -> None:
    upward = [
        f"{found}  (layer {LAYERS[part(found.importer)]} -> {LAYERS[part(found.target)]})"
        for found in _ruled()
        if LAYERS[part(found.target)] > LAYERS[part(found.importer)]
    ]
    assert not upward, "imports from a lower layer to a higher one:\n" + "\n".join(upward)


def _across_the_edge(allowed: dict[str, frozenset[str]], *, of_importer: bool) -> list[str]:
    """The imports between an edge part (a key of ``allowed``: the importer with
    ``of_importer``, else the imported part) and another part not in its entry."""
    outside = []
    for found in _ruled():
        importer, target = part(found.importer), part(found.target)
        edge, other = (importer, target) if of_importer else (target, importer)
        if edge in allowed and other != edge and other not in allowed[edge]:
            outside.append(str(found))
    return outside


def test_the_edge_imports_only_what_it_may() -> None:
    outside = _across_the_edge(EDGE_IMPORTS, of_importer=True)
    assert not outside, "imports the edge may not make:\n" + "\n".join(outside)


def test_only_the_listed_parts_import_the_edge() -> None:
    wrong = _across_the_edge(EDGE_IMPORTERS, of_importer=False)
    assert not wrong, "imports of the edge from parts it does not serve:\n" + "\n".join(wrong)


def test_no_circle_between_parts() -> None:
    edges: dict[str, set[str]] = {}
    for found in _ruled():
        if part(found.importer) != part(found.target):
            edges.setdefault(part(found.importer), set()).add(part(found.target))
    assert not circles(edges), f"parts that import each other: {circles(edges)}"


def test_no_circle_between_files() -> None:
    """A circle through an import under ``if TYPE_CHECKING:`` never runs, so it does not
    count here (the layer rule does count that import)."""
    edges: dict[str, set[str]] = {}
    for found in _ruled():
        if found.importer != found.target and not found.typing_only:
            edges.setdefault(found.importer, set()).add(found.target)
    assert not circles(edges), f"files that import each other: {circles(edges)}"


#: The folders of ``tolins.learning`` in order: a file in one may import the folders before
#: it, never one after it.
LEARNING_FOLDERS = (
    "tolins.learning.embedding",
    "tolins.learning.imitation",
    "tolins.learning.agents",
)


def _learning_folder(module: str) -> int | None:
    """The place of ``module``'s folder in :data:`LEARNING_FOLDERS` (``None``: no folder)."""
    folder = ".".join(module.split(".")[:3])
    return LEARNING_FOLDERS.index(folder) if folder in LEARNING_FOLDERS else None


def test_learning_folders_import_only_the_ones_before_them() -> None:
    later = [
        str(found)
        for found in _imports()
        if (source := _learning_folder(found.importer)) is not None
        and (target := _learning_folder(found.target)) is not None
        and target > source
    ]
    assert not later, "imports of a later folder of tolins.learning:\n" + "\n".join(later)


def test_every_exception_is_still_needed() -> None:
    matched = {(found.path, found.target) for found in _imports()}
    matched |= {(found.path, part(found.target)) for found in _imports()}
    stale = sorted(set(EXCEPTIONS) - matched)
    assert not stale, f"no import matches {stale} any more: remove it from EXCEPTIONS"

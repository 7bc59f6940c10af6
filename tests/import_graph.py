"""The imports between tolins's files, read from the source with ``ast``.

Every import counts, wherever it stands: at the top of a file, inside a function, under
``if TYPE_CHECKING:`` (marked ``typing_only``), and ``importlib.import_module("tolins...")``
with a literal name. Relative imports are resolved against the importing file's package.
``from package import name`` points at the submodule ``package.name`` when there is one,
else at the package.
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

PACKAGE = "tolins"


@dataclass(frozen=True)
class Import:
    """One import of a tolins module by a file of tolins."""

    path: str  # the importing file, relative to the package folder (``learning/agents/actors.py``)
    line: int
    importer: str  # the importing module (``tolins.learning.agents.actors``)
    target: str  # the module it imports (``tolins.learning.embedding.encoding``)
    typing_only: bool = False  # under ``if TYPE_CHECKING:``: for type checkers, never run

    def __str__(self) -> str:
        return f"{self.path}:{self.line}: {self.importer} -> {self.target}"


def part(module: str) -> str:
    """The top-level part a module belongs to: ``tolins.learning`` for
    ``tolins.learning.agents.actors``, ``tolins.atomic`` for itself, ``tolins`` for the root."""
    return ".".join(module.split(".")[:2])


def module_name(path: Path, root: Path) -> str:
    """``tolins.learning.agents.actors`` for ``root/learning/agents/actors.py`` (``root``:
    the package)."""
    parts = [PACKAGE, *path.relative_to(root).with_suffix("").parts]
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def modules(root: Path) -> dict[str, Path]:
    """Every module of the package in ``root``, by name."""
    return {module_name(path, root): path for path in sorted(root.rglob("*.py"))}


def read_imports(root: Path) -> list[Import]:
    """Every import of a tolins module in the package in ``root``, in file order."""
    known = modules(root)
    found = []
    for importer, path in known.items():
        package = importer if path.name == "__init__.py" else importer.rpartition(".")[0]
        tree = ast.parse(path.read_text(), filename=str(path))
        relative = path.relative_to(root).as_posix()
        for node, typing_only in _nodes(tree, typing_only=False):
            for target in _targets(node, package, known):
                if target == PACKAGE or target.startswith(f"{PACKAGE}."):
                    found.append(Import(relative, node.lineno, importer, target, typing_only))
    return sorted(set(found), key=lambda i: (i.path, i.line, i.target))


def _nodes(node: ast.AST, *, typing_only: bool) -> Iterator[tuple[ast.AST, bool]]:
    """Every node under ``node`` (itself included), each with whether it stands in the body
    of an ``if TYPE_CHECKING:``."""
    yield node, typing_only
    if isinstance(node, ast.If) and _is_type_checking(node.test):
        for child in node.body:
            yield from _nodes(child, typing_only=True)
        for child in node.orelse:
            yield from _nodes(child, typing_only=typing_only)
        return
    for child in ast.iter_child_nodes(node):
        yield from _nodes(child, typing_only=typing_only)


def _is_type_checking(test: ast.expr) -> bool:
    """``TYPE_CHECKING`` or ``typing.TYPE_CHECKING``."""
    if isinstance(test, ast.Attribute):
        return test.attr == "TYPE_CHECKING"
    return isinstance(test, ast.Name) and test.id == "TYPE_CHECKING"


def _targets(node: ast.AST, package: str, known: dict[str, Path]) -> Iterator[str]:
    """The modules ``node`` imports (none unless it is an import)."""
    if isinstance(node, ast.Import):
        yield from (alias.name for alias in node.names)
    elif isinstance(node, ast.ImportFrom):
        base = _absolute(node, package)
        for alias in node.names:
            submodule = f"{base}.{alias.name}"
            yield submodule if submodule in known else base
    elif isinstance(node, ast.Call) and _is_import_module(node.func) and node.args:
        name = node.args[0]
        if isinstance(name, ast.Constant) and isinstance(name.value, str):
            yield name.value


def _absolute(node: ast.ImportFrom, package: str) -> str:
    """The module a ``from ... import`` names, relative levels resolved."""
    if not node.level:
        return node.module or ""
    parts = package.split(".")
    base = parts[: len(parts) - node.level + 1]
    return ".".join(base + ([node.module] if node.module else []))


def _is_import_module(func: ast.expr) -> bool:
    """``importlib.import_module`` or a bare ``import_module``."""
    if isinstance(func, ast.Attribute):
        return func.attr == "import_module"
    return isinstance(func, ast.Name) and func.id == "import_module"


def circles(edges: dict[str, set[str]]) -> list[list[str]]:
    """The groups of nodes that reach each other through ``edges`` (Tarjan's strongly
    connected components of more than one node), each sorted, in sorted order."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    groups = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for successor in sorted(edges.get(node, ())):
            if successor not in index:
                visit(successor)
                low[node] = min(low[node], low[successor])
            elif successor in on_stack:
                low[node] = min(low[node], index[successor])
        if low[node] == index[node]:
            group = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                group.append(member)
                if member == node:
                    break
            if len(group) > 1:
                groups.append(sorted(group))

    nodes = set(edges) | {n for successors in edges.values() for n in successors}
    for node in sorted(nodes):
        if node not in index:
            visit(node)
    return sorted(groups)

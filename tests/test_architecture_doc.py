"""docs/architecture.md names every module of tolins in the part that holds it."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "tolins"
SECTION = "## What lives where today"


DOC = (ROOT / "docs" / "architecture.md").read_text()


def _parts() -> list[str]:
    """The section's bullets, one string each (a bullet's continuation lines included)."""
    section = DOC[DOC.index(SECTION) : DOC.index("\n## ", DOC.index(SECTION) + 1)]
    return re.split(r"\n- ", section)[1:]


def _names(text: str, module: Path) -> bool:
    """Whether ``text`` names ``module`` (a path inside tolins): by its file name, or by a
    path that ends in its own (``envs/vector.py``, ``tolins/paper.py``)."""
    for match in re.finditer(r"[\w/.]*" + re.escape(module.name), text):
        named = match.group(0)
        path = f"tolins/{module.as_posix()}"
        if named in (module.name, path) or path.endswith("/" + named):
            return True
    return False


def _modules() -> list[Path]:
    """Every module of the package but the package markers (``__init__.py``)."""
    return sorted(
        path.relative_to(PACKAGE)
        for path in PACKAGE.rglob("*.py")
        if path.name != "__init__.py" and "reference" not in path.parts
    )


@pytest.mark.parametrize("module", _modules(), ids=str)
def test_every_module_is_named_in_the_bullet_of_its_folder(module: Path) -> None:
    if len(module.parts) == 1:  # a base module or a users' name: anywhere on the page
        assert _names(DOC, module), f"docs/architecture.md does not name tolins/{module}"
        return
    top = module.parts[0]
    folder = f"tolins/{top}"
    holders = [part for part in _parts() if folder in part or f"`{top}/" in part]
    assert holders, f"docs/architecture.md has no bullet for {folder}"
    assert any(_names(part, module) for part in holders), (
        f"docs/architecture.md's bullet for {folder} does not name {module.as_posix()}"
    )


def _steps_mujoco(tree: ast.AST) -> bool:
    """Whether a module calls ``mj_step`` (or ``mj_step1``/``2``), MuJoCo's rollout, or
    builds a ``mujoco.batch.Batch``."""
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and node.attr in {"mj_step", "mj_step1", "mj_step2"}:
            return True
        if isinstance(node, ast.Attribute) and node.attr == "Batch":
            return True
        if isinstance(node, ast.alias) and node.name in {"mj_step", "rollout", "Batch"}:
            return True
    return False


def test_servo_is_the_one_module_that_steps_mujoco() -> None:
    """docs/architecture.md says so: every simulator's physics goes through servo.py."""
    stepping = [
        module.as_posix()
        for module in _modules()
        if _steps_mujoco(ast.parse((PACKAGE / module).read_text()))
    ]
    assert stepping == ["physics/servo.py"]
    assert "the one module that calls `mj_step`" in " ".join(DOC.split())

"""Reference results shipped with tolins, named ``reference:NAME`` by ``tolins compare``.

A reference is ``tolins/bench/reference/NAME/results.json`` (package data), the
``results.json`` of a measured ``tolins bench`` run (beside its ``run.json`` for the
provenance). See this folder's README.md for what is shipped and how one is added.
"""

from __future__ import annotations

from pathlib import Path

from tolins.resources import package_path

PREFIX = "reference:"
FOLDER = package_path(__name__)


def reference_names() -> list[str]:
    """The names of the shipped references (sorted)."""
    return sorted(p.parent.name for p in FOLDER.glob("*/results.json"))


def reference_path(name: str) -> Path:
    """The ``results.json`` of the shipped reference ``name``; ``ValueError`` if none is
    shipped under that name."""
    path = FOLDER / name / "results.json"
    if not name or "/" in name or "\\" in name or not path.is_file():
        shipped = ", ".join(PREFIX + n for n in reference_names()) or "none yet"
        raise ValueError(
            f"{PREFIX}{name}: no such reference results ({FOLDER / name / 'results.json'}); "
            f"shipped: {shipped} (see {FOLDER / 'README.md'})"
        )
    return path

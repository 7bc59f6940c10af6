"""CITATION.cff, LICENSE and the README's Cite section agree with pyproject.toml."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

yaml = pytest.importorskip("yaml")
tomllib = pytest.importorskip("tomllib")

ROOT = Path(__file__).resolve().parents[1]


def _project() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]


def _citation() -> dict:
    return yaml.safe_load((ROOT / "CITATION.cff").read_text())


def test_citation_cff_has_the_required_keys_and_pyprojects_version_and_license() -> None:
    citation = _citation()
    assert citation["cff-version"] == "1.2.0"
    assert {"cff-version", "message", "title", "authors"} <= set(citation)
    assert all("name" in a or "family-names" in a for a in citation["authors"])
    assert citation["version"] == _project()["version"]
    assert citation["license"] == _project()["license"]["text"] == "Apache-2.0"
    assert re.fullmatch(r"\d{4}-\d{2}-\d{2}", str(citation["date-released"]))


def test_citation_cff_references_the_paper() -> None:
    (paper,) = [r for r in _citation()["references"] if r["type"] == "conference-paper"]
    assert paper["title"].startswith("Tolerance-Guided Policy Learning")
    assert [a["family-names"] for a in paper["authors"]] == ["Niu", "Wang", "Liu"]
    assert paper["year"] == 2020 and "CoRL 2020" in paper["conference"]["name"]


def test_license_is_the_apache_2_text_and_the_readme_cites_this_version() -> None:
    text = (ROOT / "LICENSE").read_text()
    assert "Apache License\n                           Version 2.0, January 2004" in text
    assert "END OF TERMS AND CONDITIONS" in text and len(text.splitlines()) == 202
    readme = (ROOT / "README.md").read_text()
    cite = readme.split("## Cite", 1)[1]
    assert f"version = {{{_project()['version']}}}" in cite
    assert "@inproceedings{niu2020tolerance" in cite

"""Deterministic formatting of numbers for MJCF attributes."""

from __future__ import annotations

from collections.abc import Iterable


def num(value: float) -> str:
    """A float as the shortest text that reads back to nearly the same value (12 digits)."""
    text = f"{float(value):.12g}"
    return "0" if text == "-0" else text


def nums(values: Iterable[float]) -> str:
    """Space-separated numbers."""
    return " ".join(num(v) for v in values)

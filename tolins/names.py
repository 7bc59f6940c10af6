"""Comma-separated lists of names, as options take them (``--rows C1.1,C2.3``,
``--methods random,inference``): one parser and one set of error messages for all."""

from __future__ import annotations

from collections.abc import Sequence


def comma_separated(text: str, allowed: Sequence[str], *, option: str) -> tuple[str, ...]:
    """The names in ``text`` in its order (spaces around a name ignored): each one of
    ``allowed``, each at most once, at least one.

    Raises ``ValueError`` naming ``option``, what is wrong and the allowed names.
    """
    names = tuple(name.strip() for name in text.split(","))
    subset = f"allowed: a comma-separated subset of {', '.join(allowed)}"
    if not any(names):
        raise ValueError(f"{option} {text!r} names nothing; {subset}")
    for name in names:
        if not name:
            raise ValueError(f"{option} {text!r} has an empty name; {subset}")
        if name not in allowed:
            raise ValueError(f"{option}: {name!r} is unknown; {subset}")
        if names.count(name) > 1:
            raise ValueError(f"{option}: {name!r} is named twice; {subset}")
    return names

"""A socket spec as JSON-ready data, and back: the metadata a recording carries."""

from __future__ import annotations

import dataclasses
from typing import Any

from tolins.geometry.specs import CircularSocket, PolygonSocket, SocketSpec

_TYPES = {cls.__name__: cls for cls in (CircularSocket, PolygonSocket)}


def spec_to_dict(spec: SocketSpec) -> dict[str, Any]:
    """``{"type": "CircularSocket", "rows": 2, ...}``; tuples become lists."""
    if not isinstance(spec, tuple(_TYPES.values())):
        raise ValueError(f"spec={spec!r}; allowed: a CircularSocket or PolygonSocket")
    fields = dataclasses.asdict(spec)
    if fields.get("pin_offsets") is not None:
        fields["pin_offsets"] = [list(pair) for pair in fields["pin_offsets"]]
    return {"type": type(spec).__name__, **fields}


def spec_from_dict(data: dict[str, Any]) -> SocketSpec:
    """The spec that :func:`spec_to_dict` wrote."""
    fields = dict(data)
    kind = fields.pop("type", None)
    if kind not in _TYPES:
        raise ValueError(f"spec type={kind!r}; allowed: {sorted(_TYPES)}")
    return _TYPES[kind](**fields)

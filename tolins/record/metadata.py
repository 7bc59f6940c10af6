"""A socket spec as JSON-ready data, and back: the metadata a recording carries."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any

from tolins.geometry.spec_json import SPEC_TYPES, spec_from_mapping
from tolins.geometry.specs import SocketSpec

#: The spec classes a recording's metadata names, by ``type``.
_TYPES = SPEC_TYPES


def spec_to_dict(spec: SocketSpec) -> dict[str, Any]:
    """``{"type": "CircularSocket", "rows": 2, ...}``; tuples become lists."""
    if not isinstance(spec, tuple(_TYPES.values())):
        raise ValueError(f"spec={spec!r}; allowed: a CircularSocket or PolygonSocket")
    fields = dataclasses.asdict(spec)
    if fields.get("pin_offsets") is not None:
        fields["pin_offsets"] = [list(pair) for pair in fields["pin_offsets"]]
    return {"type": type(spec).__name__, **fields}


def spec_from_dict(data: dict[str, Any]) -> SocketSpec:
    """The spec that :func:`spec_to_dict` wrote: its ``type`` is required and nothing but
    the fields of that type is allowed (:func:`~tolins.geometry.spec_json.spec_from_mapping`
    with ``derived=False``); ``ValueError`` otherwise."""
    kind = data.get("type") if isinstance(data, Mapping) else None
    if kind not in _TYPES:  # spec_from_mapping would guess a missing type from the fields
        raise ValueError(f"spec type={kind!r}; allowed: {sorted(_TYPES)}")
    return spec_from_mapping(data, derived=False)

"""A socket spec from JSON, as ``tolins export --socket`` takes it.

The object holds a spec's fields (:mod:`tolins.geometry.specs`), as a recording's metadata
and :func:`~tolins.geometry.specs.workpiece_dict` write them::

    {"type": "CircularSocket", "rows": 2, "cols": 1,
     "pin_offsets": [[0.1, 0.0], [0.0, -0.05]], "blocked_holes": [1]}

``type`` may be left out: ``sides`` makes a :class:`PolygonSocket`, ``rows`` and ``cols`` a
:class:`CircularSocket`. ``defective`` (derived from the fields) is ignored.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping

from tolins.geometry.specs import CircularSocket, PolygonSocket, SocketSpec
from tolins.json_input import parse_json, shorten

SPEC_TYPES: dict[str, type[CircularSocket] | type[PolygonSocket]] = {
    "CircularSocket": CircularSocket,
    "PolygonSocket": PolygonSocket,
}
#: Keys that describe a spec without being one of its fields.
_DERIVED = frozenset({"defective"})


def spec_from_mapping(data: Mapping[str, object], *, derived: bool = True) -> SocketSpec:
    """The spec whose fields ``data`` holds (``type`` optional, see the module); with
    ``derived=False`` a derived key (``defective``) is an unknown field, not ignored.

    Raises ``ValueError`` (one line) for a wrong type, an unknown or missing field, or a
    value the spec refuses.
    """
    if not isinstance(data, Mapping):
        raise ValueError(
            f"socket {shorten(repr(data))} is not an object; allowed: a JSON object of fields"
        )
    ignored = _DERIVED if derived else frozenset()
    fields = {key: value for key, value in data.items() if key not in ignored}
    kind = fields.pop("type", None)
    if kind is None:
        kind = "PolygonSocket" if "sides" in fields else "CircularSocket"
    if kind not in SPEC_TYPES:
        raise ValueError(f"socket type={kind!r}; allowed: {', '.join(SPEC_TYPES)}")
    cls = SPEC_TYPES[kind]
    names = [field.name for field in dataclasses.fields(cls)]
    unknown = sorted(set(fields) - set(names))
    if unknown:
        raise ValueError(f"{kind} has no field {', '.join(unknown)}; allowed: {', '.join(names)}")
    required = [
        field.name
        for field in dataclasses.fields(cls)
        if field.default is dataclasses.MISSING and field.name not in fields
    ]
    if required:
        raise ValueError(f"{kind} needs {', '.join(required)}; allowed fields: {', '.join(names)}")
    try:
        return cls(**fields)
    except TypeError as error:  # e.g. a list where the spec compares numbers
        raise ValueError(f"{kind}: {error}") from None


#: What a socket in JSON may be, for error messages.
ALLOWED = 'a JSON object of a spec\'s fields, e.g. {"rows": 2, "cols": 2}'


def spec_from_json(text: str | bytes, source: str | None = None) -> SocketSpec:
    """The spec of the JSON object ``text`` (bytes: UTF-8; :func:`spec_from_mapping`);
    ``source`` names it in errors (default: the text, shortened).

    Raises ``ValueError`` (one line) for text that is not JSON, or a spec it does not make.
    """
    data = parse_json(text, source or f"socket {shorten(repr(text))}", ALLOWED)
    return spec_from_mapping(data)

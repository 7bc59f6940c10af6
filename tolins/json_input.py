"""JSON handed to tolins (a file, an option's value, a file inside a zip), read with
one-line errors, and values shortened for the messages that echo them.

:func:`parse_json` and :func:`read_json_file` raise ``ValueError`` naming the source, what
is wrong with it (not UTF-8 text, not JSON, or nested deeper than :data:`DEPTH_MAX`) and
what is allowed: never ``UnicodeDecodeError``'s or ``RecursionError``'s own text.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

#: The deepest nesting of lists and objects read. tolins's own documents nest a few levels;
#: Python's parser (and any recursive reader after it) fails near 1,000.
DEPTH_MAX = 64
#: The most characters of a user's value that a message echoes (:func:`shorten`).
SHOWN_MAX = 80


def shorten(value: object, limit: int = SHOWN_MAX) -> str:
    """``str(value)``, cut to ``limit`` characters with an ellipsis when longer."""
    text = str(value)
    return text if len(text) <= limit else f"{text[: limit - 1]}…"


def parse_json(text: str | bytes, source: str, allowed: str) -> Any:
    """The JSON document ``text`` (bytes must be UTF-8); ``ValueError``
    ``"{source}: {what is wrong}; allowed: {allowed}"`` when it cannot be read."""
    try:
        document = json.loads(text.decode("utf-8") if isinstance(text, bytes) else text)
    except UnicodeDecodeError as error:
        problem = f"not UTF-8 text (byte 0x{error.object[error.start]:02x} at {error.start})"
    except json.JSONDecodeError as error:
        problem = f"not JSON ({error.msg}: line {error.lineno} column {error.colno})"
    except RecursionError:
        problem = f"nested deeper than {DEPTH_MAX} levels"
    else:
        if not _deeper_than(document, DEPTH_MAX):
            return document
        problem = f"nested deeper than {DEPTH_MAX} levels"
    raise ValueError(f"{source}: {problem}; allowed: {allowed}")


def read_json_file(path: str | os.PathLike[str], allowed: str) -> Any:
    """The JSON document in the file at ``path`` (:func:`parse_json`, the path naming it in
    errors). ``FileNotFoundError`` and other ``OSError`` pass."""
    return parse_json(Path(path).read_bytes(), str(path), allowed)


def _deeper_than(document: Any, depth: int) -> bool:
    """Whether lists and objects nest in ``document`` more than ``depth`` levels."""
    level = [document]
    for _ in range(depth + 1):
        level = [
            child
            for item in level
            if isinstance(item, dict | list)
            for child in (item.values() if isinstance(item, dict) else item)
        ]
        if not level:
            return False
    return True

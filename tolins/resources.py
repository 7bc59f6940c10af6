"""Files shipped inside the tolins package (package data), found with importlib.resources.

tolins reads two kinds at run time: the tolerance embedding's checkpoints
(``tolins/assets/``) and the bench's reference results (``tolins/bench/reference/``).
pyproject.toml's ``package-data`` puts both in the wheel and the sdist; an editable
install reads them from the checkout.
"""

from __future__ import annotations

import atexit
from contextlib import ExitStack
from importlib.resources import as_file, files
from pathlib import Path

# Holds what ``as_file`` extracted from a zipped install until the process exits; on a
# file system it yields the file itself and extracts nothing.
_EXTRACTED = ExitStack()
atexit.register(_EXTRACTED.close)


def package_path(package: str, *parts: str) -> Path:
    """The file or folder ``parts`` inside the package ``package`` (dotted name) as a path
    on disk, valid for the rest of the process; it need not exist."""
    return _EXTRACTED.enter_context(as_file(files(package).joinpath(*parts)))

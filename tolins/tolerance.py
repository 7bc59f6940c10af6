"""``tolins.tolerance``: the tolerance model (see :mod:`tolins.geometry.tolerance`)."""

from tolins.geometry.tolerance import (
    GRADED_WINDOWS,
    NO_TOLERANCE,
    WINDOWS,
    Extents,
    ImageWindow,
    contains,
    extents,
    image,
)

__all__ = [
    "GRADED_WINDOWS",
    "NO_TOLERANCE",
    "WINDOWS",
    "Extents",
    "ImageWindow",
    "contains",
    "extents",
    "image",
]

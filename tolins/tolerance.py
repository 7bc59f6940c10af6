"""``tolins.tolerance``: the tolerance model (see :mod:`tolins.geometry.tolerance`)."""

from tolins.geometry.tolerance import (
    NO_TOLERANCE,
    WINDOWS,
    Extents,
    ImageWindow,
    contains,
    extents,
    image,
)

__all__ = ["NO_TOLERANCE", "WINDOWS", "Extents", "ImageWindow", "contains", "extents", "image"]

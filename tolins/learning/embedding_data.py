"""Training data: tolerance images of workpieces sampled from a family's ranges."""

from __future__ import annotations

import numpy as np

from tolins.geometry.specs import SocketSpec
from tolins.geometry.tolerance import WINDOWS, image
from tolins.learning.ranges import RANGES, FamilyRanges


def sample_specs(
    family: str, count: int, rng: np.random.Generator, ranges: FamilyRanges | None = None
) -> list[SocketSpec]:
    """``count`` workpieces drawn from the family's ranges (default :data:`RANGES`)."""
    ranges = ranges or family_ranges(family)
    return [ranges.sample(rng) for _ in range(count)]


def make_images(specs: list[SocketSpec], resolution: int) -> np.ndarray:
    """Tolerance images ``(len(specs), resolution, resolution)`` in the family windows."""
    return np.stack([image(spec, resolution, window=WINDOWS[spec.family]) for spec in specs])


def family_ranges(family: str) -> FamilyRanges:
    """The ranges of ``family`` ("circle" or "polygon")."""
    if family not in RANGES:
        raise ValueError(f"family={family!r}; allowed: {', '.join(RANGES)}")
    return RANGES[family]

"""Training data: tolerance images of workpieces sampled from a family's ranges."""

from __future__ import annotations

import numpy as np

from tolins.geometry.specs import SocketSpec
from tolins.geometry.tolerance import GRADED_WINDOWS, WINDOWS, ImageWindow, image
from tolins.learning.embedding.ranges import FamilyRanges, model_ranges


def sample_specs(
    family: str, count: int, rng: np.random.Generator, ranges: FamilyRanges | None = None
) -> list[SocketSpec]:
    """``count`` workpieces drawn from the family's ranges (default :data:`RANGES`)."""
    ranges = ranges or family_ranges(family)
    return [ranges.sample(rng) for _ in range(count)]


def make_images(
    specs: list[SocketSpec], resolution: int, window: ImageWindow | None = None
) -> np.ndarray:
    """Tolerance images ``(len(specs), resolution, resolution)`` in ``window`` (default:
    the family windows)."""
    return np.stack(
        [image(spec, resolution, window=window or WINDOWS[spec.family]) for spec in specs]
    )


def family_ranges(family: str, model: str = "paper") -> FamilyRanges:
    """The ranges of ``family`` ("circle" or "polygon") of ``model`` ("paper", "graded")."""
    return model_ranges(family, model)


def model_window(family: str, model: str = "paper") -> ImageWindow:
    """The image window of ``family`` of ``model``: ``WINDOWS`` or ``GRADED_WINDOWS``."""
    model_ranges(family, model)  # checks both
    return (WINDOWS if model == "paper" else GRADED_WINDOWS)[family]

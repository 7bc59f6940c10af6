"""Socket specs as MJCF models: pure functions, same spec, same bytes."""

from tolins.mjcf.layout import BEND_FIELDS, FORCE_SCALE, ModelLayout, bend_fields, model_layout
from tolins.mjcf.model import make_mjcf

__all__ = ["BEND_FIELDS", "FORCE_SCALE", "ModelLayout", "bend_fields", "make_mjcf", "model_layout"]

"""Socket specs as MJCF models: pure functions, same spec, same bytes."""

from tolins.mjcf.model import make_mjcf

__all__ = ["make_mjcf"]

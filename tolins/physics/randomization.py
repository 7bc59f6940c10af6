"""Randomised physics: friction, contact stiffness, servo gains and force limit, force-sensor
noise and bias, and initial-pose spread, drawn per episode (off by default).

A :class:`PhysicsRandomization` holds a range per quantity, each a factor of the nominal
model's value or an absolute amount; ``None`` leaves a quantity at its nominal value.
``reset`` draws one :class:`PhysicsDraw` from the env's generator (after the workpiece,
before the pose: an env without randomisation draws exactly as before) and applies it to
the episode's MuJoCo model with :func:`apply_draw`, always from the nominal values, so
draws never compound. The drawn values are in the reset's ``info["physics"]``.

=================  ==============================================  =====================
quantity           what is scaled or added                          example range
=================  ==============================================  =====================
``friction``       sliding friction of every geom (nominal 0.3)     factor (0.67, 1.33)
``stiffness``      contact time constant ``solref[0]`` (nominal     factor (1.0, 2.0);
                   2 ms; larger is softer)                          < 1 is refused
``servo_gain``     the servos' ``kp`` (× g) and ``kv`` (× √g: the   factor (0.5, 2.0)
                   same damping ratio)
``force_limit``    the servos' force range                          factor (0.8, 1.2)
``force_bias``     a constant added to ``[F̂x, F̂y, q̂θ, F̂z]``        N, N·mm (-0.1, 0.1)
``force_noise``    extra std of ``[F̂x, F̂y, q̂θ, F̂z]``               N, N·mm (0.0, 0.1)
``pose_spread``    the initial pose's horizontal offset and theta   factor (0.5, 1.0)
=================  ==============================================  =====================

The widest pose spread must keep every initial pose in the servo range (checked with the
env's ``initial_pose``: the default one is already at its edge, so spreads above 1 need a
narrower ``initial_pose``). The kinematic backend has no friction, stiffness or servos:
there only the sensor terms and the pose spread apply.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields
from typing import Any

import mujoco
import numpy as np

#: Bounds of every range (beyond them the model is no longer the task's): factor or amount.
_LIMITS = {
    "friction": (0.1, 3.0),
    "stiffness": (1.0, 5.0),  # solref below 2 physics steps is clamped by MuJoCo
    "servo_gain": (0.1, 10.0),
    "force_limit": (0.2, 5.0),
    "force_bias": (-1.0, 1.0),
    "force_noise": (0.0, 1.0),
    "pose_spread": (0.0, 1.0 / 0.6),  # the default initial pose stays in the servo range
}
_MODEL_TERMS = ("friction", "stiffness", "servo_gain", "force_limit")


def _check_range(name: str, value: object) -> tuple[float, float] | None:
    if value is None:
        return None
    lo_ok, hi_ok = _LIMITS[name]
    allowed = f"None or (low, high) with {lo_ok} ≤ low ≤ high ≤ {hi_ok}"
    if isinstance(value, (str, bytes, dict)) or not hasattr(value, "__len__") or len(value) != 2:
        raise ValueError(f"randomization.{name}={value!r}; allowed: {allowed}")
    try:
        lo, hi = (float(v) for v in value)
    except (TypeError, ValueError) as error:
        raise ValueError(f"randomization.{name}={value!r}; allowed: {allowed}") from error
    if any(isinstance(v, (bool, complex)) for v in value) or not (
        math.isfinite(lo) and math.isfinite(hi) and lo_ok <= lo <= hi <= hi_ok
    ):
        raise ValueError(f"randomization.{name}={value!r}; allowed: {allowed}")
    return lo, hi


@dataclass(frozen=True)
class PhysicsRandomization:
    """Per-episode ranges (see the module docstring); every field ``None`` by default."""

    friction: tuple[float, float] | None = None
    stiffness: tuple[float, float] | None = None
    servo_gain: tuple[float, float] | None = None
    force_limit: tuple[float, float] | None = None
    force_bias: tuple[float, float] | None = None
    force_noise: tuple[float, float] | None = None
    pose_spread: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        for field in fields(self):
            checked = _check_range(field.name, getattr(self, field.name))
            object.__setattr__(self, field.name, checked)

    @classmethod
    def of(cls, value: object) -> PhysicsRandomization | None:
        """``value`` as a randomisation: ``None``, an instance, a dict of ranges, or
        ``"default"`` (:data:`DEFAULT_RANDOMIZATION`)."""
        if value is None or isinstance(value, cls):
            return value
        if isinstance(value, str) and value == "default":  # not an array's elementwise ==
            return DEFAULT_RANDOMIZATION
        if isinstance(value, dict):
            unknown = set(value) - {f.name for f in fields(cls)}
            if unknown:
                raise ValueError(
                    f"randomization keys {sorted(map(str, unknown))} are unknown; allowed: "
                    f"{', '.join(f.name for f in fields(cls))}"
                )
            return cls(**value)
        raise ValueError(
            f"randomization={value!r}; allowed: None, 'default', a dict of ranges or a "
            "PhysicsRandomization"
        )

    def sample(self, rng: np.random.Generator) -> PhysicsDraw:
        """One episode's values: a uniform draw in each set range (per axis for the sensor
        terms), in field order."""
        values: dict[str, Any] = {}
        for field in fields(self):
            bounds = getattr(self, field.name)
            if bounds is None:
                continue
            size = 4 if field.name in ("force_bias", "force_noise") else None
            draw = rng.uniform(bounds[0], bounds[1], size)
            values[field.name] = draw.tolist() if size else float(draw)
        return PhysicsDraw(**values)


#: Ranges in the spirit of FORGE's randomisation, around the paper's setting.
DEFAULT_RANDOMIZATION = PhysicsRandomization(
    friction=(0.67, 1.33),
    stiffness=(1.0, 2.0),
    servo_gain=(0.5, 2.0),
    force_limit=(0.8, 1.2),
    force_bias=(-0.1, 0.1),
    force_noise=(0.0, 0.1),
    pose_spread=(0.5, 1.0),
)


@dataclass(frozen=True)
class PhysicsDraw:
    """One episode's randomised values (``None``: nominal)."""

    friction: float | None = None
    stiffness: float | None = None
    servo_gain: float | None = None
    force_limit: float | None = None
    force_bias: list[float] | None = None
    force_noise: list[float] | None = None
    pose_spread: float | None = None

    def to_info(self) -> dict[str, Any]:
        """The drawn values for ``info["physics"]`` (nominal ones left out)."""
        return {k: v for k, v in asdict(self).items() if v is not None}

    @property
    def changes_model(self) -> bool:
        return any(getattr(self, name) is not None for name in _MODEL_TERMS)

    def observe(self, observation: np.ndarray, rng: np.random.Generator) -> np.ndarray:
        """``observation`` with the drawn sensor bias and extra noise on the wrench."""
        if self.force_bias is not None:
            observation[4:] += self.force_bias
        if self.force_noise is not None:
            observation[4:] += rng.normal(0.0, 1.0, 4) * self.force_noise
        return observation


_FIELDS = ("geom_friction", "geom_solref", "actuator_gainprm", "actuator_biasprm")


def nominal_fields(model: mujoco.MjModel) -> dict[str, np.ndarray]:
    """Copies of the model fields :func:`apply_draw` writes, to draw from."""
    return {name: getattr(model, name).copy() for name in (*_FIELDS, "actuator_forcerange")}


def apply_draw(model: mujoco.MjModel, nominal: dict[str, np.ndarray], draw: PhysicsDraw) -> None:
    """Write ``draw``'s model terms into ``model``, from the ``nominal`` fields (every field
    reset to nominal first, so a draw without a term leaves it nominal)."""
    for name, value in nominal.items():
        getattr(model, name)[:] = value
    if draw.friction is not None:
        model.geom_friction[:, 0] = nominal["geom_friction"][:, 0] * draw.friction
    if draw.stiffness is not None:
        model.geom_solref[:, 0] = nominal["geom_solref"][:, 0] * draw.stiffness
    if draw.servo_gain is not None:
        # intvelocity: force = kp (act - q) - kv qdot; gainprm[0] = kp, biasprm = [0, -kp, -kv]
        model.actuator_gainprm[:, 0] = nominal["actuator_gainprm"][:, 0] * draw.servo_gain
        model.actuator_biasprm[:, 1] = nominal["actuator_biasprm"][:, 1] * draw.servo_gain
        kv = nominal["actuator_biasprm"][:, 2] * math.sqrt(draw.servo_gain)
        model.actuator_biasprm[:, 2] = kv
    if draw.force_limit is not None:
        model.actuator_forcerange[:] = nominal["actuator_forcerange"] * draw.force_limit

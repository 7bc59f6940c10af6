"""Force-aware scores of an episode: how hard the part was pushed, and whether it jammed.

Every score comes from two per-step ``info`` entries that both backends and the vector env
give: ``peak_force`` (the largest summed normal force between the pins and the board
during the step, N) and the true height ``pose[3]`` (``z``, mm). :class:`ForceTracker`
accumulates them step by step; the :class:`~tolins.rollouts.collectors.Forces` collector
of every episode feeds it, in the single-env loop (:func:`tolins.rollouts.episodes.
run_episode`) as in the vector-env runner (:func:`tolins.rollouts.runner.run_jobs`), so
both give the same scores.

* ``peak_force``: the episode's largest step peak (N).
* ``contact_force``: the mean step peak over the steps in contact (N; 0 with none). A step
  is in contact when its peak exceeds :data:`CONTACT_FORCE` (0.01 N).
* ``impulse``: ``Σ peak · control_dt`` over the steps in contact (N·s): an upper estimate
  of ``∫ F dt`` (each step's peak held for the whole step).
* ``jams``: how many times the part jammed. A jam is :data:`JAM_STEPS` (k = 4) consecutive
  blocked steps (a collision: peak above the env's ``collision_force``, 0.5 N) over which
  the pins went less than :data:`JAM_PROGRESS` (0.01 mm) deeper; a run of such windows is
  one jam.
* ``cycle_time``: ``steps · control_dt`` (s).

Why k = 4 and 0.01 mm: 4 steps are 1 s, in which a descent at the experts' 2.5 mm/s would
have gone 2.5 mm deeper; a corner touch while aligning is resolved within one or two
steps by any of the experts, so it is not a jam. 0.01 mm is far above what a pin blocked
on the board moves (0.03–0.13 µm of penetration at 5 N, a capture zone of 1–4 µm;
docs/DESIGN facts) and far below one free step's travel (0.625 mm), so "less than 0.01 mm"
means "no progress". 0.01 N for contact is 2 % of the collision threshold; a free step's
summed normal force is exactly 0 on both backends.
"""

from __future__ import annotations

from dataclasses import dataclass

#: A step is in contact when its peak summed normal force exceeds this (N).
CONTACT_FORCE = 0.01
#: Consecutive blocked steps that make a jam (k; 1 s at the paper's 0.25 s).
JAM_STEPS = 4
#: Depth (mm) the pins must gain over ``JAM_STEPS`` blocked steps not to be jammed.
JAM_PROGRESS = 0.01
#: The score names, in the order of the tables.
FORCE_FIGURES = ("peak_force", "contact_force", "impulse", "jams", "cycle_time")


@dataclass(frozen=True)
class ForceScores:
    """One episode's force-aware scores (see the module docstring)."""

    peak_force: float
    contact_force: float
    impulse: float
    jams: int
    cycle_time: float


class ForceTracker:
    """Accumulates :class:`ForceScores` over one episode, one :meth:`step` per env step.

    Args:
        z: The true height ``pose[3]`` after the reset (mm).
        control_dt: The env's control step (s).
        collision_force: The env's collision threshold (N): a step above it is blocked.
    """

    def __init__(self, z: float, *, control_dt: float, collision_force: float) -> None:
        self.control_dt, self.collision_force = float(control_dt), float(collision_force)
        self._heights = [float(z)]  # z after the reset and after each step
        self._blocked: list[bool] = []
        self._peaks: list[float] = []
        self._peak, self._contact_sum, self._contact_steps, self._jams = 0.0, 0.0, 0, 0
        self._jammed = False

    @classmethod
    def of(cls, settings, info: dict) -> ForceTracker:
        """A tracker for an env's ``settings`` (``TaskSettings``) from its reset ``info``."""
        return cls(
            float(info["pose"][3]),
            control_dt=settings.control_dt,
            collision_force=settings.collision_force,
        )

    def step(self, peak_force: float, z: float) -> None:
        """Add one step: its ``peak_force`` (N) and the true height ``z`` after it (mm)."""
        peak = float(peak_force)
        self._heights.append(float(z))
        self._blocked.append(peak > self.collision_force)
        self._peaks.append(peak)
        self._peak = max(self._peak, peak)
        if peak > CONTACT_FORCE:
            self._contact_sum += peak
            self._contact_steps += 1
        jammed = False
        if len(self._blocked) >= JAM_STEPS and all(self._blocked[-JAM_STEPS:]):
            jammed = self._heights[-JAM_STEPS - 1] - self._heights[-1] < JAM_PROGRESS
        if jammed and not self._jammed:
            self._jams += 1
        self._jammed = jammed

    def profile(self) -> tuple[tuple[float, float], ...]:
        """Each step's ``(depth, peak_force)``: how deep the pin tips were after it (mm below
        the board's top, ``-z``; negative above it) and its peak normal force (N)."""
        return tuple((-z, peak) for z, peak in zip(self._heights[1:], self._peaks, strict=True))

    def scores(self) -> ForceScores:
        """The scores of the steps so far."""
        steps = len(self._blocked)
        mean = self._contact_sum / self._contact_steps if self._contact_steps else 0.0
        return ForceScores(
            peak_force=self._peak,
            contact_force=mean,
            impulse=self._contact_sum * self.control_dt,
            jams=self._jams,
            cycle_time=steps * self.control_dt,
        )

"""π_φ*: any observation → action policy with probabilistic inference in the loop.

:class:`InferenceGuidedPolicy` wraps a policy (π_φ, an expert, ...) acting in an
:class:`~tolins.envs.insertion_env.InsertionEnv`. While the policy runs, the wrapper
watches for **blocked attempts**: a control step after which

* the measured vertical force of the board exceeds the env's ``collision_force``
  (``F̂z = obs[7] > collision_force``, the observable counterpart of ``info["collision"]``)
  and
* the measured pin height is at the board surface, ``|ẑ| = |obs[3]| ≤ surface_tol``
  (default 0.3 mm, three times the paper's z noise): the pins rest on the board top.

A blocked attempt is recorded in a :class:`~tolins.inference.History` at the *measured*
truncated pose ``ŝ = obs[:3] + goal`` with the env's pose noise (the paper's ``g′``) and,
with ``contact=True`` on the MuJoCo backend, which pins the board blocked (per-pin touch
sensors ``MujocoBackend.pin_forces() > touch_force``) and where each touched it (the
bearing of ``MujocoBackend.pin_touch_points()`` from its hole's centre). The posterior is
updated, the next goal found with :func:`~tolins.inference.next_goal`, and
``env.unwrapped.goal`` set to it, so that the observation (and the wrapped policy) steers
to the new goal.

One attempt per **contact**: on a blocked step the wrapper records the attempt, re-plans
(at most ``max_replans`` per episode; a ``discard`` recommendation keeps the goal) and
lifts the workpiece for ``lift_steps`` control steps at full speed (0.625 mm each), then
hands control back to the wrapped policy, which aligns with the new goal and descends
again. The lift matters: a learned policy pressed onto the board is outside its training
data and tends to drift away. ``inference=False`` only lifts and retries at the same goal
(the ablation). Call :meth:`reset` before every episode: it restores the base goal (so
the initial pose is drawn as for the bare policy) and empties the history.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from tolins.geometry.specs import CircularSocket
from tolins.inference.goal import next_goal
from tolins.inference.history import History
from tolins.inference.physics import touch_bearings
from tolins.inference.posterior import DefectModel
from tolins.paper import A_MAX

Policy = Callable[[np.ndarray], np.ndarray]


class InferenceGuidedPolicy:
    """``observation (8,) -> action (4,)``: ``policy`` with its goal chosen by inference.

    Args:
        policy: Any ``observation -> action`` callable.
        env: The env it acts in (wrapped or not); its ``unwrapped.goal`` is moved.
        spec: The nominal socket the inference starts from; default the env's
            ``nominal_socket``.
        sigma: Prior std of each pin's offset (mm) of the bent-pin prior; default the env's
            ``defect_sigma``. Not needed with ``model``, which holds its own prior.
        contact: Use the per-pin touch sensors and touch points as evidence (MuJoCo
            backend only).
        surface_tol: ``|ẑ|`` (mm) up to which the pins count as on the board top.
        lift_steps: Control steps of full-speed lift (0.625 mm each) after every blocked
            attempt, before the wrapped policy takes over again.
        inference: False: lift and retry at the same goal (the ablation without inference).
        touch_force: Touch-sensor reading (N) above which a pin counts as blocked.
        max_replans: Re-plans per episode at most.
        n_samples: Posterior samples.
        model: Infer with the defect model (:class:`~tolins.inference.posterior.DefectModel`:
            bends, pitch error, burrs, a blocked hole, a grasp error) instead of the bent-pin
            prior; then the wrapper stops re-planning once a goal search says the workpiece
            is not insertable (:attr:`not_insertable`).
    """

    def __init__(
        self,
        policy: Policy,
        env,
        *,
        spec: CircularSocket | None = None,
        sigma: float | None = None,
        contact: bool = True,
        surface_tol: float = 0.3,
        lift_steps: int = 1,
        inference: bool = True,
        touch_force: float = 0.05,
        max_replans: int = 8,
        n_samples: int = 1000,
        model: DefectModel | None = None,
    ) -> None:
        self.policy = policy
        self.env = env.unwrapped
        self.spec = self.env.nominal_socket if spec is None else spec
        sigma = self.env.defect_sigma if sigma is None else sigma
        if model is None and (sigma is None or not sigma > 0):
            raise ValueError(
                f"sigma={sigma!r}; allowed: > 0 (or an env with defect_sigma, or a model)"
            )
        self.sigma = float("nan") if sigma is None else float(sigma)
        self.contact = bool(contact)
        self.surface_tol = float(surface_tol)
        self.lift_steps = int(lift_steps)
        self.inference = bool(inference)
        self.touch_force = float(touch_force)
        self.max_replans = int(max_replans)
        self.n_samples = int(n_samples)
        self.model = model
        self.base_goal = self.env.goal
        noise = np.asarray(self.env.measurement_noise, dtype=float)[:3]
        self.noise = noise if np.any(noise > 0) else None
        self.reset()

    def reset(self, seed: int | None = None) -> None:
        """Start a new workpiece: base goal, empty history, inference RNG from ``seed``."""
        self.env.goal = self.base_goal
        self.history = History.empty(self.noise)
        self.rng = np.random.default_rng(seed)
        self.goals: list[np.ndarray] = []
        self.results: list = []
        self._lifting = 0

    @property
    def replans(self) -> int:
        return len(self.goals)

    @property
    def not_insertable(self) -> bool:
        """Whether the inference (with ``model``) said no goal inserts this workpiece."""
        return any(result.not_insertable for result in self.results)

    def blocked(self, observation: np.ndarray) -> bool:
        """Whether ``observation`` shows the pins pushed onto the board top."""
        return bool(
            observation[7] > self.env.collision_force and abs(observation[3]) <= self.surface_tol
        )

    def __call__(self, observation: np.ndarray) -> np.ndarray:
        observation = np.asarray(observation, dtype=float)
        if self._lifting > 0:
            self._lifting -= 1
            return self._lift()
        if not self.blocked(observation):
            return self.policy(observation)
        if self.inference and self.replans < self.max_replans and not self.not_insertable:
            self._replan(observation[:3] + self.env.goal - self.base_goal)
        self._lifting = self.lift_steps - 1
        return self._lift() if self.lift_steps else self.policy(observation)

    def _lift(self) -> np.ndarray:
        return np.array([0.0, 0.0, 0.0, A_MAX[3]])

    def _replan(self, pose: np.ndarray) -> None:
        """Record a blocked attempt at the measured ``pose`` and move the goal."""
        pins = bearings = None
        if self.contact and self.env.backend.supports_touch_points:
            forces = self.env.backend.pin_forces()
            pins = forces > self.touch_force
            if not pins.any():  # the board pushes back: at least the most loaded pin
                pins[int(np.argmax(forces))] = True
            bearings = touch_bearings(self.env.backend, pins)
        self.history = self.history.append(pose, False, pins, bearings)
        result = next_goal(
            self.spec,
            self.history,
            self.sigma,
            self.rng,
            n_samples=self.n_samples,
            model=self.model,
        )
        self.results.append(result)
        stay = result.discard or result.not_insertable
        goal = self.env.goal if stay else self.base_goal + result.goal
        self.goals.append(goal)
        self.env.goal = goal

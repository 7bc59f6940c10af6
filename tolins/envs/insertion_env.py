"""The insertion environment: the paper's task interface over a choice of simulators."""

from __future__ import annotations

from typing import Any, ClassVar

import gymnasium as gym
import numpy as np

from tolins.envs.actions import check_action
from tolins.envs.episode_state import EpisodeState
from tolins.envs.rendering import FRAME_SIZE, close_renderer, draw_frame, open_renderer
from tolins.envs.task_settings import (
    SettingsAttributes,
    TaskSettings,
    check_capabilities,
    keywords_of,
)
from tolins.geometry.specs import SocketSpec
from tolins.geometry.validation import is_seed
from tolins.paper import A_MAX
from tolins.physics import BACKENDS, Backend, make_backend, simulator

__all__ = ["BACKENDS", "ENV_KEYWORDS", "InsertionEnv"]


def check_reset_seed(seed: object) -> int | None:
    """``seed`` as gymnasium's ``reset`` takes it (``None`` or a Python int); ``ValueError``
    unless it is ``None`` or an integer ≥ 0 (numpy's as well, as the vector env takes them;
    a bool is not a seed)."""
    if seed is None:
        return None
    if not is_seed(seed):
        raise ValueError(f"seed={seed!r} is not a seed; allowed: None or an int ≥ 0")
    return int(seed)


class InsertionEnv(gym.Env, SettingsAttributes):
    """Insert a workpiece's pins into a socket's holes (the paper's task).

    ``InsertionEnv(socket, *, backend="mujoco", goal=(0, 0, 0), render_mode=None,
    **settings)``: ``socket`` the nominal :class:`~tolins.geometry.specs.CircularSocket` or
    :class:`~tolins.geometry.specs.PolygonSocket`; ``backend`` the simulator (``"mujoco"``
    or ``"kinematic"``, :data:`~tolins.physics.registry.BACKENDS`); ``goal`` ``[x*, y*,
    θ*]``; ``render_mode`` ``None`` or ``"rgb_array"``. Every other keyword is a setting of
    the task, an attribute of :class:`~tolins.envs.task_settings.TaskSettings` (whose
    docstring gives each one's meaning and default: ``measurement_noise``, ``horizon``,
    ``control_dt``, ``reward_mode``, ``physics_version``, ``robot``, …), validated there
    once and readable as an attribute of the env (``env.horizon``; all at once:
    ``env.settings``); :data:`ENV_KEYWORDS` lists every keyword. The sections below say
    what they do in the episode.

    **Task.** A workpiece with one or more pins starts above a board and must be
    moved by velocity commands until its pins are inside their holes. It moves in
    x, y, z and rotates by theta about the vertical axis (rotation about the board
    origin, then translation).

    **Action** ``[ux, uy, utheta, uz]``: velocities in mm/s and rad/s, a
    ``Box(-a_max, a_max)`` with the paper's ``a_max = [2.5, 2.5, 0.1, 2.5]``.
    Larger values are clipped; NaN, inf, bools, strings and complex numbers raise
    ``ValueError`` and leave the state untouched. Each action is held for ``control_dt``
    = 0.25 s.

    **Observation** (8 floats, float64):

    ===  ===========  =====================================================
    idx  name         meaning
    ===  ===========  =====================================================
    0-2  x̂−x*, ŷ−y*,  measured pose minus the goal ``[x*, y*, θ*]`` (mm, rad)
         θ̂−θ*
    3    ẑ            measured height of the pin tips over the board (mm)
    4-5  F̂x, F̂y       horizontal force of the board on the workpiece (N)
    6    q̂θ           torque of the board about the vertical axis (N·mm)
    7    F̂z           vertical force of the board on the workpiece (N)
    ===  ===========  =====================================================

    Pose measurements carry Gaussian noise of std ``measurement_noise``
    (``[x, y, theta, z]``, default the paper's ``[0.1, 0.1, 0, 0.1]``); forces carry
    ``force_noise`` (``[Fx, Fy, q_theta, Fz]``, default 0). ``0`` turns either off.

    **Success**: every pin is inside its own hole: the pin tips are at least
    ``success_depth`` (default 1 mm) below the board's top, ``z ≤ -success_depth``, and
    each pin's axis lies within its hole's circumradius
    (:func:`tolins.geometry.workspace.in_holes`, the same on both backends and in
    dm_control). Success terminates the episode; stepping an ended episode (success,
    horizon or fault) raises ``gymnasium.error.ResetNeeded``.

    **Workspace**: the servos hold ``|x|, |y| ≤ 5`` mm, ``|theta| ≤ 0.3`` rad and
    ``-4 ≤ z ≤ 40`` mm (:mod:`tolins.geometry.workspace`); the MuJoCo board covers every
    place a pin can reach within it, and the carrier plate above the pins stops on the
    board's top. ``reset`` raises ``ValueError`` for a pose outside this range or with a
    pin inside the board, and for a goal more than 2 mm / 0.15 rad from the nominal one.
    ``control_dt`` must be a whole number of 1 ms physics steps in [2 ms, 1 s] (in one
    physics step the re-anchored servos cannot move the workpiece). A ``robot`` holds the
    pose it commands in the same range (its target stops at the edge, as the servos'
    joints do); its part is off that by the arm's lag and the part's offset in the hand.
    A socket's holes lie within 100 mm of its centre
    (:data:`~tolins.geometry.specs.MAX_EXTENT`; its spec refuses more).

    **Collision**: a control step with a collision is one in which the summed normal
    force of all contacts between the board and the pins exceeded ``collision_force``
    (default 0.5 N) at any of the backend's checks during the step (on the MuJoCo
    backend ``min(5, physics steps)`` reads, five 50 steps apart at the default 0.25 s).
    A sum of normal forces cannot cancel out, so a pin wedged by a rotation (zero net
    force, non-zero torque) is a collision too.
    The ``kinematic`` backend (the paper's simulator, docs/tolerance.md) reports a
    binary 1 N on a step that collides (the motion into the obstacle stops, the rest of
    the step slides along it).

    **Reward** (``reward_mode``, ManiSkill3's names; success and collision are the same in
    every mode, and ``info`` has every term, ``reward_*``, summing to the reward):

    * ``"sparse"`` (default, the paper's, Table 1): ``reward_success + reward_collision``,
      ``c (1 - k / k_max)`` with c = 100 on the step ``k`` (1-based) that succeeds, and
      -1 on every step with a collision.
    * ``"dense"``: sparse plus four shaping terms of the true pose, each ≤ 0 and near 0
      only once every pin is ``success_depth`` deep in its hole, centred (so no term pays
      for hovering, pushing on the board or leaving it, and success always beats staying
      in the episode): ``reward_approach = -min(d / 5 mm, 1)`` (``d``: mean horizontal
      distance of the pins to their holes; a polygon peg's vertices, theta modulo its
      symmetry); ``reward_height = -clip(z, 0, 20 mm) / 20 mm`` (pin tips over the board's
      top); ``reward_alignment = -u / (1 + u)``, ``u`` the share of the clearance used (0
      centred, ``u ≤ 1`` exactly when every pin is over its own hole);
      ``reward_depth = -0.5 (1 - aligned · clip(-z, 0, success_depth) / success_depth)``
      (insertion depth, counted only while aligned).
    * ``"normalized_dense"``: the dense reward mapped affinely onto [0, 1]:
      ``(r - lo) / (hi - lo)``, ``lo = -3.5 - 1``, ``hi = c``; each term is scaled and
      ``reward_offset`` holds the shift. With success ending the episode the shift is a
      small per-step bonus for staying in it; learn with ``dense`` (measured: SB3 SAC
      and PPO insert on MuJoCo from ``dense`` within 15k and 100k env steps, from
      ``sparse`` and ``normalized_dense`` not within 15k; benchmarks/README.md).

    ``reward_offset`` is 0 and the shaping terms are 0 in the sparse mode. See
    :mod:`tolins.envs.reward`.

    **Horizon**: the episode is truncated after ``horizon`` = 40 steps. A simulator
    fault (a MuJoCo warning or a non-finite state) also truncates it, with the
    previous observation and ``info["error"]``.

    **Randomisation**: ``reset()`` draws the initial pose from ``initial_pose``
    (see :class:`InitialPoseDistribution`) around the goal, or takes
    ``options={"pose": [x, y, theta, z]}``; ``options={"goal": [x*, y*, θ*]}`` moves
    the goal of that episode only (gymnasium's convention: options apply to one reset;
    ``env.goal = ...`` moves it for the running episode and the later ones). With
    ``defect_sigma``, every reset draws a new bent-pin workpiece (per-pin offsets ~ N(0,
    sigma² I), mm) from the nominal circular ``socket``; ``defects=(kind, sigma)`` draws
    another kind after it (``"pitch"``, ``"burr"``, ``"short"``, ``"blocked"``:
    :func:`~tolins.geometry.defects.sample_defects`); the episode's workpiece is the
    reset's ``info["workpiece"]``. ``randomization`` (``None`` by
    default: the paper's fixed physics; ``"default"``, a dict of ranges or a
    :class:`~tolins.physics.randomization.PhysicsRandomization`) draws friction, contact
    stiffness, servo gains and force limit, force-sensor bias and noise and the
    initial-pose spread per episode, after the workpiece and before the pose; the values
    are in the reset's ``info["physics"]``. ``reset``'s ``seed`` is ``None`` or an integer
    ≥ 0 (numpy's too; a bool raises, as in the vector env). ``reset`` validates every
    option before it changes anything: a failed reset raises ``ValueError``, leaves the
    episode as it was, and ``step`` raises ``gymnasium.error.ResetNeeded`` until a reset
    succeeds.

    **Info**: ``success``, ``is_success``, ``collision``, ``n_collisions``, ``pose``
    (true ``[x, y, theta, z]``), ``wrench`` (true ``[Fx, Fy, q_theta, Fz]``),
    ``peak_force``, ``step``, ``goal``, the reward terms ``reward_success``,
    ``reward_collision``, ``reward_approach``, ``reward_height``, ``reward_alignment``,
    ``reward_depth``, ``reward_offset``, and ``error`` after a fault. With a robot, also
    ``sensed_pose`` and ``sensed_wrench`` (what the observation measures) and, at a reset
    with ``grasp_error``, ``grasp_error`` (the drawn offset in the hand). With
    ``pins="elastic-plastic"``, also ``pin_bend`` and ``pin_deflection`` (each pin's
    permanent and present tip offset, ``(n_pins, 2)`` mm), ``damaged`` and ``damaged_at``
    (the step a pin passed ``damage_threshold``), and ``reward_damage`` with a
    ``damage_penalty``.

    **Robot** (``robot``): ``"free"`` (the default), the paper's ideal servos on a
    free-floating workpiece; ``"panda"`` (``pip install 'tolins[robot]'``; the ids
    ``tolins/{name}Panda-v2`` and ``-v3``), a Franka Panda holding it by friction under a task-space
    impedance law that tracks the same actions (:mod:`tolins.physics.panda`, docs/robot.md).
    The observation then measures what the robot senses: the pose from the arm's forward
    kinematics and the nominal grasp, the wrench from its wrist sensor less the weight
    of the hand and the part; ``info["pose"]`` and ``info["wrench"]`` stay the truth, and
    success is judged on the true pose. ``grasp_error`` (three stds ``[x, y, yaw]``, mm, mm,
    rad; a single number is refused) puts the part off in the hand every episode.

    **Closing**: ``close()`` releases the simulation and the renderer; a later ``reset``,
    ``step`` or ``render`` raises ``gymnasium.error.ClosedEnvironmentError`` (closing twice
    is harmless). ``step`` before the first ``reset`` raises ``gymnasium.error.ResetNeeded``,
    as gymnasium's ``OrderEnforcing`` does. A keyword the env does not take raises
    ``ValueError`` naming it and the allowed ones.

    **Physics version** (``physics_version``, the ids' ``-v1``, ``-v2`` and ``-v3``;
    :mod:`tolins.physics.versions`): 1, the default of the generic constructor, or 2;
    3 with ``robot="panda"`` only.

    Version history:

    * v2, after tolins 0.6.0: ``pins="elastic-plastic"`` (round pins that bend and stay
      bent, ``pin_material``, ``damage_threshold``, ``damage_penalty``, ``keep_part``;
      ``info["pin_bend"]``, ``info["pin_deflection"]``, ``info["damaged"]``) and its ids
      ``tolins/{name}Delicate-v2`` (docs/delicate.md), with the free body or the Panda
      holding the part (the Panda's ids ``tolins/{name}DelicatePanda-v3``); rigid pins,
      the default, unchanged bit for bit.
    * v2 and v3, after tolins 0.6.0: the Panda's law compiled (numba, the numpy law the
      fallback): the same law within rounding, its torques within 1e-9 of numpy's; the
      last bits of every Panda episode change, and 3 of 1,600 expert episodes end
      otherwise, all at 50 µm (``benchmarks/panda_law_equivalence.py``), as numpy's own
      BLAS kernels change them from one CPU family to another.
    * v2 and v3, later in 0.6.0: the Panda's target stops at the workspace's edge, as
      the free body's joints do (an episode whose target stays inside is unchanged bit
      for bit); a single-number ``grasp_error``, a bool ``seed`` and a socket reaching
      beyond 100 mm are refused.
    * v3 (tolins 0.6.0, the Panda's only): the Panda's pads hold the handle through
      stiffer contacts (the part creeps about 12 µm in the hand over an episode instead of
      about 90) and its law is eight times as stiff along x and y; version 2's compliant
      arm stays as it was, bit for bit. At 50 µm both experts then insert within 0.05 of
      the free body on the 2*2, the 2*8 and the square (100 episodes each; on v2 the arm
      was 0.07–0.17 below). A randomised ``servo_gain`` may reach 2 (beyond, the law
      rings and the part is lost).

    * v2 (tolins 0.5.0): faster MuJoCo physics, the same task. The board's pieces sit in
      the world body, and a control step in which no part of the workpiece can reach the
      board or a joint limit (from the pose, the commanded velocity and the servos'
      overshoot, :mod:`tolins.physics.free_flight`) runs on 5 ms physics steps instead of
      the 1 ms contact step (the finer grades, whose jams turn on the state's last bits,
      keep their contact step). Free flight ends within 1e-8 µm of v1's state; over 8,000
      expert, random and π_n episodes of every paper preset, the grades, each defect kind
      and randomised physics (``benchmarks/v2_equivalence.py``) 12 (0.15 %) ended
      otherwise, each parting in contact on the contact step from a femtometre apart: v1
      itself changes 89 of them (1.1 %) when its start moves 1e-12 mm. What it may move
      is such a contact decided by the state's last bits, and the digits of forces and
      poses. The kinematic backend is the same in both.
    * v2, after tolins 0.6.0: ``robot="panda"`` and its ids ``tolins/{name}Panda-v2`` (a
      Franka Panda holds the part); ``robot="free"``, the default, is unchanged bit for
      bit. Later in 0.6.0 the Panda's fingers got flat pads and close on a weightless
      part (a soft weld and the model files' rounded finger capsules had left the grasp
      tens of µm off where the robot believes it).
    * v1 (tolins 0.3.0): success requires every pin inside its own hole (not only
      ``z ≤ -success_depth``); the workpiece's joints keep every pin over the board and
      the carrier collides with the board's top; reset poses and goals are validated;
      stepping after the episode ended raises; ``reward_mode`` (the default,
      ``sparse``, is the paper's reward as before).
    * v1, tolins 0.4.0 (default outcomes bit-identical to 0.3.0): ``options={"goal":
      ...}`` applies to one episode (it used to persist; ``env.goal = ...`` still moves
      the running episode's goal and the later ones'); a failed reset changes nothing and
      the next step raises ``ResetNeeded``; every setting is validated (real numbers
      only, ``success_depth < 4``, ``defect_sigma`` bounded with invalid bent-pin draws
      re-drawn, ``control_dt ≥ 2 ms``); ``randomization``; ``info["workpiece"]`` at
      reset; ``tolins.make_vec`` / ``gym.make_vec`` give the batched
      :class:`~tolins.envs.vector.InsertionVectorEnv`, bit-identical per env.
    * v0 (tolins 0.1.0): the first release.
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["rgb_array"], "render_fps": 4}

    def __init__(
        self,
        socket: SocketSpec,
        *,
        backend: str = "mujoco",
        goal: Any = (0.0, 0.0, 0.0),
        render_mode: str | None = None,
        **settings: Any,
    ) -> None:
        self.settings = TaskSettings.build(InsertionEnv, socket, settings)
        simulator(backend, single=True, robot=self.settings.robot)
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise ValueError(f"render_mode={render_mode!r}; allowed: None, 'rgb_array'")
        check_capabilities(self.settings, backend, single=True)
        self.backend_name = backend
        self.render_mode = render_mode
        self.action_space = gym.spaces.Box(-A_MAX, A_MAX, dtype=np.float64)
        self.observation_space = gym.spaces.Box(-np.inf, np.inf, shape=(8,), dtype=np.float64)
        self.backend: Backend | None = make_backend(
            backend,
            socket,
            self.control_dt,
            self.settings.version,
            self.settings.robot,
            self.settings.elastic,
        )
        self._episode = EpisodeState(self.settings, goal)
        self._renderer = None
        self._closed = False

    @property
    def goal(self) -> np.ndarray:
        """The goal ``[x*, y*, theta*]`` (mm, rad) the observation is measured from; setting
        it moves the running episode's goal and that of every later reset naming none."""
        return self._episode.goal

    @goal.setter
    def goal(self, value: Any) -> None:
        self._episode.goal = value

    @property
    def socket(self) -> SocketSpec:
        """The workpiece of the current episode (a bent-pin draw with ``defect_sigma``)."""
        return self._episode.socket

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        self._check_open()
        super().reset(seed=check_reset_seed(seed))
        plan = self._episode.plan(self.np_random, options)
        if plan.socket is not self.backend.spec:
            self.backend.set_socket(plan.socket)
            self._close_renderer()  # it draws the previous workpiece's model
        plan.apply_physics(self.backend.set_physics)
        plan.apply_grasp(lambda grasp: self.backend.set_grasp(grasp))
        state = self.backend.reset(plan.pose, keep_part=plan.keep_part)
        return self._episode.begin(plan, state, self.np_random)

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        self._check_open()
        self._episode.check_running()
        state = self.backend.step(check_action(action))
        return self._episode.advance(state, self.np_random)

    def render(self) -> np.ndarray | None:
        """The ``rgb_array`` frame ``(480, 640, 3)`` of the current state, or ``None`` without
        ``render_mode="rgb_array"``."""
        self._check_open()
        if self.render_mode != "rgb_array":
            return None
        if self._renderer is None:
            self._renderer = open_renderer(self.backend.model, *FRAME_SIZE)
        return draw_frame(self._renderer, self.backend.data)

    def __getstate__(self) -> dict[str, Any]:
        # The renderer holds an OpenGL context, which cannot be copied; render() makes anew.
        return {**self.__dict__, "_renderer": None}

    def close(self) -> None:
        """Release the simulation (model and data) and the renderer. A later ``reset``,
        ``step`` or ``render`` raises ``gymnasium.error.ClosedEnvironmentError``; closing
        again does nothing."""
        self._close_renderer()
        self.backend = None
        self._closed = True

    @property
    def closed(self) -> bool:
        """Whether :meth:`close` has released the simulation."""
        return self._closed

    def _check_open(self) -> None:
        """``gymnasium.error.ClosedEnvironmentError`` once the env is closed."""
        if self._closed:
            raise gym.error.ClosedEnvironmentError(
                "this InsertionEnv is closed: close() released its simulation; make a new env"
            )

    def _close_renderer(self) -> None:
        if self._renderer is not None:
            close_renderer(self._renderer)
            self._renderer = None


#: Every keyword ``InsertionEnv`` takes: its own, then the settings'.
ENV_KEYWORDS = keywords_of(InsertionEnv)

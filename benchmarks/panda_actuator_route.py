"""The Panda's law as MuJoCo actuators: a measured prototype against the compiled law.

Usage::

    python benchmarks/panda_actuator_route.py [--episodes 100]
        [--presets Circle2x2,Circle2x8,Square] [--cost-episodes 10]
        [--cost-presets Circle2x2,Circle2x2Fit50] [--skip cost,creep,success]
        [--inertia decoupled|diagonal] [--no-yaw-feedforward]

Results and what they mean for the route: ``benchmarks/README.md``, "The law as MuJoCo
actuators".

Issue 47's second route, built here and not as an env version: the ``-v3`` Panda world
tolins generates for a workpiece (:func:`tolins.mjcf.panda.panda_world`), its Python/numba
law replaced by actuators that MuJoCo computes inside ``mj_step``:

- per task axis (x, y, z and the three rotations of the grip site, measured in a world
  site's frame through ``refsite``) an integrating position actuator (``dyntype``
  integrator: its activation is the target, its control the commanded twist, its
  ``actrange`` the workspace, :func:`tolins.physics.panda.target_range`) whose force
  ``Kp (target − length)`` is limited by ``forcerange`` to the law's spring limit (20 N
  sideways, 5 N up and down), and a velocity actuator ``Kd (v* − v)`` (the law's damping
  and feed-forward); ``Kp`` and ``Kd`` are the ``-v3`` law's gains (s⁻²) times an
  inertia per axis from its task inertia ``Λ`` at the first reset's grasp
  (``--inertia``, :data:`INERTIAS`; no cross terms: the one thing the law has that a site
  actuator cannot);
- ``gravcomp`` on the arm's bodies with ``actuatorgravcomp`` on its joints, and the
  joints' ``actuatorfrcrange`` at the Franka's torque limits (87 / 12 N·m), so that all
  actuator torques on a joint together stay within its motor's limit, as the law clips;
- a constant upward force at the grip site for the held part's weight (the law's ``m g``);
- the posture held by weak joint position actuators (the law's ``kq = 20 s⁻²`` times the
  joint inertia's diagonal), acting on the whole arm, not in the null space.

The target is moved as tolins' Panda moves it: once a control step, Python keeps it
within one control step's travel of the grip site (``PandaSimulations._anchor``) and
writes it into the activations; within the step the activations integrate the twist and
stop at the workspace's edge (``actrange``) where the law's update clips its target. The
rest (reset, grasp, fingers, observation, reward) is the ``-v3`` env's own.

Measured, for each preset and its 50 µm grade and both experts, on the same seeds:
(a) success (and mean steps) on the free body ``tolins/{name}-v2``, the compiled-law
``tolins/{name}Panda-v3`` and the actuator prototype, with the binomial standard error;
(b) the thread CPU time (``time.thread_time``) of a control step on the cost presets: the
free body, ``-v3`` with the law in numpy, ``-v3`` compiled, its physics alone (time in
``mj_step``, a second pass so that the timer's calls are not in the first), and the
prototype (its step and its time in ``mj_step``), with the ratios; (c) the limits: the
closest any arm joint came to its range, the largest total actuator torque on a joint
over its motor's limit (sampled at every contact read, 5 per control step) and the share
of samples at it, and the share with a Cartesian spring at its force limit; and a probe:
how far the part moves in the hand over one control step that moves and turns
(:func:`creep_table`).
"""

from __future__ import annotations

import argparse
import functools
import math
import time

import gymnasium as gym
import mujoco
import numpy as np
from panda_step_cost import Timed  # a callable timed while installed

import tolins  # noqa: F401  (registers the ids)
from tolins.mjcf.panda import ARM_JOINTS, GRAVITY, GRIP_SITE, PREFIX, panda_world
from tolins.physics.arm import Arm
from tolins.physics.panda import (
    LAW_RATE,
    PandaSimulations,
    default_gains,
    update_plan,
)
from tolins.physics.servo import run_plan
from tolins.policies import EXPERTS

#: The world site the grip site's actuators measure from: at the board's centre, its
#: frame the grip frame at yaw 0 (x along x, z down), so that rotations stay near 0.
REFSITE = "actuator_route_ref"
#: Gears in the refsite frame (x, −y, −z are the world's x, y, z) giving lengths along the
#: world's x, y, z and rotations about them: an actuator's length is the grip site's world
#: coordinate, yaw included.
GEARS = np.array(
    [
        [1, 0, 0, 0, 0, 0],
        [0, -1, 0, 0, 0, 0],
        [0, 0, -1, 0, 0, 0],
        [0, 0, 0, 1, 0, 0],
        [0, 0, 0, 0, -1, 0],
        [0, 0, 0, 0, 0, -1],
    ],
    dtype=float,
)
#: The order of a target ``[x, y, z, yaw]`` of :func:`~tolins.physics.panda.target_range`
#: among the six axes.
TARGET_AXES = (0, 1, 2, 5)


#: How each axis's gains are scaled from the law's (s⁻²) to a force per unit error:
#: ``decoupled``: by ``1 / (Λ⁻¹)ᵢᵢ``, the inertia the grip site shows to a force along that
#: axis alone (every axis then has the law's natural frequency, 400 rad/s sideways); or
#: ``diagonal``: by ``Λᵢᵢ``, the law's own stiffness along each axis with the others held
#: (7.4 kg along x against 0.96 decoupled: the coupled modes reach 1,100–1,180 rad/s).
INERTIAS = ("decoupled", "diagonal")


def task_inertia(env, inertia: str = "decoupled") -> np.ndarray:
    """Per task axis, the inertia (kg, kg·mm²) the gains are scaled by (:data:`INERTIAS`),
    from the law's ``Λ = (J M⁻¹ Jᵀ)⁻¹`` at ``env``'s grasp now."""
    sims = env.backend._batch.sims
    arm, data = sims.arm, sims.datas[0]
    jac = arm.jacobian(data)
    mobility = jac @ np.linalg.solve(arm._arm_mass(data), jac.T)
    if inertia == "diagonal":
        return np.diag(np.linalg.inv(mobility))
    return 1.0 / np.diag(mobility)


def joint_inertia(env) -> np.ndarray:
    """The diagonal of the arm's joint-space inertia at ``env``'s grasp now."""
    sims = env.backend._batch.sims
    return np.diag(sims.arm._arm_mass(sims.datas[0]))


def actuator_world(env, lam: np.ndarray, inertia: np.ndarray) -> tuple[mujoco.MjModel, dict]:
    """``env``'s ``-v3`` Panda world with the law as actuators (see the module docstring):
    the compiled model and the actuator ids by role."""
    batch = env.backend._batch
    version = batch.version
    gains = default_gains(version)
    spec = panda_world(
        env.nominal_socket, board_body=not version.board_in_world, firm_grip=version.firm_grip
    )
    limits = batch.arm.limit  # the motors' torque limits (model units)
    for body in spec.bodies:
        if body.name.startswith(PREFIX) and not body.name.endswith("link0"):
            body.gravcomp = 1.0
    for name, limit in zip(ARM_JOINTS, limits, strict=True):
        joint = spec.joint(PREFIX + name)
        joint.actgravcomp = True
        joint.actfrclimited = mujoco.mjtLimited.mjLIMITED_TRUE
        joint.actfrcrange = [-limit, limit]
    spec.worldbody.add_site(name=REFSITE, pos=[0.0, 0.0, 0.0], quat=[0.0, 1.0, 0.0, 0.0])
    low, high = batch.sims._bounds
    stiffness = np.asarray(gains.stiffness) * lam
    damping = gains.damping * lam
    force_limit = np.r_[gains.force_limit, [np.inf] * 3]

    def site_actuator(name: str, gear: np.ndarray) -> mujoco.MjsActuator:
        actuator = spec.add_actuator(name=name)
        actuator.trntype = mujoco.mjtTrn.mjTRN_SITE
        actuator.target = PREFIX + GRIP_SITE
        actuator.refsite = REFSITE
        actuator.gear = gear
        actuator.gaintype = mujoco.mjtGain.mjGAIN_FIXED
        actuator.biastype = mujoco.mjtBias.mjBIAS_AFFINE
        actuator.ctrllimited = mujoco.mjtLimited.mjLIMITED_FALSE
        return actuator

    for axis in range(6):
        spring = site_actuator(f"spring{axis}", GEARS[axis])
        spring.dyntype = mujoco.mjtDyn.mjDYN_INTEGRATOR  # act: the target, ctrl: its rate
        spring.gainprm = [stiffness[axis]] + [0.0] * 9
        spring.biasprm = [0.0, -stiffness[axis], 0.0] + [0.0] * 7
        if axis in TARGET_AXES:
            r = TARGET_AXES.index(axis)
            spring.actlimited = mujoco.mjtLimited.mjLIMITED_TRUE
            spring.actrange = [low[r], high[r]]
        if np.isfinite(force_limit[axis]):
            spring.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
            spring.forcerange = [-force_limit[axis], force_limit[axis]]
        damper = site_actuator(f"damper{axis}", GEARS[axis])
        damper.gainprm = [damping[axis]] + [0.0] * 9
        damper.biasprm = [0.0, 0.0, -damping[axis]] + [0.0] * 7
    weight = site_actuator("payload", GEARS[2])  # ctrl: the held weight, up (mN)
    weight.gainprm = [1.0] + [0.0] * 9
    weight.biasprm = [0.0] * 10
    for name, m_jj in zip(ARM_JOINTS, inertia, strict=True):
        hold = spec.add_actuator(name=f"posture_{name}")
        hold.trntype = mujoco.mjtTrn.mjTRN_JOINT
        hold.target = PREFIX + name
        hold.gaintype = mujoco.mjtGain.mjGAIN_FIXED
        hold.biastype = mujoco.mjtBias.mjBIAS_AFFINE
        kp, kv = gains.null * m_jj, 2.0 * math.sqrt(gains.null) * m_jj
        hold.gainprm = [kp] + [0.0] * 9
        hold.biasprm = [0.0, -kp, -kv] + [0.0] * 7
    model = spec.compile()
    ids = {
        "spring": np.array([model.actuator(f"spring{a}").id for a in range(6)]),
        "damper": np.array([model.actuator(f"damper{a}").id for a in range(6)]),
        "payload": model.actuator("payload").id,
        "posture": np.array([model.actuator(f"posture_{n}").id for n in ARM_JOINTS]),
    }
    ids["act"] = model.actuator_actadr[ids["spring"]]
    ids["force_limit"] = force_limit
    return model, ids


class Limits:
    """What a route's arm came to: joint range margins, joint torques against the motors'
    limits, Cartesian springs against their force limits."""

    def __init__(self) -> None:
        self.margin = np.inf
        self.torque = 0.0
        self.samples = self.at_torque = self.at_force = 0

    def joints(self, arm: Arm, data: mujoco.MjData) -> None:
        q = data.qpos[arm.qpos]
        room = np.minimum(q - arm.range[:, 0], arm.range[:, 1] - q)
        self.margin = min(self.margin, float(room.min()))

    def torques(self, tau: np.ndarray, limit: np.ndarray, spring_saturated: bool) -> None:
        share = np.abs(tau) / limit
        self.torque = max(self.torque, float(share.max()))
        self.samples += 1
        self.at_torque += int(np.any(share >= 1 - 1e-9))
        self.at_force += int(spring_saturated)


def install_actuators(env, limits: Limits, inertia: str = "decoupled") -> None:
    """Run ``env`` (a ``-v3`` Panda env, reset once) on the actuator world, its gains
    scaled by ``inertia`` (:data:`INERTIAS`)."""
    lam = task_inertia(env, inertia)
    inertia = joint_inertia(env)
    model, ids = actuator_world(env, lam, inertia)
    batch = env.backend._batch
    arm = Arm(model, batch.arm.gains)
    old = batch.sims
    sims = PandaSimulations(arm, [model], [mujoco.MjData(model)], old.nstep * model.opt.timestep)
    # The law's update once a control step (the target handed to the activations); the
    # physics steps in the contact reads' chunks alone.
    sims.every = sims.nstep
    sims.plan = update_plan(sims.nstep, sims.checks, sims.nstep)
    sims.grasp = old.grasp
    spring, damper, act = ids["spring"], ids["damper"], ids["act"]
    low, high = sims._bounds
    limited = np.isfinite(ids["force_limit"])

    def update(i: int, advance: float, payload: float | None = None) -> None:
        data = sims.datas[i]
        held = sims._held_mass if payload is None else payload
        target = np.r_[sims.target[i], 0.0, 0.0, sims.yaw[i]]
        twist = sims.twist[i].copy()
        data.act[act] = target
        data.ctrl[spring] = twist
        # The law drops the feed-forward along an axis whose target it holds at the edge.
        for r, axis in enumerate(TARGET_AXES):
            edge = (target[axis] <= low[r] and twist[axis] < 0) or (
                target[axis] >= high[r] and twist[axis] > 0
            )
            if edge:
                twist[axis] = 0.0
        if not YAW_FEEDFORWARD[0]:
            twist[5] = 0.0
        data.ctrl[damper] = twist
        data.ctrl[ids["payload"]] = -held * GRAVITY[2]
        data.ctrl[ids["posture"]] = sims.posture[i]

    def step_one(i: int) -> float:
        model, data = sims.models[i], sims.datas[i]
        peak = 0.0

        def read() -> None:
            nonlocal peak
            force = sims._touch_of(i)
            if not force <= peak:
                peak = force
            saturated = np.abs(data.actuator_force[spring[limited]])
            at = bool(np.any(saturated >= ids["force_limit"][limited] * (1 - 1e-9)))
            limits.torques(data.qfrc_actuator[arm.dof], arm.limit, at)

        law = functools.partial(sims._update_law, i, sims._span)
        run_plan(model, data, sims.plan, law, read)
        sims.target[i] = data.act[act[:3]]
        sims.yaw[i] = data.act[act[5]]
        limits.joints(arm, data)
        return peak

    sims._update_law = update
    sims._step_one = step_one
    batch.sims, batch.arm, batch.model = sims, arm, model


def watch_law(env, limits: Limits) -> None:
    """Record the compiled law's torques against the motors' limits after every update."""
    sims = env.backend._batch.sims
    law = sims._update_law

    def counted(i: int, *args, **kwargs) -> None:
        law(i, *args, **kwargs)
        limits.torques(sims.datas[i].ctrl[sims.arm.motors], sims.arm.limit, False)

    sims._update_law = counted


#: The gain scaling :func:`make` gives the prototype (``--inertia``).
INERTIA = ["decoupled"]
#: Whether the prototype's yaw damper is commanded the twist's turn (``--no-yaw-feedforward``
#: drops it: the law's feed-forward on x, y and z alone).
YAW_FEEDFORWARD = [True]


def make(preset: str, route: str, limits: Limits | None = None, numpy_law: bool = False):
    """The env of a route: ``free`` (the free body), ``law`` (``-v3``, the compiled law, or
    numpy's with ``numpy_law``) or ``actuators`` (the prototype, gains by :data:`INERTIA`)."""
    if route == "free":
        return gym.make(f"tolins/{preset}-v2").unwrapped
    env = gym.make(f"tolins/{preset}Panda-v3").unwrapped
    limits = limits or Limits()
    if route == "actuators":
        env.reset(seed=0)  # the grasp whose task inertia sets the gains
        install_actuators(env, limits, INERTIA[0])
    else:
        env.backend._batch.sims.compiled = not numpy_law
        watch_law(env, limits)
    return env


def physics_clock() -> Timed:
    """``mujoco.mj_step`` timed on thread CPU time (installed by :func:`run`)."""
    return Timed(mujoco.mj_step, time.thread_time)


def run(env, expert: str, episodes: int, clock: Timed | None = None) -> dict[str, float]:
    """Outcomes and the thread CPU time per control step (ms) of ``episodes`` episodes."""
    successes, steps, faults, cpu, count = [], [], 0, 0.0, 0
    for seed in range(episodes):
        policy = EXPERTS[expert]()
        observation, info = env.reset(seed=seed)
        done = False
        while not done:
            action = policy(observation)
            if clock is not None:
                mujoco.mj_step = clock
            began = time.thread_time()
            try:
                observation, _, terminated, truncated, info = env.step(action)
            finally:
                cpu += time.thread_time() - began
                mujoco.mj_step = clock.function if clock is not None else mujoco.mj_step
            count += 1
            done = terminated or truncated or "error" in info
        successes.append(float(info["success"]))
        steps.append(info["step"])
        faults += int("error" in info)
    physics = None if clock is None else clock.seconds / count * 1e3
    return {
        "success": float(np.mean(successes)),
        "steps": float(np.mean(steps)),
        "faults": faults,
        "ms": cpu / count * 1e3,
        "physics_ms": physics,
        "n": episodes,
    }


def margin_of(env, limits: Limits) -> None:
    """The compiled law's joint margins are read after each step (see :func:`run_law`)."""
    sims = env.backend._batch.sims
    limits.joints(sims.arm, sims.datas[0])


def se(p: float, n: int) -> float:
    return math.sqrt(max(p * (1 - p), 0.0) / n)


def success_table(presets: list[str], episodes: int) -> list[tuple[str, str, Limits]]:
    print(
        f"\n**(a) Success over {episodes} episodes per cell** (seeds 0 …; ± binomial "
        "standard error of the prototype's rate)\n\n"
        "| preset | expert | free body | `-v3` compiled law | actuators | actuators − free "
        "| actuators − `-v3` | steps free / `-v3` / actuators | faults `-v3` / actuators "
        "| ms per step free / `-v3` / actuators |\n"
        "|---|---|--:|--:|--:|--:|--:|--:|--:|--:|"
    )
    limit_rows = []
    for name in presets:
        for preset in (name, f"{name}Fit50"):
            for expert in EXPERTS:
                law_limits, act_limits = Limits(), Limits()
                free = run(make(preset, "free"), expert, episodes)
                law_env = make(preset, "law", law_limits)
                law = run_law(law_env, expert, episodes, law_limits)
                act = run(make(preset, "actuators", act_limits), expert, episodes)
                print(
                    f"| {preset} | {expert} | {free['success']:.2f} | {law['success']:.2f} "
                    f"| {act['success']:.2f} ± {se(act['success'], episodes):.2f} "
                    f"| {act['success'] - free['success']:+.2f} "
                    f"| {act['success'] - law['success']:+.2f} "
                    f"| {free['steps']:.1f} / {law['steps']:.1f} / {act['steps']:.1f} "
                    f"| {law['faults']} / {act['faults']} "
                    f"| {free['ms']:.2f} / {law['ms']:.2f} / {act['ms']:.2f} |",
                    flush=True,
                )
                limit_rows.append((f"{preset} {expert}", "`-v3`", law_limits))
                limit_rows.append((f"{preset} {expert}", "actuators", act_limits))
    return limit_rows


def run_law(env, expert: str, episodes: int, limits: Limits, clock=None) -> dict[str, float]:
    """:func:`run` on a ``-v3`` env, its joint margins read after every control step."""
    step = env.step

    def stepped(action):
        out = step(action)
        margin_of(env, limits)
        return out

    env.step = stepped
    try:
        return run(env, expert, episodes, clock)
    finally:
        del env.step


def limits_table(rows: list[tuple[str, str, Limits]]) -> None:
    print(
        "\n**(c) Limits** (torques sampled after every law update for `-v3`, at every contact "
        "read for the actuators)\n\n"
        "| episodes | route | closest joint to its range (rad) | largest joint torque / motor "
        "limit | samples at a torque limit | samples with a spring at its force limit |\n"
        "|---|---|--:|--:|--:|--:|"
    )
    for label, route, lim in rows:
        force = "–" if route == "`-v3`" else f"{lim.at_force / max(lim.samples, 1):.1%}"
        print(
            f"| {label} | {route} | {lim.margin:.2f} | {lim.torque:.2f} "
            f"| {lim.at_torque / max(lim.samples, 1):.2%} | {force} |",
            flush=True,
        )


def cost_table(presets: list[str], episodes: int) -> None:
    print(
        f"\n**(b) Thread CPU time of a control step** (ms; {episodes} episodes per row, the "
        "same seeds for every column; physics: time in `mj_step`, a second pass)\n\n"
        "| preset | expert | free body | `-v3` numpy law | `-v3` compiled | its physics "
        "| actuators | their physics | `-v3` / its physics | actuators / `-v3` physics "
        "| actuators / `-v3` | numpy / actuators |\n"
        "|---|---|--:|--:|--:|--:|--:|--:|--:|--:|--:|--:|"
    )
    for preset in presets:
        for expert in EXPERTS:
            free = run(make(preset, "free"), expert, episodes)
            numpy_law = run(make(preset, "law", numpy_law=True), expert, episodes)
            law = run(make(preset, "law"), expert, episodes)
            law_physics = run(
                make(preset, "law"), expert, episodes, Timed(mujoco.mj_step, time.thread_time)
            )
            act = run(make(preset, "actuators"), expert, episodes)
            act_physics = run(
                make(preset, "actuators"), expert, episodes, Timed(mujoco.mj_step, time.thread_time)
            )
            physics = law_physics["physics_ms"]
            print(
                f"| {preset} | {expert} | {free['ms']:.2f} | {numpy_law['ms']:.2f} "
                f"| {law['ms']:.2f} | {physics:.2f} | {act['ms']:.2f} "
                f"| {act_physics['physics_ms']:.2f} | {law['ms'] / physics:.2f} "
                f"| {act['ms'] / physics:.2f} | {act['ms'] / law['ms']:.2f} "
                f"| {numpy_law['ms'] / act['ms']:.2f} |",
                flush=True,
            )


#: The probe's action: the safe expert's first on the 2*2 (seed 0), moving along x and y
#: and turning at once.
PROBE = np.array([1.34, -2.5, 0.1, 0.0])


def creep(route: str, no_yaw_feedforward: bool = False) -> np.ndarray:
    """How far (µm, the grip site's frame: along the pads, across, down the fingers) the
    part moves in the hand over one control step of :data:`PROBE` after seed 0's reset on
    the 2*2, and the largest rate (rad/s) at which the hand turns about its x (along the pads)
    and y (across them) axes over the step's second half: ``no_yaw_feedforward`` drops the
    prototype's yaw damper's command."""
    env = make("Circle2x2", route)
    sims = env.backend._batch.sims
    model, data = sims.models[0], sims.datas[0]
    part = model.joint("workpiece").qposadr[0]
    if no_yaw_feedforward:
        law, yaw = sims._update_law, model.actuator("damper5").id

        def update(i: int, *args, **kwargs) -> None:
            law(i, *args, **kwargs)
            data.ctrl[yaw] = 0.0

        sims._update_law = update

    def in_hand() -> np.ndarray:
        frame = data.site_xmat[sims.arm.site].reshape(3, 3)
        return frame.T @ (data.qpos[part : part + 3] - data.site_xpos[sims.arm.site])

    rates = []
    step = mujoco.mj_step

    def recorded(m, d, nstep=1):
        for _ in range(nstep):
            step(m, d)
            velocity = np.zeros(6)  # rotation, then translation, in the site's frame
            mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_SITE, sims.arm.site, velocity, 1)
            rates.append(np.abs(velocity[:2]))

    env.reset(seed=0)
    before = in_hand()
    sims.plan = tuple((count, update, True) for count, update, _ in sims.plan)
    mujoco.mj_step = recorded
    try:
        env.step(PROBE)
    finally:
        mujoco.mj_step = step
    turning = np.max(rates[len(rates) // 2 :], axis=0)
    return np.r_[(in_hand() - before) * 1e3, turning]


def creep_table() -> None:
    print(
        f"\n**The part in the hand over one control step of {PROBE.tolist()}** (2*2, seed "
        "0's reset; µm in the grip frame; the hand's largest turning rate about the grip frame's x "
        "and y axes over the step's second half)\n\n"
        "| route | along the pads | across | down the fingers | about x (rad/s) | about y |\n"
        "|---|--:|--:|--:|--:|--:|"
    )
    for label, route, drop in (
        ("`-v3` compiled law", "law", False),
        ("actuators", "actuators", False),
        ("actuators, no yaw feed-forward", "actuators", True),
    ):
        x, y, z, about_x, about_y = creep(route, drop)
        print(
            f"| {label} | {x:+.1f} | {y:+.1f} | {z:+.1f} | {about_x:.4f} | {about_y:.4f} |",
            flush=True,
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=100, help="per success cell")
    parser.add_argument("--presets", default="Circle2x2,Circle2x8,Square")
    parser.add_argument("--cost-episodes", type=int, default=10)
    parser.add_argument("--cost-presets", default="Circle2x2,Circle2x2Fit50")
    parser.add_argument("--skip", default="", help="comma list of: cost, creep, success")
    parser.add_argument("--inertia", choices=INERTIAS, default="decoupled")
    parser.add_argument("--no-yaw-feedforward", action="store_true")
    args = parser.parse_args()
    INERTIA[0] = args.inertia
    YAW_FEEDFORWARD[0] = not args.no_yaw_feedforward
    skip = set(filter(None, args.skip.split(",")))
    print(
        f"`-v3` law at {LAW_RATE} Hz; prototype gains scaled by the {args.inertia} task "
        f"inertia; yaw feed-forward {'on' if YAW_FEEDFORWARD[0] else 'off'}; "
        f"mujoco {mujoco.__version__}"
    )
    if "cost" not in skip:
        cost_table(args.cost_presets.split(","), args.cost_episodes)
    if "creep" not in skip:
        creep_table()
    if "success" not in skip:
        limits_table(success_table(args.presets.split(","), args.episodes))


if __name__ == "__main__":
    main()

"""``-v2`` physics: the longer physics step in free flight, taken only where nothing can
touch, and its state at every control step's end that of ``-v1``."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import tolins  # noqa: F401  (registers the ids)
from tolins.geometry.specs import CircularSocket, PolygonSocket
from tolins.physics.compiled import compile_model
from tolins.physics.free_flight import CLEARANCE, MAX_FREE_STEP, free_steps, servo_limits
from tolins.physics.mujoco import MujocoBackend
from tolins.physics.randomization import PhysicsDraw
from tolins.physics.versions import physics_version
from tolins.policies import EXPERTS

SOCKET = CircularSocket(rows=2, cols=2)
DOWN = np.array([0.0, 0.0, 0.0, -2.5])  # full speed down
SOCKET_STEP = compile_model(SOCKET).opt.timestep


def _edge_z(backend: MujocoBackend) -> float:
    """The lowest tip height from which a full-speed descent from rest is still free flight:
    the commanded travel of one control step plus the clearance."""
    return 2.5 * backend.control_dt + CLEARANCE


@pytest.mark.parametrize("outside", [True, False])
def test_the_bound_decides_the_step_at_its_edge(outside) -> None:
    backend = MujocoBackend(SOCKET, 0.25, physics_version=2)
    # Pins 0.5 mm beside their holes: the descent ends on the board's top.
    z = _edge_z(backend) + (1e-3 if outside else -1e-3)  # one µm outside / inside
    backend.reset(np.array([0.5, 0.0, 0.0, z]))
    first = backend.step(DOWN)
    stepper = backend.stepper
    if outside:
        assert stepper.step_factor * SOCKET_STEP == pytest.approx(MAX_FREE_STEP)
        assert first.peak_force == 0.0 and backend.data.ncon == 0
        assert first.pose[3] > 0.0  # ended above the board
        second = backend.step(DOWN)
        assert stepper.step_factor == 1  # the contact is reached on the contact step only
        assert second.peak_force > 0.0
    else:  # the bound is conservative: the servo's lag keeps it 12 µm off the board here
        assert stepper.step_factor == 1


def test_a_pin_centred_in_its_hole_descends_in_free_flight() -> None:
    backend = MujocoBackend(SOCKET, 0.25, physics_version=2)
    backend.reset(np.array([0.0, 0.0, 0.0, -0.5]))  # tips 0.5 mm deep, centred
    backend.step(np.array([0.0, 0.0, 0.0, -2.5]))
    assert backend.stepper.step_factor > 1
    # 0.1 mm sideways stays inside the 0.2 mm clearance; 0.25 mm could touch a wall.
    for speed, free in ((0.4, True), (1.0, False)):
        backend.reset(np.array([0.0, 0.0, 0.0, -0.5]))
        backend.step(np.array([speed, 0.0, 0.0, -2.5]))
        assert (backend.stepper.step_factor > 1) == free


def test_limits_of_a_model() -> None:
    limits = servo_limits(compile_model(SOCKET, physics_version=2))
    assert limits.lowest == pytest.approx(0.0, abs=1e-12)  # the tips are the pose's z
    assert limits.board_top == pytest.approx(0.0, abs=1e-12)
    assert np.allclose(1 / limits.omega[:3], 2.35e-3, rtol=0.01)  # the servos' 2.35 ms
    assert np.allclose(limits.hole_radius, SOCKET.hole_radius, atol=1e-6)
    assert np.allclose(limits.hole_xy, SOCKET.hole_centers) and np.all(limits.pin_radius == 0.3)
    plugged = servo_limits(compile_model(CircularSocket(rows=2, cols=2, blocked_holes=(1,))))
    assert plugged.hole_radius[1] == -np.inf  # a pin over a plug is never free
    short = compile_model(CircularSocket(rows=2, cols=2, pin_shortenings=(0.1,) * 4))
    assert servo_limits(short).lowest == pytest.approx(-0.1, abs=1e-9)


def test_the_ways_to_step_end_every_chunk_on_a_whole_step() -> None:
    for timestep, chunks in ((1e-3, [50] * 5), (1e-3, [100] * 2), (1e-3, [3, 2, 2, 2, 2])):
        for option in free_steps(timestep, chunks):
            assert option.factor * timestep <= MAX_FREE_STEP + 1e-12
            rest = [chunks[0] - option.window, *chunks[1:]]
            assert all(n % option.factor == 0 for n in rest)
    assert free_steps(1e-3, [3, 2, 2, 2, 2]) == []  # no longer step divides the chunks
    assert free_steps(5e-4, [100] * 5) == []  # the fine grades stay on their contact step


def test_stiffer_servos_take_a_shorter_free_step() -> None:
    factors = []
    for draw in (None, PhysicsDraw(servo_gain=4.0)):
        backend = MujocoBackend(SOCKET, 0.25, physics_version=2)
        backend.set_physics(draw)
        backend.reset(np.array([0.0, 0.0, 0.0, 10.0]))
        backend.step(np.array([0.0, 0.0, 0.0, -0.5]))
        factors.append(backend.stepper.step_factor)
    assert factors[0] * SOCKET_STEP == pytest.approx(MAX_FREE_STEP)
    assert factors[1] < factors[0]  # omega twice as high: the longest stable step is shorter


def test_v1_never_takes_a_longer_step() -> None:
    backend = MujocoBackend(SOCKET, 0.25)
    assert not physics_version(1).free_flight
    backend.reset(np.array([0.0, 0.0, 0.0, 10.0]))
    backend.step(np.array([0.0, 0.0, 0.0, -0.5]))
    assert backend.stepper.step_factor == 1


@pytest.mark.parametrize(
    "socket", [SOCKET, CircularSocket(rows=2, cols=8), PolygonSocket(4, 1.5, 1.65)]
)
def test_v2_follows_v1_through_expert_and_random_episodes(socket) -> None:
    # Free flight on the longer step, then contact on the board in the world body: the
    # pose at every control step's end within 0.1 µm of -v1, the outcomes the same.
    rng = np.random.default_rng(1)
    largest, factors = 0.0, set()
    for policy in (EXPERTS["safe"](), EXPERTS["efficient"](), None):
        envs = [gym.make("tolins/Insert-v1", socket=socket)]
        envs.append(gym.make("tolins/Insert-v2", socket=socket))
        for seed in range(2):
            results = []
            actions = rng.uniform(-2.5, 2.5, (40, 4)) * [1, 1, 0.04, 1]
            for env in envs:
                obs, _ = env.reset(seed=seed)
                trace = []
                for k in range(40):
                    action = actions[k] if policy is None else policy(obs)
                    obs, reward, terminated, truncated, info = env.step(action)
                    backend = env.unwrapped.backend
                    pose = backend.stepper.state(0.0).pose
                    trace.append((pose, reward, terminated, info["collision"]))
                    factors.add(getattr(backend.stepper, "step_factor", 1))
                    if terminated or truncated:
                        break
                results.append(trace)
            v1, v2 = results
            assert [t[1:] for t in v1] == [t[1:] for t in v2]
            largest = max(
                largest, max(np.abs(a[0] - b[0]).max() for a, b in zip(v1, v2, strict=True))
            )
    assert largest <= 1e-4, largest  # 0.1 µm
    assert max(factors) > 1  # the longer step was taken


def test_dm_control_runs_the_version_it_is_given() -> None:
    from tolins.dmc import suite

    env = suite.load("circle2x2", "insert", task_kwargs={"random": 0, "physics_version": 2})
    env.reset()
    assert env.physics.version.number == 2 and env.physics.stepper.free_flight
    env.step(np.array([0.0, 0.0, 0.0, -0.5]))
    v1 = suite.load("circle2x2", "insert", task_kwargs={"random": 0})
    assert v1.physics.version.number == 1 and not v1.physics.stepper.free_flight


def test_unknown_physics_version_is_refused() -> None:
    with pytest.raises(ValueError, match="physics_version=4; allowed: 1, 2, 3"):
        gym.make("tolins/Insert-v1", socket=SOCKET, physics_version=4)
    # The Panda's version is refused to the free body, naming the free body's.
    with pytest.raises(ValueError, match="allowed with robot='free': physics_version 1, 2"):
        gym.make("tolins/Insert-v1", socket=SOCKET, physics_version=3)

"""π_φ*: a policy with probabilistic inference in the loop, real MuJoCo."""

from __future__ import annotations

import dataclasses

import gymnasium as gym
import numpy as np
import pytest

import tolins  # noqa: F401  (registers the envs)
from tolins.envs.insertion_env import InsertionEnv
from tolins.geometry.specs import CircularSocket
from tolins.geometry.tolerance import pins_inside
from tolins.inference.adaptive import InferenceGuidedPolicy
from tolins.inference.posterior import DefectModel
from tolins.policies import SafeExpert
from tolins.rollouts.episodes import run_episode

NOMINAL = CircularSocket(rows=2, cols=1)
#: Pin 0 bent 0.3 mm in x: the nominal goal is blocked (clearance 0.2 mm), a shift is not.
BENT = dataclasses.replace(NOMINAL, pin_offsets=np.array([[0.3, 0.0], [0.0, 0.0]]))


def test_bent_workpiece_shifts_goal_after_first_blocked_attempt_then_inserts() -> None:
    assert not pins_inside(NOMINAL, BENT.pin_offsets, np.zeros(3)).all()
    env = InsertionEnv(BENT, measurement_noise=0.0)
    assert not run_episode(env, SafeExpert(), seed=0).success  # blocked at the nominal goal
    wrapper = InferenceGuidedPolicy(SafeExpert(), env, spec=NOMINAL, sigma=0.12)
    wrapper.reset(0)
    episode = run_episode(env, wrapper, seed=0)
    assert episode.success
    assert wrapper.replans == 1
    assert wrapper.history.inserted.tolist() == [False]
    assert wrapper.history.blocked.tolist() == [[True, False]]  # pin 0 on the board top
    # Pin 0 rests on the rim beyond its hole in +x (bearing 0), pin 1 gives no bearing.
    bearing, none = wrapper.history.bearings[0]
    assert abs(bearing) < 0.2 and np.isnan(none)
    assert np.linalg.norm(wrapper.goals[0][:2]) > 0.05
    np.testing.assert_array_equal(env.goal, wrapper.goals[0])
    wrapper.reset(0)
    np.testing.assert_array_equal(env.goal, np.zeros(3))  # reset restores the base goal


def test_nominal_workpiece_never_changes_goal() -> None:
    env = InsertionEnv(NOMINAL, measurement_noise=0.0)
    wrapper = InferenceGuidedPolicy(SafeExpert(), env, sigma=0.12)
    for seed in range(5):
        wrapper.reset(seed)
        bare_env = InsertionEnv(NOMINAL, measurement_noise=0.0)
        assert run_episode(env, wrapper, seed=seed) == run_episode(bare_env, SafeExpert(), seed)
        assert wrapper.replans == 0
        np.testing.assert_array_equal(env.goal, np.zeros(3))


def test_deterministic_for_a_seed() -> None:
    def run(seed: int) -> tuple:
        env = gym.make("tolins/Circle2x1Defective-v1").unwrapped
        wrapper = InferenceGuidedPolicy(SafeExpert(), env, contact=False)
        episodes = []
        for s in (seed, seed + 1, seed + 2):
            wrapper.reset(s)
            episodes.append((run_episode(env, wrapper, seed=s), np.array(wrapper.goals)))
        return episodes

    first, second = run(10004), run(10004)
    assert any(len(goals) for _, goals in first)  # some re-planning happened
    for (a, goals_a), (b, goals_b) in zip(first, second, strict=True):
        assert a == b
        np.testing.assert_array_equal(goals_a, goals_b)


def test_defect_model_reports_a_blocked_hole_not_insertable_and_inserts_the_others() -> None:
    """With the defect model the wrapper stops re-planning on a plugged hole."""
    from tolins.inference.posterior import DefectModel

    model = DefectModel(0.12, pitch_sigma=0.02, burr_sigma=0.08, blocked_prior=0.1)
    plugged = dataclasses.replace(NOMINAL, blocked_holes=(1,))
    for spec, inserts in ((plugged, False), (NOMINAL, True), (BENT, True)):
        env = InsertionEnv(spec, measurement_noise=0.0)
        wrapper = InferenceGuidedPolicy(
            SafeExpert(), env, spec=NOMINAL, sigma=0.12, model=model, n_samples=400
        )
        wrapper.reset(0)
        assert run_episode(env, wrapper, seed=0).success == inserts
        assert wrapper.not_insertable == (not inserts)
        assert wrapper.replans < wrapper.max_replans


def test_a_grasp_error_prior_needs_no_pin_sigma_and_finds_a_part_held_off() -> None:
    """Both pins 0.3 mm off in x, as a part held off in a robot's hand: the grasp-error
    prior (a common offset of every pin, no bends) moves the goal with it and inserts."""
    held_off = dataclasses.replace(NOMINAL, pin_offsets=np.array([[0.3, 0.0], [0.3, 0.0]]))
    env = InsertionEnv(held_off, measurement_noise=0.0)
    assert env.defect_sigma is None
    with pytest.raises(ValueError, match="or a model"):
        InferenceGuidedPolicy(SafeExpert(), env, spec=NOMINAL)
    model = DefectModel(0.0, grasp_sigma=(0.3, 0.3, 0.01))
    wrapper = InferenceGuidedPolicy(SafeExpert(), env, spec=NOMINAL, model=model)
    wrapper.reset(0)
    episode = run_episode(env, wrapper, seed=0)
    assert episode.success and wrapper.replans >= 1
    assert abs(wrapper.goals[-1][0] + 0.3) < NOMINAL.clearance  # the goal moved with the part

"""The scripted experts, the rollout summary and ``tolins demo``."""

from __future__ import annotations

import subprocess
import sys

import gymnasium as gym
import numpy as np
import pytest

import tolins  # noqa: F401  (registers the envs)
from tolins.cli import main
from tolins.demo import format_table, run_demo
from tolins.envs import TASKS
from tolins.paper import A_MAX
from tolins.policies import EfficientExpert, SafeExpert
from tolins.rollouts.episodes import Episode, run_episode
from tolins.rollouts.summary import summarise


def _summary(policy, gym_id: str = "tolins/Circle2x2-v1", episodes: int = 20):
    env = gym.make(gym_id).unwrapped
    return summarise([run_episode(env, policy, seed=s) for s in range(episodes)])


def test_safe_expert_aligns_before_it_descends() -> None:
    action = SafeExpert()(np.array([2.0, -0.1, 0.05, 10.0, 0, 0, 0, 0]))
    assert action[3] == 0.0
    assert action[0] == -A_MAX[0] and action[2] == -A_MAX[2]
    action = SafeExpert()(np.array([0.1, -0.1, 0.0, 10.0, 0, 0, 0, 0]))
    assert action[3] == -A_MAX[3]
    assert np.allclose(action[:2], [-0.4, 0.4])


def test_efficient_expert_heads_straight_for_the_hole_at_full_speed() -> None:
    observation = np.array([2.0, -1.0, 0.02, 10.0, 0, 0, 0, 0])
    action = EfficientExpert(depth=2.0)(observation)
    error = np.array([2.0, -1.0, 0.02, 12.0])
    assert np.all(np.abs(action) <= A_MAX + 1e-12)
    assert np.isclose(np.max(np.abs(action) / A_MAX), 1.0)
    assert np.allclose(np.cross(action[[0, 1, 3]], -error[[0, 1, 3]]), 0.0)


def test_experts_need_about_35_and_30_steps_as_in_the_paper() -> None:
    safe, efficient = _summary(SafeExpert()), _summary(EfficientExpert())
    assert 33.0 <= safe.steps_mean <= 37.0
    assert 28.0 <= efficient.steps_mean <= 32.0
    assert safe.success_mean >= 0.8 and efficient.success_mean >= 0.8
    assert safe.collisions_mean < efficient.collisions_mean
    assert efficient.reward_mean > safe.reward_mean


def test_summary_of_episodes() -> None:
    episodes = [Episode(10.0, True, 30, 1), Episode(-2.0, False, 40, 2)]
    summary = summarise(episodes)
    assert summary.episodes == 2 and summary.faults == 0
    assert summary.reward_mean == 4.0 and summary.reward_std == 6.0
    assert summary.success_mean == 0.5 and summary.steps_mean == 35.0
    with pytest.raises(ValueError, match="no episodes"):
        summarise([])


def test_demo_does_not_depend_on_the_number_of_workers() -> None:
    one = run_demo(episodes=1, seed=3, workers=1, progress=False)
    two = run_demo(episodes=1, seed=3, workers=2, progress=False)
    assert one == two
    # The newest version of every paper preset, as the README's pages use them.
    assert [row.env_id for row in one[::2]] == [f"tolins/{task.name}-v2" for task in TASKS]
    assert {row.expert for row in one} == {"safe", "efficient"}
    table = format_table(one)
    assert table.count("\n") == len(one) + 1


@pytest.mark.slow
def test_demo_command_prints_the_table_with_the_pandas_rows(capsys) -> None:
    assert main(["demo", "--episodes", "2", "--robot-episodes", "1"]) == 0
    printed = capsys.readouterr().out
    for task in TASKS:
        assert printed.count(f"| tolins/{task.name}-v2 |") == 2
        assert printed.count(f"| tolins/{task.name}Panda-v3 |") == 2
    assert "success rate" in printed and "1 per Panda row" in printed


@pytest.mark.slow
def test_demo_without_the_robot_extra_says_how_to_add_the_pandas_rows() -> None:
    hidden = "import sys; sys.modules['gymnasium_robotics'] = None; from tolins.cli import main"
    code = f"{hidden}; sys.exit(main(['demo', '--episodes', '1']))"
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert "Panda" not in result.stdout and "| tolins/Circle2x2-v2 |" in result.stdout
    lines = [line for line in result.stderr.splitlines() if "Panda" in line]
    assert len(lines) == 1 and "tolins[robot]" in lines[0], result.stderr


def test_demo_command_rejects_bad_arguments(capsys) -> None:
    assert main(["demo", "--episodes", "0"]) == 2
    assert "allowed" in capsys.readouterr().err

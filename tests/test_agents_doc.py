"""docs/agents.md: its PPO example is docs/examples/train_ppo.py and runs; its other Python
code runs as written."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "agents.md"
EXAMPLE = ROOT / "docs" / "examples" / "train_ppo.py"


def _python_blocks() -> list[str]:
    return re.findall(r"```python\n(.*?)```", DOC.read_text(), flags=re.DOTALL)


def test_the_doc_quotes_the_example_file_exactly() -> None:
    assert EXAMPLE.read_text() in _python_blocks()


@pytest.mark.slow
def test_the_ppo_example_trains_saves_and_scores_with_a_tiny_budget(tmp_path) -> None:
    out = tmp_path / "ppo.zip"
    command = [sys.executable, str(EXAMPLE), "--backend", "kinematic", "--steps", "256"]
    command += ["--n-steps", "128", "--episodes", "3", "--out", str(out)]
    result = subprocess.run(command, capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert result.returncode == 0, result.stderr[-2000:]
    assert out.is_file()
    assert re.search(r"ppo\.zip: reward -?\d+\.\d\d ± \d+\.\d\d, .* over 3 episodes", result.stdout)


def test_the_other_python_code_of_the_doc_runs() -> None:
    others = [block for block in _python_blocks() if block != EXAMPLE.read_text()]
    assert others
    for block in others:
        exec(compile(block, str(DOC), "exec"), {"__name__": "agents_doc"})


def test_the_reward_modes_and_terms_the_doc_names_are_the_envs() -> None:
    import gymnasium as gym

    import tolins  # noqa: F401
    from tolins.envs.reward import REWARD_MODES

    section = DOC.read_text().split("## Reward modes", 1)[1].split("\n## ", 1)[0]
    modes = re.findall(r'^- `"([a-z_]+)"`', section, flags=re.MULTILINE)
    assert tuple(modes) == REWARD_MODES
    env = gym.make("tolins/Square-v1", backend="kinematic", reward_mode="dense")
    env.reset(seed=0)
    _, reward, *_, info = env.step(env.action_space.sample())
    terms = {key for key in info if key.startswith("reward_")}
    assert terms == set(re.findall(r"`(reward_[a-z]+)`", section))
    assert abs(sum(info[key] for key in terms) - reward) < 1e-9

"""`tolins record --policy/--backend` records any saved policy; `tolins replay --step`."""

from __future__ import annotations

import json
from pathlib import Path

import gymnasium as gym
import numpy as np
from rerun.chunk import RrdReader

import tolins  # noqa: F401  (registers the env ids)
from tolins.cli import main
from tolins.learning.imitation.policy import Policy, PolicyArchitecture, save_policy
from tolins.rollouts.episodes import episode_poses


def _poses_and_metadata(path: Path) -> tuple[np.ndarray, dict]:
    poses, metadata = {}, {}
    for chunk in RrdReader(path).stream():
        table = chunk.to_record_batch().to_pydict()
        if chunk.entity_path == "/pose/episode_000":
            poses.update(zip(table["step"], table["Scalars:scalars"], strict=True))
        if chunk.entity_path == "/metadata/episode_000":
            metadata = {k: v[0][0] for k, v in table.items() if k != "rerun.controls.RowId"}
    return np.array([poses[k] for k in sorted(poses)]), metadata


def test_record_takes_a_policy_file_and_the_kinematic_backend(tmp_path, capsys) -> None:
    policy = Policy(PolicyArchitecture(), seed=1)
    path = save_policy(tmp_path / "policy.pt", policy, {"seed": 1})
    out = tmp_path / "pi.rrd"
    argv = ["record", "--env", "tolins/Square-v1", "--policy", str(path), "--backend"]
    assert main([*argv, "kinematic", "--episodes", "1", "--out", str(out), "--seed", "4"]) == 0
    assert "1 episodes" in capsys.readouterr().out
    poses, metadata = _poses_and_metadata(out)
    env = gym.make("tolins/Square-v1", backend="kinematic")
    assert np.array_equal(poses, episode_poses(env, policy.bind(), seed=4))
    assert metadata["backend"] == "kinematic" and metadata["policy"] == str(path)


def test_record_takes_module_name_and_refuses_bad_policies(tmp_path, capsys) -> None:
    out = tmp_path / "x.rrd"
    argv = ["record", "--env", "tolins/Circle2x2-v1", "--episodes", "1", "--out", str(out)]
    assert main([*argv, "--policy", "tolins.policies.experts:SafeExpert"]) == 0
    assert json.loads(json.dumps(_poses_and_metadata(out)[1]))["policy"].endswith("SafeExpert")
    capsys.readouterr()
    for bad, message in (("nope_module_x:f", "cannot import"), ("gone.zip", "no such file")):
        assert main([*argv, "--policy", bad]) == 2
        error = capsys.readouterr().err
        assert message in error and error.count("\n") == 1


def test_replay_step_needs_a_screenshot_and_a_step_inside_the_recording(tmp_path, capsys):
    out = tmp_path / "c.rrd"
    argv = ["record", "--env", "tolins/Circle2x2-v1", "--backend", "kinematic"]
    assert main([*argv, "--episodes", "1", "--out", str(out)]) == 0
    capsys.readouterr()
    assert main(["replay", str(out), "--step", "3"]) == 2
    assert "allowed: with --screenshot" in capsys.readouterr().err
    shot = str(tmp_path / "s.png")
    assert main(["replay", str(out), "--screenshot", shot, "--step", "-1"]) == 2
    assert main(["replay", str(out), "--screenshot", shot, "--step", "400"]) == 2
    assert "past its last step" in capsys.readouterr().err
    assert not (tmp_path / "s.png").exists() and not list(tmp_path.glob(".*"))

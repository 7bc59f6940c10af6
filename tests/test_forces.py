"""Force-aware scores (tolins.rollouts.forces): what they measure on real episodes, the same
from the single-env loop and the vector-env runner, and in results.json (schema /2)."""

from __future__ import annotations

import dataclasses
import json
import re

import gymnasium as gym
import numpy as np
import pytest

from tolins.bench.table.results import SCHEMA, force_figures, read_results, row_entry
from tolins.bench.table.rows import ROWS
from tolins.policies import EXPERTS
from tolins.rollouts.episodes import Episode, episode_from_dict, episode_to_dict, run_episode
from tolins.rollouts.forces import FORCE_FIGURES, JAM_STEPS, ForceScores, ForceTracker
from tolins.rollouts.runner import Job, VectorEnvCache, run_jobs

ENV = "tolins/Circle2x2-v1"


def _straight_down(observation: np.ndarray) -> np.ndarray:
    """Descend at full speed without aligning: the pins land on the board and stay there."""
    return np.array([0.0, 0.0, 0.0, -2.5])


@pytest.mark.parametrize("backend", ["kinematic", "mujoco"])
def test_pushing_on_the_board_is_one_jam_and_the_safe_expert_barely_touches(backend):
    env = gym.make(ENV, backend=backend)
    pushed = run_episode(env, _straight_down, seed=3)
    assert not pushed.success and pushed.steps == 40
    forces = pushed.forces
    assert forces.jams == 1  # one long jam, counted once
    assert forces.peak_force > env.unwrapped.collision_force
    assert forces.cycle_time == pytest.approx(40 * 0.25)
    assert 0 < forces.impulse <= forces.peak_force * forces.cycle_time
    assert forces.contact_force <= forces.peak_force
    safe = [run_episode(env, EXPERTS["safe"](), seed=s).forces for s in range(3, 8)]
    assert all(f.jams == 0 and f.impulse < forces.impulse for f in safe)
    env.close()


def test_the_contact_figures_follow_the_steps_they_are_made_of():
    env = gym.make(ENV, backend="mujoco")
    _, info = env.reset(seed=1)
    tracker = ForceTracker.of(env.unwrapped.settings, info)
    peaks, done, observation = [], False, None
    policy = EXPERTS["efficient"]()
    observation = env.unwrapped._episode.observation
    while not done:
        observation, _, terminated, truncated, info = env.step(policy(observation))
        tracker.step(info["peak_force"], info["pose"][3])
        peaks.append(info["peak_force"])
        done = terminated or truncated
    scores, touching = tracker.scores(), [p for p in peaks if p > 0.01]
    assert touching, "the efficient expert meets the board on its straight path"
    assert scores.peak_force == max(peaks)
    assert scores.contact_force == pytest.approx(np.mean(touching))
    assert scores.impulse == pytest.approx(sum(touching) * 0.25)
    assert scores.jams == 0 and scores.cycle_time == len(peaks) * 0.25
    env.close()


def test_a_jam_needs_k_blocked_steps_without_progress():
    tracker = ForceTracker(10.0, control_dt=0.25, collision_force=0.5)
    for _ in range(JAM_STEPS - 1):
        tracker.step(2.0, 10.0)
    assert tracker.scores().jams == 0
    tracker.step(2.0, 9.995)  # the k-th blocked step, 5 µm deeper: no progress
    assert tracker.scores().jams == 1
    tracker.step(2.0, 9.99)
    assert tracker.scores().jams == 1  # still the same jam
    tracker.step(0.0, 9.0)  # free again
    for z in (8.0, 7.0, 6.0, 5.0):
        tracker.step(2.0, z)  # blocked but going in: not a jam
    assert tracker.scores().jams == 1
    for _ in range(JAM_STEPS):
        tracker.step(2.0, 5.0)
    assert tracker.scores().jams == 2


@pytest.mark.parametrize("backend", ["kinematic", "mujoco"])
def test_the_vector_runner_gives_the_single_loops_force_scores(backend):
    seeds = [10, 11, 12]
    env = gym.make(ENV, backend=backend)
    for policy in (EXPERTS["efficient"](), _straight_down):
        single = [run_episode(env, policy, seed=s) for s in seeds]
        envs = VectorEnvCache(backend, num_envs=2)
        batched = run_jobs(envs, [Job(ENV, policy, s) for s in seeds])
        envs.close()
        assert batched == single
        assert all(e.forces is not None for e in batched)
    env.close()


def _episodes(peaks):
    return [
        Episode(1.0, True, 30, 0, None, ForceScores(p, p / 2, p / 4, i % 2, 7.5))
        for i, p in enumerate(peaks)
    ]


def test_the_force_table_adds_the_damage_where_pins_could_bend():
    from tolins.bench.table.force_table import format_force_table

    rigid = row_entry(ROWS[0], [_episodes([1.0, 3.0])])
    seeds = [
        [
            dataclasses.replace(e, damaged=d)
            for e, d in zip(_episodes([1.0, 3.0]), bends, strict=True)
        ]
        for bends in ((True, False), (True, True))
    ]
    delicate = row_entry(ROWS[1], seeds)
    header, _, *lines = format_force_table({"C1.1": rigid, "C1.2": delicate}).splitlines()
    assert header.endswith("| cycle time (s) | damaged | success, undamaged |")
    assert lines[0].startswith("| C1.1 |") and lines[0].endswith("| – | – |")
    # per seed: damaged 0.5 and 1.0, undamaged successes 0.5 and 0.0 (std over seed means)
    assert lines[1].endswith("| 0.75 ± 0.25 | 0.25 ± 0.25 |")
    assert "damaged" not in format_force_table({"C1.1": rigid})


def test_rows_carry_the_force_figures_per_seed_and_per_episode(tmp_path):
    entry = row_entry(ROWS[0], [_episodes([1.0, 3.0]), _episodes([5.0, 7.0])])
    assert entry["peak_force_mean"] == 4.0
    assert entry["peak_force_std"] == pytest.approx(np.std([2.0, 6.0]))  # over seed means
    assert entry["peak_force_per_seed"] == [2.0, 6.0]
    assert entry["jams_per_episode"] == [[0.0, 1.0], [0.0, 1.0]]
    assert entry["cycle_time_mean"] == 7.5
    assert {f"{name}_mean" for name in FORCE_FIGURES} <= set(entry)
    old = [Episode(1.0, True, 30, 0)]
    assert force_figures([old]) == {}
    assert "peak_force_mean" not in row_entry(ROWS[0], [old])


def test_results_of_schemas_1_and_2_are_still_read(tmp_path):
    assert SCHEMA == "tolins.results/3"
    entry = row_entry(ROWS[0], [[Episode(1.0, True, 30, 0)]])
    for schema in ("tolins.results/1", "tolins.results/2"):
        (tmp_path / "results.json").write_text(
            json.dumps({"schema": schema, "rows": {"C1.1": entry}})
        )
        assert read_results(tmp_path)["rows"]["C1.1"]["reward_mean"] == 1.0
    (tmp_path / "results.json").write_text(json.dumps({"schema": "tolins.results/4", "rows": {}}))
    allowed = r"allowed: 'tolins\.results/1' or 'tolins\.results/2' or 'tolins\.results/3'"
    with pytest.raises(ValueError, match=allowed):
        read_results(tmp_path)


def test_an_episode_round_trips_through_json():
    from dataclasses import asdict

    episode = _episodes([2.5])[0]
    assert episode_from_dict(json.loads(json.dumps(asdict(episode)))) == episode
    assert episode_from_dict(asdict(Episode(1.0, False, 40, 3))) == Episode(1.0, False, 40, 3)


def test_evaluate_prints_and_writes_the_force_figures(tmp_path, capsys):
    from tolins.cli import main

    argv = ["evaluate", "--policy", "efficient", "--env", ENV, "--episodes", "3"]
    assert main([*argv, "--backend", "kinematic", "--out", str(tmp_path)]) == 0
    printed = capsys.readouterr().out
    assert "| ID | policy | eval env | peak force (N) | force in contact (N) |" in printed
    assert re.search(r"\| efficient \| efficient \| Circle2x2 \| 1\.00 ± 0\.00 \|", printed)
    assert (tmp_path / "force_profile.png").stat().st_size > 1000
    document = read_results(tmp_path)
    assert document["schema"] == SCHEMA
    entry = document["rows"]["efficient"]
    assert len(entry["impulse_per_episode"][0]) == 3 and entry["jams_mean"] == 0.0


def test_the_force_table_and_panel_show_rows_that_have_the_figures(tmp_path):
    from tolins.bench.reports.plots import plot_table
    from tolins.bench.table.force_table import format_force_table
    from tolins.bench.table.rows import PAPER

    with_forces = row_entry(ROWS[0], [_episodes([1.0, 3.0])])
    without = row_entry(ROWS[1], [[Episode(1.0, True, 30, 0)]])
    table = format_force_table({"C1.1": with_forces, "C1.2": without})
    assert table.count("\n") == 2 and "| C1.1 |" in table and "C1.2" not in table
    assert "| 2.00 ± 1.00 | 1.00 ± 0.50 | 0.50 ± 0.25 | 0.50 ± 0.50 | 7.50 ± 0.00 |" in table
    assert format_force_table({"C1.2": without}) == ""
    three = plot_table(tmp_path / "forces.png", {"C1.1": with_forces}, PAPER)
    two = plot_table(tmp_path / "plain.png", {"C1.2": without}, PAPER)
    from PIL import Image

    assert Image.open(three).size[1] > Image.open(two).size[1]  # the third panel


def test_the_profile_is_each_steps_depth_and_peak_force():
    env = gym.make(ENV, backend="mujoco")
    episode = run_episode(env, EXPERTS["efficient"](), seed=4)
    assert len(episode.profile) == episode.steps
    assert max(force for _, force in episode.profile) == episode.forces.peak_force
    assert episode.profile[-1][0] >= env.unwrapped.success_depth  # inserted: ≥ 1 mm deep
    env.close()


def test_stage_episodes_with_forces_are_checked_on_reading(tmp_path):
    from tolins.bench.store.integrity import StageFileError, checked_episodes

    episode = Episode(1.0, True, 2, 0, None, ForceScores(2.0, 1.5, 0.75, 0, 0.5), ((0.1, 1.0),) * 2)
    rows = [episode_to_dict(e) for e in (episode, Episode(1.0, True, 30, 0))]
    rows = json.loads(json.dumps(rows))
    assert checked_episodes(tmp_path, rows, 2)[0] == episode
    rows[0]["forces"]["impulse"] = -1.0
    with pytest.raises(StageFileError, match=r"forces\.impulse -1\.0; allowed: finite, ≥ 0"):
        checked_episodes(tmp_path, rows, 2)
    rows[0]["forces"]["impulse"], rows[0]["profile"] = 0.75, [[0.1, "x"]]
    with pytest.raises(StageFileError, match="profile is not"):
        checked_episodes(tmp_path, rows, 2)


def test_a_row_force_profile_is_drawn_from_its_episodes(tmp_path):
    from tolins.bench.reports.force_plot import plot_force_profile

    env = gym.make(ENV, backend="kinematic")
    episodes = [run_episode(env, p, seed=5) for p in (EXPERTS["efficient"](), _straight_down)]
    assert [e.success for e in episodes] == [True, False]
    path = plot_force_profile(tmp_path / "profile.png", episodes, "C2.1")
    assert path.stat().st_size > 1000
    with pytest.raises(ValueError, match="without force profiles"):
        plot_force_profile(tmp_path / "none.png", [Episode(1.0, True, 30, 0)], "old")
    assert not (tmp_path / "none.png").exists()
    env.close()

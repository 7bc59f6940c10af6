"""Minari datasets: ``tolins dataset`` writes them, ``recover_environment()`` replays them bit
for bit, and the learners read them (tolins.datasets)."""

from __future__ import annotations

import functools
import json
import sys

import gymnasium as gym
import numpy as np
import pytest

minari = pytest.importorskip("minari")

from tolins.cli import main  # noqa: E402
from tolins.datasets import (  # noqa: E402
    STEP_INFO,
    episode_seeds,
    load_demonstrations,
    make_source,
    open_dataset,
    write_dataset,
)
from tolins.geometry.specs import CircularSocket  # noqa: E402
from tolins.learning.agents.actors import make_actor  # noqa: E402
from tolins.learning.imitation.demonstrations import collect  # noqa: E402
from tolins.learning.imitation.runs import trained_bc  # noqa: E402

NAME = "tolins/test/mixed-v0"


def _write(root, env_id, entries, episodes, backend, **kwargs):
    socket = kwargs.get("env_kwargs", {}).get("socket") or gym.spec(env_id).kwargs["socket"]
    train_bc = functools.partial(trained_bc, env_id, backend, 0)
    sources = [make_source(e, socket, make_actor=make_actor, train_bc=train_bc) for e in entries]
    return write_dataset(env_id, sources, episodes, root, NAME, backend=backend, **kwargs)


def _replays_bit_for_bit(dataset) -> None:
    """Every episode, replayed in recover_environment() from its seed with its actions,
    gives the stored observations exactly (and the stored true poses)."""
    env = dataset.recover_environment()
    metadata = list(dataset.storage.get_episode_metadata(range(dataset.total_episodes)))
    for episode, meta in zip(dataset.iterate_episodes(), metadata, strict=True):
        observation, info = env.reset(seed=meta["seed"])
        observations, poses = [observation], [info["pose"]]
        np.testing.assert_array_equal(env.unwrapped.socket.offsets, meta["pin_offsets"])
        for action in episode.actions:
            observation, *_, info = env.step(action)
            observations.append(observation)
            poses.append(info["pose"])
        assert np.array_equal(np.array(observations), episode.observations)
        assert np.array_equal(np.array(poses), episode.infos["pose"])
    env.close()


@pytest.mark.parametrize(
    ("backend", "env_id", "episodes"),
    [("kinematic", "tolins/Circle2x1Defective-v1", 6), ("mujoco", "tolins/Circle2x2-v1", 2)],
)
def test_a_dataset_replays_bit_for_bit_in_its_recovered_env(tmp_path, backend, env_id, episodes):
    path = _write(tmp_path, env_id, ["safe", "random"], episodes, backend, seed=3)
    assert path == tmp_path / NAME and (path / "data" / "main_data.hdf5").is_file()
    dataset = minari.MinariDataset(path / "data")
    assert dataset.total_episodes == episodes
    assert dataset.env_spec.id == env_id
    assert dataset.env_spec.kwargs["backend"] == backend
    _replays_bit_for_bit(dataset)
    episode = dataset[0]
    steps = len(episode)
    assert set(episode.infos) == set(STEP_INFO)
    assert episode.infos["wrench"].shape == (steps + 1, 4)
    assert episode.infos["peak_force"].shape == (steps + 1,)
    metadata = list(dataset.storage.get_episode_metadata(range(episodes)))
    assert [m["policy"] for m in metadata] == ["safe", "random"] * (episodes // 2)
    assert [m["seed"] for m in metadata] == episode_seeds(3, episodes)
    socket = json.loads(metadata[0]["socket"])
    assert socket["type"] == "CircularSocket"
    if backend == "kinematic":  # the defective preset: each episode its own bent pins
        assert socket["pin_offsets"] is not None
        assert not np.array_equal(metadata[0]["pin_offsets"], metadata[1]["pin_offsets"])


def test_the_generic_env_with_a_custom_socket_is_recovered(tmp_path):
    socket = CircularSocket(rows=1, cols=3, hole_radius=0.45)
    path = _write(
        tmp_path,
        "tolins/Insert-v1",
        ["efficient"],
        2,
        "kinematic",
        env_kwargs={"socket": socket, "horizon": 30},
    )
    dataset = minari.MinariDataset(path / "data")
    env = dataset.recover_environment()
    assert env.unwrapped.nominal_socket == socket and env.unwrapped.horizon == 30
    _replays_bit_for_bit(dataset)


def test_minari_load_dataset_finds_it_by_id(tmp_path, monkeypatch):
    _write(tmp_path, "tolins/Circle2x2-v1", ["safe"], 2, "kinematic")
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path))
    dataset = minari.load_dataset(NAME)
    assert dataset.total_episodes == 2 and dataset.spec.dataset_id == NAME
    assert len(load_demonstrations(NAME, "tolins/Circle2x2-v1")) == 2


def test_an_error_mid_way_leaves_no_dataset(tmp_path):
    calls = []

    def failing(observation):
        calls.append(1)
        if len(calls) > 50:
            raise RuntimeError("policy broke")
        return np.zeros(4)

    from tolins.datasets import Source

    with pytest.raises(RuntimeError, match="policy broke"):
        write_dataset(
            "tolins/Circle2x2-v1",
            [Source("failing", lambda _: failing)],
            3,
            tmp_path,
            NAME,
            backend="kinematic",
        )
    assert list(tmp_path.rglob("*")) == [tmp_path / "tolins", tmp_path / "tolins" / "test"]


def test_safe_expert_dataset_holds_the_demonstrations_train_collects(tmp_path):
    _write(tmp_path, "tolins/Circle2x2-v1", ["safe"], 4, "kinematic", seed=2)
    rollouts = load_demonstrations(tmp_path / NAME, "tolins/Circle2x2-v1")
    expected = collect("tolins/Circle2x2-v1", "safe", 4, 2 * 1000, "kinematic")
    for got, want in zip(rollouts, expected, strict=True):
        assert np.array_equal(got.observations, want.observations)
        assert np.array_equal(got.actions, want.actions)
        assert (got.success, got.collisions) == (want.success, want.collisions)
        assert got.reward == pytest.approx(want.reward)


def test_reading_checks_env_and_spaces(tmp_path):
    path = _write(tmp_path, "tolins/Circle2x2-v1", ["safe"], 2, "kinematic")
    with pytest.raises(ValueError, match="allowed: episodes of tolins/Square-v1"):
        open_dataset(path, "tolins/Square-v1")
    from minari.dataset.minari_storage import MinariStorage

    from tolins.datasets import dataset_env_spec

    for folder, spec in (("cartpole", gym.spec("CartPole-v1")), ("box", None)):
        (tmp_path / folder).mkdir()
        storage = MinariStorage.new(
            tmp_path / folder / "data",
            observation_space=gym.spaces.Box(-1, 1, (3,)),
            action_space=gym.spaces.Box(-1, 1, (4,)),
            env_spec=spec or dataset_env_spec("tolins/Circle2x2-v1"),
        )
        storage.update_metadata(
            {"dataset_id": f"{folder}-v0", "minari_version": minari.__version__}
        )
    with pytest.raises(ValueError, match="'CartPole-v1' is not a tolins env"):
        open_dataset(tmp_path / "cartpole")
    with pytest.raises(ValueError, match=r"observation_space Box\(-1.0, 1.0, \(3,\)"):
        open_dataset(tmp_path / "box", "tolins/Circle2x2-v1")
    with pytest.raises(ValueError, match="not a Minari dataset"):
        open_dataset(tmp_path / "missing")


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--recipe", "best"], "recipe 'best' is unknown; allowed: expert-safe"),
        (["--policy", "nope"], "policy 'nope': unknown"),
        (["--policy", "nope"], "; --policy takes a .zip/.pt file path"),
        (["--policy", "safe", "--name", "no spaces"], "is not a Minari dataset id"),
        (["--policy", "safe", "--recipe", "mixed"], "not allowed with argument"),
        (["--policy", "safe", "--episodes", "0"], "allowed: an integer ≥ 1"),
    ],
)
def test_bad_options_exit_2_before_any_episode(tmp_path, capsys, argv, message):
    out = tmp_path / "root"
    code = main(["dataset", "--env", "tolins/Circle2x2-v1", "--out", str(out), *argv])
    assert code == 2
    assert message in capsys.readouterr().err
    assert not out.exists()


def test_cli_writes_a_recipe_and_refuses_to_overwrite_it(tmp_path, capsys):
    argv = ["dataset", "--env", "tolins/Circle2x2-v1", "--recipe", "mixed", "--episodes", "4"]
    argv += ["--out", str(tmp_path), "--backend", "kinematic"]
    assert main(argv) == 0
    path = tmp_path / "tolins" / "circle2x2" / "mixed-v0"
    assert f"wrote {path}: 4 episodes" in capsys.readouterr().out
    dataset = minari.MinariDataset(path / "data")
    metadata = dataset.storage.get_episode_metadata(range(4))
    assert [m["policy"] for m in metadata] == ["safe", "efficient", "bc", "random"]
    assert dataset.storage.metadata["tolins_env"] == "tolins/Circle2x2-v1"
    assert main(argv) == 2
    assert "exists; allowed: a new --name" in capsys.readouterr().err
    argv[2] = "tolins/Circle2x2-v2"  # another physics version: its own default place
    assert main(argv) == 0
    assert (
        f"wrote {tmp_path / 'tolins' / 'circle2x2-v2' / 'mixed-v0'}: 4" in capsys.readouterr().out
    )


def _train(argv, out):
    return main(["train", *argv, "--out", str(out)])


def test_bc_from_a_safe_expert_dataset_equals_todays_pi_bc(tmp_path, capsys):
    """Same seed, same demonstrations: ``--demos`` gives π_bc bit for bit."""
    from tolins.learning.imitation.policy import load_policy

    env = "tolins/Circle2x2-v1"
    _write(tmp_path / "datasets", env, ["safe"], 6, "kinematic", seed=1)
    argv = ["bc", "--env", env, "--backend", "kinematic", "--seed", "1", "--epochs", "4"]
    assert _train([*argv, "--demonstrations", "6"], tmp_path / "expert") == 0
    dataset = str(tmp_path / "datasets" / NAME)
    assert _train([*argv, "--demos", dataset], tmp_path / "minari") == 0
    today, _ = load_policy(tmp_path / "expert" / "policy.pt")
    from_dataset, _ = load_policy(tmp_path / "minari" / "policy.pt")
    assert np.array_equal(today.get_flat(), from_dataset.get_flat())
    run = json.loads((tmp_path / "minari" / "run.json").read_text())
    assert run["configs"]["demos"] == {"dataset": dataset, "episodes": 6}


def test_train_refuses_a_dataset_of_another_env_before_any_work(tmp_path, capsys):
    _write(tmp_path / "datasets", "tolins/Circle2x2-v1", ["safe"], 2, "kinematic")
    dataset = str(tmp_path / "datasets" / NAME)
    for method in ("bc", "rs-gail"):
        code = _train([method, "--env", "tolins/Square-v1", "--demos", dataset], tmp_path / "out")
        assert code == 2
        assert "allowed: episodes of tolins/Square-v1" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


def test_rs_gail_from_a_safe_expert_dataset_equals_todays(tmp_path):
    """RS-GAIL (BC start and discriminator) from the dataset: the same π_n bit for bit."""
    from tolins.learning.imitation.policy import load_policy

    env = "tolins/Circle2x2-v1"
    _write(tmp_path / "datasets", env, ["safe"], 4, "kinematic", seed=2)
    argv = ["rs-gail", "--env", env, "--backend", "kinematic", "--seed", "2", "--epochs", "3"]
    argv += ["--iterations", "2", "--popsize", "4", "--episodes", "1", "--eval-episodes", "2"]
    assert _train([*argv, "--demonstrations", "4"], tmp_path / "expert") == 0
    assert _train([*argv, "--demos", str(tmp_path / "datasets" / NAME)], tmp_path / "minari") == 0
    today, _ = load_policy(tmp_path / "expert" / "policy.pt")
    from_dataset, _ = load_policy(tmp_path / "minari" / "policy.pt")
    assert np.array_equal(today.get_flat(), from_dataset.get_flat())
    assert np.array_equal(
        np.load(tmp_path / "expert" / "means.npy"), np.load(tmp_path / "minari" / "means.npy")
    )


def test_without_minari_each_user_says_what_to_install(tmp_path, capsys, monkeypatch):
    from tolins.datasets.reader import require_minari

    monkeypatch.setitem(sys.modules, "minari", None)  # import minari raises ImportError
    with pytest.raises(ImportError, match=r"tolins bench needs Minari .*tolins\[data\]"):
        require_minari("tolins bench")
    for argv in (
        ["dataset", "--env", "tolins/Circle2x2-v1", "--policy", "safe", "--out", str(tmp_path)],
        ["train", "bc", "--env", "tolins/Circle2x2-v1", "--demos", "d", "--out", str(tmp_path)],
    ):
        assert main(argv) == 2
        assert "needs Minari" in capsys.readouterr().err

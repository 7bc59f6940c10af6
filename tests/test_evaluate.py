"""Scoring any policy on the bench's protocol: callables, SB3 zips, tolins policy files,
the results.json schema and the errors of `tolins evaluate`."""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

import tolins
from tolins.bench import evaluate_policy
from tolins.bench.evaluate import write_evaluation
from tolins.bench.jobs.row_evaluation import evaluate_row
from tolins.bench.table.results import SCHEMA, read_results, row_entry
from tolins.bench.table.rows import ROWS
from tolins.bench.table.seeds import eval_seeds
from tolins.cli import main
from tolins.learning.agents.actors import make_actor
from tolins.learning.agents.external import as_actor, load_sb3, sb3_algorithm
from tolins.learning.imitation.policy import Policy, PolicyArchitecture, save_policy
from tolins.paper import A_MAX
from tolins.policies.experts import SafeExpert

CIRCLE = "tolins/Circle2x2-v2"
EPISODES = 4
#: Fields that name a row rather than measure it.
LABELS = ("policy", "train_env")


def _figures(entry: dict) -> dict:
    return {k: v for k, v in entry.items() if k not in LABELS}


def _bench_row(row_id: str, episodes: int = EPISODES) -> dict:
    row = next(r for r in ROWS if r.id == row_id)
    return row_entry(row, [evaluate_row(row, None, "kinematic", eval_seeds(0, episodes))])


class _Acts:
    def __init__(self) -> None:
        self.expert = SafeExpert()

    def act(self, observation):
        return list(self.expert(observation))


class _Predicts:
    def __init__(self) -> None:
        self.expert = SafeExpert()

    def predict(self, observation, deterministic=False):
        assert deterministic
        return self.expert(observation), None


def test_a_callable_scores_as_the_bench_scores_the_same_policy() -> None:
    bench = _bench_row("C2.1")
    expert = SafeExpert()
    for policy in (lambda observation: expert(observation), _Acts(), _Predicts()):
        entry = evaluate_policy(policy, CIRCLE, episodes=EPISODES, backend="kinematic")
        assert _figures(entry) == _figures(bench)
        assert entry["train_env"] == "-" and entry["episodes"] == EPISODES


def test_a_tolins_policy_file_scores_as_its_bound_policy(tmp_path) -> None:
    policy = Policy(PolicyArchitecture(), seed=3)
    path = save_policy(tmp_path / "policy.pt", policy, {"seed": 3})
    from_file = evaluate_policy(str(path), "tolins/Square-v1", episodes=3, backend="kinematic")
    bound = evaluate_policy(policy.bind(), "tolins/Square-v1", episodes=3, backend="kinematic")
    assert _figures(from_file) == _figures(bound)
    assert from_file["policy"] == str(path)


def test_malformed_actions_are_refused() -> None:
    with pytest.raises(ValueError, match="4 finite numbers"):
        as_actor(lambda observation: [0.0, 0.0])(np.zeros(8))
    with pytest.raises(ValueError, match="4 finite numbers"):
        as_actor(lambda observation: [0.0, np.nan, 0.0, 0.0])(np.zeros(8))
    with pytest.raises(ValueError, match="not a policy"):
        as_actor(42)


def _wrapped(env_id: str) -> gym.Env:
    from gymnasium.wrappers import DtypeObservation, RescaleAction

    env = gym.make(env_id, backend="kinematic")
    return DtypeObservation(RescaleAction(env, -1.0, 1.0), np.float32)


@pytest.mark.slow
def test_an_sb3_zip_of_a_real_ppo_and_sac_loads_and_evaluates(tmp_path) -> None:
    from stable_baselines3 import PPO, SAC

    ppo = PPO("MlpPolicy", _wrapped(CIRCLE), n_steps=128, batch_size=64, n_epochs=1, seed=0)
    ppo.learn(256)
    sac = SAC("MlpPolicy", _wrapped(CIRCLE), learning_starts=32, seed=0)
    sac.learn(64)
    observation = np.array([0.4, -0.3, 0.02, 16.0, 0.0, 0.0, 0.0, 0.0])
    for model, algorithm in ((ppo, "PPO"), (sac, "SAC")):
        path = tmp_path / f"{algorithm}.zip"
        model.save(path)
        assert sb3_algorithm(path) == algorithm
        squashed, _ = model.predict(observation.astype(np.float32), deterministic=True)
        assert np.allclose(load_sb3(path)(observation), squashed * A_MAX)  # [-1, 1] -> ±a_max
    entry = evaluate_policy(str(tmp_path / "PPO.zip"), CIRCLE, episodes=3, backend="kinematic")
    by_hand = evaluate_policy(
        lambda o: ppo.predict(o.astype(np.float32), deterministic=True)[0] * A_MAX,
        CIRCLE,
        episodes=3,
        backend="kinematic",
    )
    assert _figures(entry) == _figures(by_hand) and entry["episodes"] == 3


def test_sb3_algorithm_refuses_other_zips(tmp_path) -> None:
    import zipfile

    path = tmp_path / "other.zip"
    with zipfile.ZipFile(path, "w") as archive:
        archive.writestr("hello.txt", "not a model")
    with pytest.raises(ValueError, match="not a stable-baselines3 model zip"):
        make_actor(str(path), tolins.CircularSocket(2, 2))


def test_evaluate_writes_the_results_schema_and_shows_reference_rows(
    tmp_path, monkeypatch, capsys
) -> None:
    import tolins.bench.reference as reference

    monkeypatch.setattr(reference, "FOLDER", tmp_path / "none shipped")
    bench_like = tmp_path / "bench"
    bench_like.mkdir()
    (bench_like / "results.json").write_text(
        json.dumps({"schema": SCHEMA, "backend": "kinematic", "rows": {"C2.1": _bench_row("C2.1")}})
    )
    out = tmp_path / "mine"
    argv = ["evaluate", "--policy", "safe", "--env", CIRCLE, "--backend", "kinematic"]
    argv += ["--episodes", str(EPISODES), "--out", str(out), "--reference", str(bench_like)]
    assert main(argv) == 0
    printed = capsys.readouterr().out
    assert "| safe | safe | Circle2x2-v2 |" in printed and "| C2.1 | π_e^safe |" in printed
    document = read_results(out)
    assert document["schema"] == SCHEMA and document["source"] == "evaluate"
    assert document["backend"] == "kinematic" and document["first_eval_seed"] == 10_000
    assert _figures(document["rows"]["safe"]) == _figures(_bench_row("C2.1"))
    assert main(argv[:-2]) == 0  # no --reference: the paper's rows of the same eval env
    assert "| C2.3 | π_n | Circle2x2-v2 | 20.58 ± 0.71 |" in capsys.readouterr().out


def test_read_results_takes_the_old_layout_and_refuses_others(tmp_path) -> None:
    old = tmp_path / "old.json"
    old.write_text(json.dumps({"C2.1": {"reward_mean": 1.0, "eval_env": CIRCLE}}))
    assert read_results(old)["rows"] == {"C2.1": {"reward_mean": 1.0, "eval_env": CIRCLE}}
    other = tmp_path / "other.json"
    other.write_text(json.dumps({"schema": "tolins.results/9", "rows": {}}))
    with pytest.raises(ValueError, match=r"allowed: 'tolins\.results/1'"):
        read_results(other)
    with pytest.raises(ValueError, match="no such file"):
        read_results(tmp_path / "missing")


@pytest.mark.parametrize(
    ("policy", "env", "message"),
    [
        ("no_such_module_xyz:policy", CIRCLE, "cannot import 'no_such_module_xyz'"),
        ("tolins.paper:HORIZON", CIRCLE, "is not a policy"),
        ("tolins.paper:no_such_name", CIRCLE, "has no 'no_such_name'"),
        ("runs/missing/policy.pt", CIRCLE, "no such file"),
        ("missing.zip", CIRCLE, "no such file"),
        ("clever", CIRCLE, "unknown; allowed: an expert"),
        ("safe", "tolins/Circle2x3-v1", "env 'tolins/Circle2x3-v1' is unknown"),
        ("safe", "tolins/Insert-v1", "is unknown; allowed: tolins/Circle2x1-v1"),
    ],
)
def test_bad_inputs_exit_2_with_one_line(capsys, policy, env, message) -> None:
    argv = ["evaluate", "--policy", policy, "--env", env, "--episodes", "1"]
    assert main([*argv, "--backend", "kinematic"]) == 2
    error = capsys.readouterr().err
    assert message in error and error.count("\n") == 1 and error.startswith("tolins evaluate: ")


def test_a_module_in_the_current_folder_is_importable(tmp_path, monkeypatch, capsys) -> None:
    (tmp_path / "my_agent_for_tolins.py").write_text(
        "from tolins.policies.experts import SafeExpert\nclass Agent(SafeExpert):\n    pass\n"
    )
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "path", [p for p in sys.path if p not in ("", str(tmp_path))])
    argv = ["evaluate", "--policy", "my_agent_for_tolins:Agent", "--env", CIRCLE]
    assert main([*argv, "--episodes", "2", "--backend", "kinematic"]) == 0
    assert "| my_agent_for_tolins:Agent |" in capsys.readouterr().out


def test_shipped_references_are_shown_by_default_and_named_with_reference(
    tmp_path, monkeypatch, capsys
) -> None:
    import tolins.bench.reference as reference

    (tmp_path / "quick").mkdir()
    marked = {"reward_mean": 12.34, "reward_per_seed": [12.34], "reward_per_episode": [[12.34] * 2]}
    rows = {"C2.1": {**_bench_row("C2.1", 2), **marked}}  # a consistent row (compare checks)
    document = {"schema": SCHEMA, "backend": "kinematic", "rows": rows}
    (tmp_path / "quick" / "results.json").write_text(json.dumps(document))
    monkeypatch.setattr(reference, "FOLDER", tmp_path)
    argv = ["evaluate", "--policy", "safe", "--env", CIRCLE, "--episodes", "2"]
    assert main([*argv, "--backend", "kinematic"]) == 0
    printed = capsys.readouterr().out
    assert "from reference:quick (shipped, kinematic)" in printed and "| 12.34 ± " in printed
    assert main([*argv, "--backend", "kinematic", "--reference", "reference:quick"]) == 0
    assert "| C2.1 | π_e^safe | Circle2x2-v2 | 12.34 ± " in capsys.readouterr().out
    assert main([*argv, "--backend", "kinematic", "--reference", "reference:nope"]) == 2
    error = capsys.readouterr().err
    assert "reference:nope: no such reference results" in error and error.count("\n") == 1


def test_a_named_evaluation_lines_up_with_a_bench_row_in_compare(tmp_path, capsys) -> None:
    argv = ["evaluate", "--env", CIRCLE, "--backend", "kinematic", "--episodes", "10"]
    for policy in ("safe", "efficient"):
        out = str(tmp_path / policy)
        assert main([*argv, "--policy", policy, "--name", "C2.1", "--out", out]) == 0
    assert "| C2.1 | efficient | Circle2x2-v2 |" in capsys.readouterr().out
    assert read_results(tmp_path / "safe")["rows"]["C2.1"]["policy"] == "safe"
    assert main(["compare", str(tmp_path / "safe"), str(tmp_path / "efficient")]) == 0
    assert "| C2.1 |" in capsys.readouterr().out


def test_docs_benchmark_md_names_every_field_of_the_results_schema(tmp_path) -> None:
    doc = (Path(__file__).resolve().parents[1] / "docs" / "benchmark.md").read_text()
    section = doc.split("## `results.json`: schema `tolins.results/3`", 1)[1].split("\n## ")[0]
    named = set(re.findall(r"`([a-z_]+)`", section))
    for braces in re.findall(r"`\{([a-z_,]+)\}(_[a-z_]+)`", section):
        named |= {f"{figure}{braces[1]}" for figure in braces[0].split(",")}
    entry = evaluate_policy("safe", CIRCLE, episodes=2, backend="kinematic")
    document = read_results(write_evaluation(tmp_path, "safe", entry, backend="kinematic"))
    assert set(document) - named == set()
    assert set(entry) - named == set()


@pytest.mark.slow
def test_the_folder_of_a_real_tolins_train_run_scores_as_its_policy(tmp_path, capsys) -> None:
    out = tmp_path / "bc"
    argv = ["train", "bc", "--env", "tolins/Square-v1", "--backend", "kinematic"]
    assert main([*argv, "--demonstrations", "4", "--epochs", "2", "--out", str(out)]) == 0
    by_folder = evaluate_policy(str(out), "tolins/Square-v1", episodes=2, backend="kinematic")
    by_file = evaluate_policy(
        str(out / "policy.pt"), "tolins/Square-v1", episodes=2, backend="kinematic"
    )
    assert _figures(by_folder) == _figures(by_file)
    assert main(["evaluate", "--policy", str(tmp_path), "--env", CIRCLE]) == 2  # no policy.pt
    assert "a folder without policy.pt" in capsys.readouterr().err

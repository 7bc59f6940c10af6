"""RS-GAIL with CMA-ES, tolerance-guided training and ``tolins train`` (tiny budgets,
kinematic backend)."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest
import torch
from rollouts import train_rs_gail_on_kinematic

from tolins import __version__
from tolins.cli import main
from tolins.learning.artefacts import RunRefused
from tolins.learning.imitation.bc import behaviour_clone
from tolins.learning.imitation.config import BCConfig, ResidualConfig, RSGailConfig
from tolins.learning.imitation.demonstrations import collect
from tolins.learning.imitation.policy import load_policy
from tolins.learning.imitation.rs_gail import Workpiece
from tolins.learning.imitation.tolerance_guided import train_tolerance_guided

ENV = "tolins/Circle2x2-v1"
TINY = {"popsize": 6, "episodes": 2, "eval_episodes": 4, "sigma0": 0.05}


@pytest.fixture(scope="module")
def demos():
    return collect(ENV, "safe", 16, seed=0, backend="kinematic")


@pytest.fixture(scope="module")
def bc_policy(demos):
    return behaviour_clone(demos, BCConfig(epochs=40, batch_size=64), seed=0).policy


def _train(policy, demos, out, config, **kwargs):
    return train_rs_gail_on_kinematic(policy, demos, out, config, ENV, **kwargs)


def _figures(history):
    return [{k: v for k, v in row.items() if k != "wall_s"} for row in history]


def test_a_few_cma_es_iterations_raise_the_reward(demos, bc_policy, tmp_path):
    config = RSGailConfig(iterations=8, popsize=8, episodes=4, eval_episodes=16, sigma0=0.05)
    result = _train(bc_policy.with_flat(bc_policy.get_flat()), demos, tmp_path, config)
    start = result.history[0]["reward"]  # the BC policy, on the same eval seeds
    assert result.final["reward"] > start + 5, (start, result.final)
    assert result.final["success"] >= 0.9
    with open(tmp_path / "curves.csv") as file:
        rows = list(csv.DictReader(file))
    assert len(rows) == 8 and {"reward", "success", "d_expert"} <= set(rows[0])


def test_result_does_not_depend_on_the_number_of_workers(demos, bc_policy, tmp_path):
    results = []
    for workers in (1, 2):
        config = RSGailConfig(iterations=2, workers=workers, **TINY)
        policy = bc_policy.with_flat(bc_policy.get_flat())
        results.append(_train(policy, demos, tmp_path / str(workers), config))
    np.testing.assert_array_equal(results[0].policy.get_flat(), results[1].policy.get_flat())
    assert _figures(results[0].history) == _figures(results[1].history)


def test_resume_continues_to_the_identical_result(demos, bc_policy, tmp_path):
    config = RSGailConfig(iterations=6, discriminator_every=2, **TINY)
    whole = _train(bc_policy.with_flat(bc_policy.get_flat()), demos, tmp_path / "a", config)

    def interrupt(iteration, _row):
        if iteration == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        _train(
            bc_policy.with_flat(bc_policy.get_flat()),
            demos,
            tmp_path / "b",
            config,
            on_iteration=interrupt,
        )
    np.random.seed(12345)  # anything between the runs must not matter
    with pytest.raises(RunRefused, match="resume"):
        _train(bc_policy.with_flat(bc_policy.get_flat()), demos, tmp_path / "b", config)
    resumed = _train(
        bc_policy.with_flat(bc_policy.get_flat()), demos, tmp_path / "b", config, resume=True
    )
    np.testing.assert_array_equal(whole.policy.get_flat(), resumed.policy.get_flat())
    assert _figures(whole.history) == _figures(resumed.history)
    assert whole.final == resumed.final
    # the parameters over training (Fig. 4a) survive the interruption too
    assert whole.means.shape == (7, bc_policy.size)
    np.testing.assert_array_equal(whole.means, resumed.means)
    np.testing.assert_array_equal(whole.means[0], bc_policy.get_flat())
    np.testing.assert_array_equal(whole.means[-1], whole.policy.get_flat())


def test_keep_best_returns_the_mean_with_the_best_evaluation_reward(demos, bc_policy, tmp_path):
    # a large step: the means wander, so the best is rarely the last
    config = RSGailConfig(iterations=5, keep_best=True, **{**TINY, "sigma0": 0.5})
    result = _train(bc_policy.with_flat(bc_policy.get_flat()), demos, tmp_path / "best", config)
    last = RSGailConfig(iterations=5, **{**TINY, "sigma0": 0.5})
    plain = _train(bc_policy.with_flat(bc_policy.get_flat()), demos, tmp_path / "last", last)
    np.testing.assert_array_equal(result.means, plain.means)  # the same search
    assert plain.selected == 5
    rewards = [row["reward"] for row in plain.history] + [plain.final["reward"]]
    assert result.selected == int(np.argmax(rewards))
    np.testing.assert_array_equal(result.policy.get_flat(), result.means[result.selected])
    assert result.final["reward"] == max(rewards)


def test_stop_rule_ends_a_stalled_run(demos, bc_policy, tmp_path):
    config = RSGailConfig(
        iterations=30,
        stop_rule=True,
        patience=2,
        sigma0=1e-9,
        **{k: v for k, v in TINY.items() if k != "sigma0"},
    )
    result = _train(bc_policy.with_flat(bc_policy.get_flat()), demos, tmp_path, config)
    # sigma ~ 0: the reward cannot rise; D(student) of a BC policy stays near 50 %
    assert result.stopped == "stop rule" and len(result.history) < 30


def test_tolerance_guided_trains_only_the_residual(demos, bc_policy, tmp_path):
    pieces = [
        Workpiece(ENV, np.array([3.7, -10.7, 12.2, -13.0, 3.2])),
        Workpiece("tolins/Circle2x8-v1", np.array([3.4, -9.5, 10.9, -11.6, 2.9])),
    ]
    result = train_tolerance_guided(
        bc_policy,
        pieces,
        demos,
        RSGailConfig(iterations=2, **TINY),
        ResidualConfig(8),
        seed=0,
        backend="kinematic",
        out=tmp_path,
        metadata={},
        progress=False,
    )
    guided = result.policy
    assert guided.architecture.kind == "tolerance_guided"
    for ours, theirs in zip(
        guided.nominal.parameters(), bc_policy.nominal.parameters(), strict=True
    ):
        assert torch.equal(ours, theirs)
    assert np.any(guided.get_flat()[-4:] != 0)  # φ2's last layer moved from zero


def test_cli_train_writes_its_artefacts(tmp_path, monkeypatch, capsys):
    common = ["--env", ENV, "--backend", "kinematic", "--demonstrations", "6"]
    assert main(["train", "bc", *common, "--epochs", "5", "--out", str(tmp_path / "bc")]) == 0
    rs = ["--iterations", "2", "--popsize", "4", "--episodes", "1", "--eval-episodes", "2"]
    init = ["--init", str(tmp_path / "bc" / "policy.pt")]
    assert main(["train", "rs-gail", *common, *rs, *init, "--out", str(tmp_path / "rs")]) == 0
    assert main(["train", "rs-gail", *common, *rs, *init, "--out", str(tmp_path / "rs")]) == 2
    assert main(["train", "rs-gail", *common, *rs, *init, "--out", str(tmp_path / "rs"),
                 "--resume"]) == 0  # fmt: skip
    from tolins.learning.imitation import runs

    def no_demonstrations(*_args, **_kwargs):
        raise AssertionError("demonstrations collected before the resume check")

    monkeypatch.setattr(runs, "demonstrations", no_demonstrations)
    capsys.readouterr()
    other = ["--iterations", "3", *rs[2:]]
    assert main(["train", "rs-gail", *common, *other, *init, "--out", str(tmp_path / "rs"),
                 "--resume"]) == 3  # fmt: skip
    err = capsys.readouterr().err
    assert "another run configuration (differs in: configs)" in err and "--resume" in err, err
    monkeypatch.undo()
    for name in ("bc/policy.pt", "bc/run.json", "bc/bc_loss.csv", "rs/policy.pt",
                 "rs/checkpoint.pt", "rs/curves.csv", "rs/curves.png", "rs/run.json"):  # fmt: skip
        assert (tmp_path / name).stat().st_size > 0, name
    run = json.loads((tmp_path / "rs" / "run.json").read_text())
    assert run["seed"] == 0 and run["tolins_version"] == __version__
    assert run["configs"]["rs_gail"]["iterations"] == 2
    _, metadata = load_policy(tmp_path / "rs" / "policy.pt", kind="nominal")
    assert metadata["configs"]["task"]["backend"] == "kinematic"
    fit = json.loads((tmp_path / "bc" / "run.json").read_text())["fit"]
    assert fit["held_out_loss"] > 0


def test_cli_rejects_a_wrong_policy_file(tmp_path, capsys):
    args = ["train", "tolerance-guided", "--env", ENV, "--backend", "kinematic",
            "--nominal", str(tmp_path / "missing.pt"), "--out", str(tmp_path)]  # fmt: skip
    assert main(args) == 2
    assert "missing.pt" in capsys.readouterr().err


@pytest.mark.parametrize("method", ["bc", "rs-gail", "tolerance-guided"])
def test_cli_help_lists_every_config_field(method, capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["train", method, "--help"])
    assert exit_.value.code == 0
    text = capsys.readouterr().out
    assert "--seed" in text and "--backend" in text and "--out" in text
    if method != "bc":
        assert "--discriminator-every" in text and "--stop-rule" in text


def test_workpieces_carry_the_embedding_of_their_socket():
    import gymnasium as gym

    from tolins.embedding import encode
    from tolins.learning.imitation.tolerance_guided import workpieces

    (piece,) = workpieces(["tolins/Circle2x4-v1"])
    socket = gym.spec("tolins/Circle2x4-v1").kwargs["socket"]
    np.testing.assert_array_equal(piece.embedding, encode(socket))
    with pytest.raises(ValueError, match="one each"):
        workpieces([ENV], embeddings=[])

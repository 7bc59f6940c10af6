"""Files a user may be handed are data: no loader of tolins runs code planted in one
(docs/security.md). Each test plants a pickle whose unpickling creates a marker file and
checks that loading the file did not create it (and, where tolins can unpickle on
request, that the payload is real: the marker appears then)."""

from __future__ import annotations

import base64
import io
import json
import pickle
import zipfile
from pathlib import Path

import numpy as np
import pytest
import torch
from rollouts import train_rs_gail_on_kinematic

import tolins
from tolins.cli import main
from tolins.learning.artefacts import RunRefused
from tolins.learning.imitation.config import BCConfig, RSGailConfig

ENV = "tolins/Circle2x2-v1"


class Payload:
    """Unpickling this creates ``marker`` (``open(marker, "w")``)."""

    def __init__(self, marker: Path) -> None:
        self.marker = str(marker)

    def __reduce__(self):
        return (open, (self.marker, "w"))


def _payload(marker: Path) -> bytes:
    return pickle.dumps(Payload(marker))


# --- RS-GAIL checkpoints (tolins train rs-gail --resume, bench stage folders) ---------


@pytest.fixture(scope="module")
def interrupted(tmp_path_factory):
    """An RS-GAIL run interrupted after 2 of 4 iterations, and the same run uninterrupted."""
    from tolins.learning.imitation.bc import behaviour_clone
    from tolins.learning.imitation.demonstrations import collect

    demos = collect(ENV, "safe", 8, seed=0, backend="kinematic")
    start = behaviour_clone(demos, BCConfig(epochs=5, batch_size=64), seed=0).policy
    config = RSGailConfig(iterations=4, popsize=4, episodes=1, eval_episodes=2, sigma0=0.05)
    root = tmp_path_factory.mktemp("rs")

    def train(out, **kwargs):
        policy = start.with_flat(start.get_flat())
        return train_rs_gail_on_kinematic(policy, demos, out, config, ENV, **kwargs)

    def stop(iteration, _row):
        if iteration == 1:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        train(root / "cut", on_iteration=stop)
    return train, root / "cut" / "checkpoint.pt", train(root / "whole")


def _copy_run(checkpoint: Path, folder: Path, edit) -> Path:
    folder.mkdir()
    payload = torch.load(checkpoint, weights_only=True)
    edit(payload)
    torch.save(payload, folder / "checkpoint.pt")
    return folder


def test_an_rs_gail_checkpoint_holds_no_pickle_and_resumes_identically(interrupted, tmp_path):
    train, checkpoint, whole = interrupted
    payload = torch.load(checkpoint, weights_only=True)
    assert "es" not in payload and payload["told"].shape == (2, 4)
    marker = tmp_path / "ran"

    def plant(p):  # the 0.3.0 layout's pickled strategy, beside the arrays
        p["es"] = torch.frombuffer(bytearray(_payload(marker)), dtype=torch.uint8)

    resumed = train(_copy_run(checkpoint, tmp_path / "planted", plant), resume=True)
    assert not marker.exists()
    np.testing.assert_array_equal(resumed.means, whole.means)
    assert resumed.final == whole.final


def test_an_old_checkpoint_with_a_pickled_strategy_is_refused_unrun(interrupted, tmp_path):
    train, checkpoint, _ = interrupted
    marker = tmp_path / "ran"

    def old(p):
        p["format"] = "tolins.rs_gail_run/1"
        p["es"] = torch.frombuffer(bytearray(_payload(marker)), dtype=torch.uint8)

    with pytest.raises(RunRefused, match=r"format 'tolins\.rs_gail_run/1'.*could run code.*delete"):
        train(_copy_run(checkpoint, tmp_path / "old", old), resume=True)
    assert not marker.exists()


def test_an_edited_cma_es_state_is_refused(interrupted, tmp_path):
    train, checkpoint, _ = interrupted

    def edit(p):  # the ranking of the first iteration reversed: another mean follows
        p["told"][0] = -p["told"][0]

    with pytest.raises(RunRefused, match="does not replay"):
        train(_copy_run(checkpoint, tmp_path / "edited", edit), resume=True)


# --- torch checkpoints: policy files, embedding checkpoints -------------------------


@pytest.mark.parametrize("kind", ["policy", "embedding"])
def test_a_torch_checkpoint_with_a_pickled_object_is_refused_unrun(tmp_path, kind):
    from tolins.learning.embedding.checkpoint import load_checkpoint
    from tolins.learning.imitation.policy import load_policy

    marker = tmp_path / "ran"
    path = tmp_path / "planted.pt"
    torch.save({"format": "x", "state_dict": Payload(marker)}, path)
    load = load_policy if kind == "policy" else load_checkpoint
    with pytest.raises(ValueError, match=r"holds objects other than tensors .* would run code"):
        load(path)
    assert not marker.exists()


def test_evaluate_of_a_planted_policy_file_exits_2_unrun(tmp_path, capsys):
    marker = tmp_path / "ran"
    path = tmp_path / "policy.pt"
    torch.save({"format": "tolins.policy/1", "architecture": Payload(marker)}, path)
    args = ["evaluate", "--policy", str(path), "--env", ENV, "--backend", "kinematic"]
    assert main([*args, "--episodes", "1"]) == 2
    assert not marker.exists()
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


# --- SB3 zips (tolins evaluate / record --policy X.zip) ------------------------------


def _sb3_zip(tmp_path: Path, algorithm: str) -> Path:
    pytest.importorskip("stable_baselines3")
    from tolins.learning.agents.sb3 import make_model
    from tolins.learning.agents.sb3_config import Sb3Config

    if algorithm in ("ppo", "sac"):  # tolins's: its observation scale in the network
        model = make_model(Sb3Config(algorithm, ENV, backend="kinematic", env_steps=10))
    else:  # SB3's defaults
        import stable_baselines3

        from tolins.envs.wrappers import agent_env

        env = agent_env(ENV, backend="kinematic")
        model = getattr(stable_baselines3, algorithm.upper())(
            "MlpPolicy", env, seed=0, device="cpu"
        )
    path = tmp_path / f"{algorithm}.zip"
    model.save(path)
    return path


def _replace_data(path: Path, out: Path, edit) -> Path:
    with zipfile.ZipFile(path) as source, zipfile.ZipFile(out, "w") as target:
        for item in source.namelist():
            content = source.read(item)
            if item == "data":
                data = json.loads(content)
                edit(data)
                content = json.dumps(data).encode()
            target.writestr(item, content)
    return out


@pytest.mark.parametrize("algorithm", ["ppo", "sac", "a2c", "td3"])
def test_an_sb3_zip_loads_without_unpickling_and_acts_as_sb3s_load(tmp_path, algorithm):
    from tolins.learning.agents.external import load_sb3

    marker = tmp_path / "ran"
    serialized = base64.b64encode(_payload(marker)).decode()

    def plant(data):
        for key in ("policy_kwargs", "observation_space", "action_space", "policy_class"):
            data[key][":serialized:"] = serialized

    path = _replace_data(_sb3_zip(tmp_path, algorithm), tmp_path / "planted.zip", plant)
    actor = load_sb3(path)
    assert not marker.exists()
    observation = np.array([0.4, -0.3, 0.02, 16.0, 0.1, 0.2, 0.0, 0.3])
    unpickled = load_sb3(_sb3_zip(tmp_path, algorithm), trust_pickle=True)
    np.testing.assert_array_equal(actor(observation), unpickled(observation))
    with pytest.raises(Exception):  # noqa: B017 - whatever SB3 makes of the planted objects
        load_sb3(path, trust_pickle=True)
    assert marker.exists()  # the payload is real: SB3's load ran it


def test_an_sb3_zip_of_an_unknown_policy_is_refused_naming_the_risk(tmp_path, capsys):
    def custom(data):
        data["policy_kwargs"]["features_extractor_class"] = "<class 'evil.Extractor'>"

    path = _replace_data(_sb3_zip(tmp_path, "ppo"), tmp_path / "custom.zip", custom)
    args = ["evaluate", "--policy", str(path), "--env", ENV, "--backend", "kinematic"]
    assert main([*args, "--episodes", "1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "runs code" in err[0] and "--trust-pickle" in err[0], err


def test_policy_help_says_module_name_is_code(capsys):
    for command in ("evaluate", "record"):
        with pytest.raises(SystemExit):
            main([command, "--help"])
        text = " ".join(capsys.readouterr().out.split())
        assert "runs its code" in text and "--trust-pickle" in text, command


# --- declared sizes: checked against bounds before anything is built ----------------


def _policy_file(tmp_path: Path, **architecture) -> Path:
    """A policy file whose declared architecture has ``architecture``'s fields instead."""
    from tolins.learning.imitation.policy import Policy, PolicyArchitecture, save_policy

    path = tmp_path / "policy.pt"
    save_policy(path, Policy(PolicyArchitecture()), {})
    payload = torch.load(path, weights_only=True)
    payload["architecture"].update(architecture)
    torch.save(payload, path)
    return path


def _forbid(monkeypatch, target, name: str) -> None:
    """Building from the file's sizes fails the test (a memory bomb must be refused before)."""

    def built(*args, **kwargs):
        raise AssertionError(f"{name} was built from the file's declared sizes")

    monkeypatch.setattr(target, name, built)


def _one_line_exit_2(path: Path, capsys) -> str:
    args = ["evaluate", "--policy", str(path), "--env", ENV, "--backend", "kinematic"]
    assert main([*args, "--episodes", "1"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(path) in err[0] and "allowed: " in err[0], err
    return err[0]


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("hidden", -1),
        ("hidden", "abc"),
        ("hidden", 30_000),
        ("hidden", 10**6),
        ("hidden", True),
        ("hidden", 32.0),
        ("residual_hidden", 0),
        ("residual_hidden", 10**9),
        ("kind", "bogus"),
    ],
)
def test_a_policy_file_declaring_a_size_or_kind_out_of_bounds_is_refused_unbuilt(
    tmp_path, capsys, monkeypatch, field, value
):
    import tolins.learning.imitation.policy as policy

    path = _policy_file(tmp_path, **{field: value})
    _forbid(monkeypatch, policy, "_mlp")
    assert f"architecture.{field}={value!r}" in _one_line_exit_2(path, capsys)


def test_policy_files_at_the_bounds_load(tmp_path):
    from tolins.learning.imitation.config import HIDDEN_MAX
    from tolins.learning.imitation.policy import (
        Policy,
        PolicyArchitecture,
        load_policy,
        save_policy,
    )

    for architecture in (
        PolicyArchitecture(),
        PolicyArchitecture("tolerance_guided", hidden=1, residual_hidden=HIDDEN_MAX),
    ):
        save_policy(tmp_path / "p.pt", Policy(architecture), {"seed": 0})
        assert load_policy(tmp_path / "p.pt")[0].architecture == architecture


@pytest.fixture(scope="module")
def sb3_zips(tmp_path_factory):
    """tolins's PPO and SAC zips (``algorithm -> path``)."""
    root = tmp_path_factory.mktemp("zips")
    return {algorithm: _sb3_zip(root, algorithm) for algorithm in ("ppo", "sac")}


@pytest.mark.parametrize(
    ("algorithm", "key", "value"),
    [
        ("ppo", "net_arch", [-5]),
        ("ppo", "net_arch", [30_000, 30_000]),
        ("ppo", "net_arch", [200_000, 200_000]),
        ("ppo", "net_arch", ["abc"]),
        ("ppo", "net_arch", {"pi": [64], "vf": [10**6]}),
        ("ppo", "net_arch", [{"pi": [64], "vf": [-1]}]),
        ("ppo", "net_arch", [64] * 100),
        ("ppo", "net_arch", [4096] * 8),
        ("sac", "net_arch", [200_000, 200_000]),
        ("sac", "net_arch", {"pi": [64], "qf": [0]}),
        ("sac", "net_arch", {"pi": [64], "vf": [64]}),
        ("sac", "n_critics", 10**6),
    ],
)
def test_an_sb3_zip_declaring_sizes_out_of_bounds_is_refused_unbuilt(
    sb3_zips, tmp_path, capsys, monkeypatch, algorithm, key, value
):
    pytest.importorskip("stable_baselines3")
    from stable_baselines3.common.policies import ActorCriticPolicy
    from stable_baselines3.sac.policies import SACPolicy

    def edit(data):
        data["policy_kwargs"][key] = value

    path = _replace_data(sb3_zips[algorithm], tmp_path / "sized.zip", edit)
    for policy_class in (ActorCriticPolicy, SACPolicy):
        _forbid(monkeypatch, policy_class, "__init__")
    assert f"{key}=" in _one_line_exit_2(path, capsys)


def test_sb3_zips_of_usual_sizes_load(sb3_zips, tmp_path):
    from tolins.learning.agents.external import load_sb3

    for algorithm, net_arch in (
        ("ppo", {"pi": [256, 256], "vf": [256, 256]}),
        ("ppo", [dict(pi=[64], vf=[64])]),  # SB3 < 1.8's form
        ("sac", {"pi": [400, 300], "qf": [400, 300]}),
    ):

        def edit(data, net_arch=net_arch):
            data["policy_kwargs"]["net_arch"] = net_arch

        path = _replace_data(sb3_zips[algorithm], tmp_path / "usual.zip", edit)
        with pytest.raises(ValueError, match="do not fit"):  # the weights are of 64 × 64
            load_sb3(path)
        assert load_sb3(sb3_zips[algorithm])(np.zeros(8)).shape == (4,)


@pytest.mark.parametrize("data", [b"[" * 5000, b"\x80 not text", b"{"])
def test_an_sb3_zip_whose_json_is_unreadable_is_one_line(sb3_zips, tmp_path, capsys, data):
    path = tmp_path / "bad.zip"
    with zipfile.ZipFile(sb3_zips["ppo"]) as source, zipfile.ZipFile(path, "w") as target:
        for item in source.namelist():
            target.writestr(item, data if item == "data" else source.read(item))
    err = _one_line_exit_2(path, capsys)
    assert "its data entry: " in err and "allowed: a stable-baselines3 model zip" in err


# --- bench stage files (JSON, npy) -------------------------------------------------


def test_a_pickled_npy_is_not_unpickled(tmp_path):
    from tolins.bench.store.integrity import read_array

    marker = tmp_path / "ran"
    path = tmp_path / "means.npy"
    np.save(path, np.array([Payload(marker)], dtype=object), allow_pickle=True)
    with pytest.raises(ValueError, match=r"means\.npy"):
        read_array(path)
    assert not marker.exists()


def test_the_docs_list_every_file_kind():
    text = (Path(tolins.__file__).parents[1] / "docs" / "security.md").read_text()
    kinds = ["checkpoint.pt", "policy.pt", "model.zip", "results.json", "stage.json"]
    kinds += ["episodes.json", "means.npy", ".rrd", "MODULE:NAME", "--trust-pickle"]
    for kind in kinds:
        assert kind in text, kind
    for page in ("benchmark.md", "agents.md"):
        assert "security.md" in (Path(tolins.__file__).parents[1] / "docs" / page).read_text()


def test_pickle_payload_helper_is_real(tmp_path):
    marker = tmp_path / "ran"
    pickle.load(io.BytesIO(_payload(marker)))
    assert marker.exists()


# --- Minari datasets (tolins train --demos) ------------------------------------------


@pytest.mark.parametrize("env_id", ["tolins/Circle2x2-v1", "evil/Env-v0"])
def test_a_dataset_naming_foreign_code_does_not_import_it(tmp_path, monkeypatch, env_id):
    pytest.importorskip("minari")
    from tolins.datasets.reader import load_demonstrations

    root = tmp_path / "ds"
    args = ["dataset", "--env", ENV, "--recipe", "expert-safe", "--episodes", "2"]
    assert main([*args, "--backend", "kinematic", "--out", str(root)]) == 0
    (metadata,) = root.glob("**/data/metadata.json")
    document = json.loads(metadata.read_text())
    spec = json.loads(document["env_spec"])
    spec.update(id=env_id, entry_point="evil_dataset_module:make")
    document["env_spec"] = json.dumps(spec)
    metadata.write_text(json.dumps(document))
    marker = tmp_path / "ran"
    (tmp_path / "evil_dataset_module.py").write_text(f"open({str(marker)!r}, 'w')\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    if env_id == ENV:
        assert len(load_demonstrations(metadata.parent, ENV)) == 2  # our registry's env
    else:
        with pytest.raises(ValueError, match="is not a tolins env"):
            load_demonstrations(metadata.parent)
    assert not marker.exists()

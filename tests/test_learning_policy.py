"""Policies, behaviour cloning and the discriminator (tiny budgets, kinematic backend)."""

from __future__ import annotations

import numpy as np
import pytest
import torch

from tolins import CircularSocket
from tolins.learning.agents.actors import make_actor
from tolins.learning.imitation.bc import behaviour_clone
from tolins.learning.imitation.config import BCConfig, RSGailConfig
from tolins.learning.imitation.demonstrations import collect, pairs
from tolins.learning.imitation.discriminator import Discriminator
from tolins.learning.imitation.policy import Policy, PolicyArchitecture, load_policy, save_policy
from tolins.paper import A_MAX
from tolins.policies import SafeExpert

ENV = "tolins/Circle2x2-v1"


@pytest.fixture(scope="module")
def demos():
    return collect(ENV, "safe", 12, seed=0, backend="kinematic")


def test_demonstrations_are_seeded_expert_pairs(demos):
    again = collect(ENV, "safe", 12, seed=0, backend="kinematic")
    obs, act = pairs(demos)
    assert obs.shape[1] == 8 and act.shape[1] == 4 and len(obs) == len(act) > 12 * 20
    np.testing.assert_array_equal(obs, pairs(again)[0])
    assert all(r.success for r in demos)


def test_actions_are_bounded_by_a_max():
    policy = Policy(PolicyArchitecture(hidden=8), seed=1)
    policy.set_flat(policy.get_flat() * 100)
    actions = policy(torch.randn(256, 8, dtype=torch.float64) * 50).detach().numpy()
    assert np.all(np.abs(actions) <= A_MAX)


def test_residual_starts_at_zero_so_pi_phi_equals_pi_n_bitwise():
    nominal = Policy(PolicyArchitecture(hidden=16), seed=3)
    guided = Policy.tolerance_guided(nominal, residual_hidden=8)
    obs = torch.randn(100, 8, dtype=torch.float64) * 3
    psi = torch.tensor([3.7, -10.7, 12.2, -13.0, 3.2], dtype=torch.float64)
    assert torch.equal(guided(obs, psi), nominal(obs))
    assert guided.size == (13 * 8 + 8) + (8 * 4 + 4)  # only φ2 is trainable
    before = [p.clone() for p in guided.nominal.parameters()]
    guided.set_flat(np.ones(guided.size))
    assert all(torch.equal(a, b) for a, b in zip(before, guided.nominal.parameters(), strict=True))
    assert not torch.equal(guided(obs, psi), nominal(obs))


def test_flat_vector_round_trip():
    policy = Policy(PolicyArchitecture(hidden=8), seed=0)
    vector = np.random.default_rng(0).normal(size=policy.size)
    policy.set_flat(vector)
    np.testing.assert_array_equal(policy.get_flat(), vector)
    with pytest.raises(ValueError, match="allowed"):
        policy.set_flat(vector[:-1])


def test_save_load_round_trip_and_wrong_architecture(tmp_path):
    nominal = Policy(PolicyArchitecture(hidden=8), seed=0)
    guided = Policy.tolerance_guided(nominal, residual_hidden=4)
    guided.set_flat(np.linspace(-1, 1, guided.size))
    save_policy(tmp_path / "p.pt", guided, {"seed": 7})
    loaded, metadata = load_policy(tmp_path / "p.pt")
    obs, psi = torch.randn(10, 8, dtype=torch.float64), torch.ones(5, dtype=torch.float64)
    assert torch.equal(loaded(obs, psi), guided(obs, psi)) and metadata == {"seed": 7}
    with pytest.raises(ValueError, match="'tolerance_guided' policy; allowed: 'nominal'"):
        load_policy(tmp_path / "p.pt", kind="nominal")
    # a checkpoint whose weights do not fit its declared architecture
    payload = torch.load(tmp_path / "p.pt", weights_only=True)
    payload["architecture"]["hidden"] = 16
    torch.save(payload, tmp_path / "bad.pt")
    with pytest.raises(ValueError, match="do not fit the architecture"):
        load_policy(tmp_path / "bad.pt")
    torch.save({"format": "other"}, tmp_path / "other.pt")
    with pytest.raises(ValueError, match="format"):
        load_policy(tmp_path / "other.pt")


def test_bc_loss_falls_and_reports_held_out_fit(demos):
    result = behaviour_clone(demos, BCConfig(hidden=16, epochs=30, batch_size=64), seed=0)
    assert result.losses[-1] < 0.3 * result.losses[0]
    assert result.held_out_episodes == 2
    assert result.held_out_loss < 0.5 * result.losses[0]


def test_discriminator_separates_expert_from_random_pairs(demos):
    obs, act = pairs(demos)
    rng = np.random.default_rng(0)
    random_act = rng.uniform(-A_MAX, A_MAX, size=act.shape)
    discriminator = Discriminator(32, seed=0)
    assert abs(discriminator.expert_probability(obs, act) - 0.5) < 0.1
    discriminator.update((obs, act), (obs, random_act), steps=100)
    assert discriminator.expert_probability(obs, act) > 0.7
    assert discriminator.expert_probability(obs, random_act) < 0.3
    reward = discriminator.reward(obs, act)
    assert np.all(reward >= 0) and reward.mean() > discriminator.reward(obs, random_act).mean()


def test_alpha_schedule():
    config = RSGailConfig(iterations=5, alpha_start=0.0, alpha=0.8)
    assert [config.alpha_at(i) for i in (0, 4)] == [0.0, 0.8]
    assert RSGailConfig().alpha_at(50) == 0.8
    with pytest.raises(ValueError, match="alpha"):
        RSGailConfig(alpha=1.5)


def test_make_actor_names_experts_and_saved_policies(tmp_path) -> None:
    socket = CircularSocket(2, 2)
    assert isinstance(make_actor("safe", socket), SafeExpert)
    with pytest.raises(ValueError, match="unknown"):
        make_actor("clever", socket)
    policy = Policy(PolicyArchitecture())
    path = save_policy(tmp_path / "policy.pt", policy, {"seed": 0})
    actor = make_actor(f"pi={path}", socket)
    observation = np.array([1.0, -0.5, 0.02, 10.0, 0, 0, 0, 0])
    assert np.array_equal(actor(observation), policy.bind()(observation))

"""Demonstrations as a Minari dataset: write, load, clone (tolins and plain torch), evaluate.

python docs/examples/minari_bc.py --backend kinematic --episodes 50 --out datasets
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys

import minari
import numpy as np
import torch

ENV = "tolins/Circle2x2-v1"
NAME = "tolins/circle2x2/expert-safe-v0"  # the default --name of the expert-safe recipe
A_MAX = np.array([2.5, 2.5, 0.1, 2.5])  # the action bound: mm/s, mm/s, rad/s, mm/s


def tolins(*args: str) -> None:
    """Run a ``tolins`` command (as from a shell) and stop on failure."""
    subprocess.run([sys.executable, "-m", "tolins.cli", *args], check=True)


def collate(episodes):
    """A batch of Minari episodes as stacked (observation, action) pairs: each action with
    the observation it answered (an episode has one observation more than actions)."""
    observations = np.concatenate([e.observations[:-1] for e in episodes])
    actions = np.concatenate([e.actions for e in episodes])
    return torch.as_tensor(observations), torch.as_tensor(actions / A_MAX)


def train_torch_bc(dataset, epochs: int) -> torch.nn.Module:
    """A plain MLP cloned with a plain torch DataLoader over the dataset's episodes."""
    torch.manual_seed(0)
    net = torch.nn.Sequential(
        torch.nn.Linear(8, 64), torch.nn.Tanh(), torch.nn.Linear(64, 4), torch.nn.Tanh()
    ).double()
    optimiser = torch.optim.Adam(net.parameters(), lr=3e-3)
    loader = torch.utils.data.DataLoader(dataset, batch_size=8, shuffle=True, collate_fn=collate)
    for _ in range(epochs):
        for observations, actions in loader:
            loss = ((net(observations) - actions) ** 2).sum(dim=1).mean()
            optimiser.zero_grad()
            loss.backward()
            optimiser.step()
    return net


def evaluate(dataset, act, episodes: int) -> tuple[float, float]:
    """Mean reward and success of ``act`` in the dataset's own env (recover_environment)."""
    env = dataset.recover_environment()
    rewards, successes = [], []
    for seed in range(10_000, 10_000 + episodes):  # seeds apart from the dataset's
        observation, info = env.reset(seed=seed)
        total, done = 0.0, False
        while not done:
            observation, reward, terminated, truncated, info = env.step(act(observation))
            total += reward
            done = terminated or truncated
        rewards.append(total)
        successes.append(info["success"])
    env.close()
    return float(np.mean(rewards)), float(np.mean(successes))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--backend", default="mujoco", choices=["mujoco", "kinematic"])
    parser.add_argument("--episodes", type=int, default=50, help="dataset episodes")
    parser.add_argument("--epochs", type=int, default=200, help="BC epochs (both learners)")
    parser.add_argument("--eval-episodes", type=int, default=20)
    parser.add_argument("--out", default="datasets", help="the datasets root")
    args = parser.parse_args()

    # 1. Write the safe expert's episodes as a Minari dataset (OUT/NAME).
    episodes, backend = str(args.episodes), args.backend
    tolins("dataset", "--env", ENV, "--recipe", "expert-safe", "--episodes", episodes,
           "--backend", backend, "--out", args.out)  # fmt: skip

    # 2. Load it with Minari itself.
    os.environ["MINARI_DATASETS_PATH"] = os.path.abspath(args.out)
    dataset = minari.load_dataset(NAME)
    print(f"{NAME}: {dataset.total_episodes} episodes, {dataset.total_steps} steps")
    first = dataset[0]
    peak = first.infos["peak_force"].max()
    print(f"episode 0: {len(first)} steps, peak contact force {peak:.2f} N")

    # 3a. Clone it with tolins (π_bc; the same policy as from the expert directly).
    run = os.path.join(args.out, "bc_tolins")
    tolins("train", "bc", "--env", ENV, "--backend", backend, "--epochs", str(args.epochs),
           "--demos", os.path.join(args.out, NAME), "--out", run)  # fmt: skip
    from tolins.learning.agents.actors import make_actor

    pi_bc = make_actor(run, dataset.recover_environment().unwrapped.nominal_socket)

    # 3b. Clone it with a plain torch DataLoader over the Minari episodes.
    net = train_torch_bc(dataset, args.epochs)

    def pi_torch(observation: np.ndarray) -> np.ndarray:
        with torch.no_grad():
            return net(torch.as_tensor(observation)).numpy() * A_MAX

    # 4. Evaluate both in the dataset's env.
    for label, act in (("tolins BC", pi_bc), ("torch BC", pi_torch)):
        reward, success = evaluate(dataset, act, args.eval_episodes)
        print(f"{label}: reward {reward:.2f}, success {success:.2f}")


if __name__ == "__main__":
    main()

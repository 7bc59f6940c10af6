"""Train PPO (stable-baselines3) on a tolins env, then score it like a Table 1 row.

pip install 'tolins[rl]'
python docs/examples/train_ppo.py --steps 200000 --out runs/ppo.zip
"""

import argparse

import gymnasium as gym
import numpy as np
from gymnasium.wrappers import DtypeObservation, RescaleAction
from stable_baselines3 import PPO

import tolins  # noqa: F401  (registers tolins/...-v1)
from tolins.bench import evaluate_policy


def make_env(env_id: str, backend: str, reward_mode: str) -> gym.Env:
    """The env as SB3 wants it: actions in [-1, 1], float32 observations."""
    env = gym.make(env_id, backend=backend, reward_mode=reward_mode)
    env = RescaleAction(env, -1.0, 1.0)  # the agent's u in [-1, 1] -> a_max * u (mm/s, rad/s)
    return DtypeObservation(env, np.float32)  # the same 8 observations, as float32


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--env", default="tolins/Circle2x2-v1")
    parser.add_argument("--backend", default="mujoco", choices=["mujoco", "kinematic"])
    parser.add_argument("--reward-mode", default="dense", help="sparse, dense, normalized_dense")
    parser.add_argument("--steps", type=int, default=200_000, help="training env steps")
    parser.add_argument("--n-steps", type=int, default=2048, help="env steps per PPO update")
    parser.add_argument("--episodes", type=int, default=100, help="evaluation episodes")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", default="runs/ppo.zip")
    args = parser.parse_args()

    env = make_env(args.env, args.backend, args.reward_mode)
    model = PPO("MlpPolicy", env, n_steps=args.n_steps, seed=args.seed, device="cpu")
    model.learn(total_timesteps=args.steps)
    model.save(args.out)

    # The bench's protocol: the paper's sparse reward, evaluation seeds 10000, 10001, ...
    row = evaluate_policy(args.out, args.env, episodes=args.episodes, backend=args.backend)
    print(
        f"{args.out}: reward {row['reward_mean']:.2f} ± {row['reward_std']:.2f}, "
        f"success {row['success_mean']:.2f}, steps {row['steps_mean']:.1f}, "
        f"collisions {row['collisions_mean']:.2f} over {row['episodes']} episodes"
    )


if __name__ == "__main__":
    main()

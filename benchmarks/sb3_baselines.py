"""Train one stable-baselines3 baseline (PPO or SAC) and print its learning curve.

Usage::

    python benchmarks/sb3_baselines.py sac --backend kinematic --steps 40000 --every 5000
    python benchmarks/sb3_baselines.py ppo --backend mujoco --steps 10000 --reward sparse
    python benchmarks/sb3_baselines.py ppo --env tolins/Circle2x2-v2 --n-envs 8 --steps 8192

The same training as the bench's rows R1.x (:func:`tolins.learning.agents.sb3.train_sb3`, torch on
one thread): the agent learns from ``--reward`` (default ``dense``); every ``--every`` env
steps its deterministic policy is scored with the paper's sparse reward on ``--episodes``
episodes (seeds 30000…). ``--n-envs`` steps that many training envs in one batch (PPO
keeps SB3's 2,048 transitions per update). Each line: env steps trained, cumulative
training throughput (env steps/s, curve episodes excluded), sparse reward, success rate,
collisions.
"""

from __future__ import annotations

import argparse
import tempfile

import tolins  # noqa: F401  (registers the envs)
from tolins.envs.reward import REWARD_MODES
from tolins.learning.agents.sb3 import train_sb3
from tolins.learning.agents.sb3_config import ALGORITHM_NAMES, Sb3Config


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("algorithm", choices=ALGORITHM_NAMES)
    parser.add_argument("--env", default="tolins/Circle2x2-v1")
    parser.add_argument("--backend", choices=("mujoco", "kinematic"), default="mujoco")
    parser.add_argument("--reward", choices=REWARD_MODES, default="dense")
    parser.add_argument("--steps", type=int, default=20_000)
    parser.add_argument("--every", type=int, default=5_000)
    parser.add_argument("--episodes", type=int, default=10)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--n-envs", type=int, default=1, help="training envs in one batch")
    parser.add_argument("--out", default=None, help="folder for model.zip and curves.csv")
    args = parser.parse_args()
    config = Sb3Config(
        args.algorithm,
        args.env,
        backend=args.backend,
        reward_mode=args.reward,
        env_steps=args.steps,
        curve_every=args.every,
        curve_episodes=args.episodes,
        seed=args.seed,
        n_envs=args.n_envs,
    )
    out = args.out or tempfile.mkdtemp(prefix="sb3-")
    print(f"{config}\nout: {out}", flush=True)
    train_sb3(config, out, log=lambda line: print(line, flush=True))


if __name__ == "__main__":
    main()

"""What delicate pins cost: the control step with elastic-plastic pins against rigid pins.

Usage::

    python benchmarks/delicate_cost.py [--episodes 10] [--rounds 2] [--sockets 2,8]
        [--robot free|panda]

For each socket (``CircularSocket(2, cols)``, the paper's 200 µm) and each policy (the safe
and the efficient expert, and random actions pressing down from just over the board), the
same episodes (seeds 0 … ``--episodes`` − 1) run in three envs, side by side in one process,
alternating in blocks so that the machine's load falls on all alike:

* ``rigid -v2``: ``tolins/Circle2x{cols}-v2``'s physics (rigid pins, free flight on);
* ``rigid -v1``: rigid pins on the contact step throughout (no free flight);
* ``delicate``: ``tolins/Circle2x{cols}Delicate-v2``'s (elastic-plastic pins: on the
  contact step chunks of physics steps in which no pin can reach yield, the return mapping
  after each; in free flight the longer steps, the pins held as they are).

With ``--robot panda`` the Panda holds the part, in two envs: ``rigid -v3``
(``tolins/Circle2x{cols}Panda-v3``) and ``delicate`` (the same with
``pins="elastic-plastic"``: the return mapping after every physics step).

Printed per row: ms of thread CPU time per control step (the best of ``--rounds`` rounds),
the delicate env's over each rigid one's, the success rates, and the largest permanent tip
offset and the share of damaged episodes with delicate pins.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from tolins.envs import InsertionEnv
from tolins.geometry.specs import CircularSocket
from tolins.paper import A_MAX
from tolins.policies.experts import EXPERTS

#: The envs compared per robot, rigid ones first: label -> keywords.
VARIANTS = {
    "free": {
        "rigid -v2": {"physics_version": 2},
        "rigid -v1": {"physics_version": 1},
        "delicate": {"physics_version": 2, "pins": "elastic-plastic"},
    },
    "panda": {
        "rigid -v3": {"robot": "panda", "physics_version": 3},
        "delicate": {"robot": "panda", "physics_version": 3, "pins": "elastic-plastic"},
    },
}


class RandomPress:
    """Uniform random actions, pressing down by 1.5 mm/s on average (contact from the start)."""

    name = "random"

    def __init__(self, seed: int) -> None:
        self.rng = np.random.default_rng(seed)

    def __call__(self, observation: np.ndarray) -> np.ndarray:
        return self.rng.uniform(-1.0, 1.0, 4) * A_MAX - np.array([0.0, 0.0, 0.0, 1.5])


def run(env: InsertionEnv, policy_name: str, seeds: range) -> tuple[float, int, list[dict]]:
    """Thread CPU seconds and control steps of the episodes, and their last infos."""
    spent, steps, infos = 0.0, 0, []
    for seed in seeds:
        if policy_name == "random":
            policy = RandomPress(seed)
            observation, info = env.reset(seed=seed, options={"pose": [0.3, -0.2, 0.02, 0.3]})
        else:
            policy = EXPERTS[policy_name]()
            observation, info = env.reset(seed=seed)
        done = False
        while not done:
            action = policy(observation)
            start = time.thread_time()
            observation, _, terminated, truncated, info = env.step(action)
            spent += time.thread_time() - start
            steps += 1
            done = terminated or truncated
        infos.append(info)
    return spent, steps, infos


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--episodes", type=int, default=10)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--sockets", default="2,8", help="columns of the 2*n sockets")
    parser.add_argument("--robot", choices=sorted(VARIANTS), default="free")
    args = parser.parse_args(argv)
    seeds = range(args.episodes)
    variants = VARIANTS[args.robot]
    rigid = [label for label in variants if label != "delicate"]
    print(f"{args.episodes} episodes per row, best of {args.rounds} rounds, thread CPU time\n")
    print(
        f"| socket | policy | {rigid[0]} (ms/step) | "
        + "".join(f"{label} | " for label in rigid[1:])
        + "delicate | "
        + "".join(f"× {label} | " for label in rigid)
        + f"success {rigid[0]} / delicate | max bend (µm) | damaged |"
    )
    print("|---" * (6 + 2 * len(rigid)) + "|")
    for cols in (int(c) for c in args.sockets.split(",")):
        socket = CircularSocket(2, cols)
        envs = {label: InsertionEnv(socket, **kw) for label, kw in variants.items()}
        for policy_name in (*EXPERTS, "random"):
            best = dict.fromkeys(envs, np.inf)
            infos: dict[str, list[dict]] = {}
            for _ in range(args.rounds):
                for label, env in envs.items():
                    spent, steps, infos[label] = run(env, policy_name, seeds)
                    best[label] = min(best[label], 1e3 * spent / steps)
            success = {k: sum(i["success"] for i in v) for k, v in infos.items()}
            delicate = infos["delicate"]
            bend = max(float(np.hypot(*i["pin_bend"].T).max()) for i in delicate)
            damaged = sum(i["damaged"] for i in delicate)
            times = "".join(f"{best[label]:.2f} | " for label in variants)
            ratios = "".join(f"{best['delicate'] / best[label]:.2f} | " for label in rigid)
            print(
                f"| 2*{cols} | {policy_name} | {times}{ratios}"
                f"{success[rigid[0]]} / {success['delicate']} | {1e3 * bend:.1f} "
                f"| {damaged}/{len(delicate)} |",
                flush=True,
            )


if __name__ == "__main__":
    main()

"""The single env's cost per control step on this tree against another revision, side by side.

Usage::

    python benchmarks/env_versions.py                  # against a110726 (tolins 0.4.0)
    python benchmarks/env_versions.py --rev HEAD~3 --blocks 20

The other revision is checked out with ``git worktree`` into a temporary folder. Then, for
each regime, worker processes of the two trees run in turn (old, new, old, new, ...): each
makes ``gym.make("tolins/Circle2x2-v1")``, resets it to the regime's pose and times one
block of ``--steps`` control steps with the thread's CPU clock (a loaded machine disturbs
it less than the wall clock), after one untimed warm-up block. Regimes: ``free`` (in the
air, 3 mm over the board, moving sideways at 0.5 mm/s) and ``contact`` (the pins pressed on the
board 1 mm beside their holes at 2.5 mm/s). Both trees must end at the same pose bit for
bit (``same``). Printed: the fastest and the median block per control step of each, and
new / old.
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

REGIMES = {
    "free": ([1.0, 0.0, 0.0, 3.0], [0.5, 0.0, 0.0, 0.0]),
    "contact": ([1.0, 0.0, 0.0, 0.05], [0.0, 0.0, 0.0, -2.5]),
}

WORKER = """
import json, sys, time
sys.path.insert(0, {root!r})
import gymnasium as gym
import numpy as np
import tolins
assert tolins.__file__.startswith({root!r}), tolins.__file__
env = gym.make("tolins/Circle2x2-v1").unwrapped
pose, action = np.array({pose}), np.array({action})
for timed in (False, True):
    env.reset(seed=0, options={{"pose": pose}})
    start = time.thread_time()
    for _ in range({steps}):
        env.step(action)
    seconds = time.thread_time() - start
print(json.dumps({{"seconds": seconds, "pose": env.backend.data.qpos.tolist()}}))
"""


def _block(root: Path, regime: str, steps: int) -> tuple[float, list[float]]:
    pose, action = REGIMES[regime]
    code = WORKER.format(root=str(root), pose=pose, action=action, steps=steps)
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=root
    )
    result = json.loads(done.stdout.strip().splitlines()[-1])
    return result["seconds"] / steps, result["pose"]


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rev", default="a110726", help="the revision to compare against")
    parser.add_argument("--blocks", type=int, default=10, help="timed blocks per tree and regime")
    parser.add_argument("--steps", type=int, default=40, help="control steps per block")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory(prefix="tolins-old-") as folder:
        old = Path(folder) / "tree"
        subprocess.run(
            ["git", "worktree", "add", "--detach", "-q", str(old), args.rev], cwd=ROOT, check=True
        )
        try:
            print(f"single env, 2*2, ms per control step (thread CPU), {args.blocks} blocks each")
            print("| regime | old min | old median | new min | new median | new/old (min) | same |")
            print("|---|---|---|---|---|---|---|")
            for regime in REGIMES:
                times: dict[str, list[float]] = {"old": [], "new": []}
                poses: dict[str, list[float]] = {}
                for _ in range(args.blocks):
                    for name, root in (("old", old), ("new", ROOT)):
                        seconds, poses[name] = _block(root, regime, args.steps)
                        times[name].append(seconds * 1e3)
                o, n = times["old"], times["new"]
                print(
                    f"| {regime} | {min(o):.3f} | {statistics.median(o):.3f} | {min(n):.3f} | "
                    f"{statistics.median(n):.3f} | {min(n) / min(o):.3f} | "
                    f"{poses['old'] == poses['new']} |"
                )
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(old)], cwd=ROOT)


if __name__ == "__main__":
    main()

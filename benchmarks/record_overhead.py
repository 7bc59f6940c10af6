"""How much recording to rerun adds to an episode's time (target: at most 10 %).

Side by side in one run, per env: the same safe-expert episodes (same seeds, so the same
physics) run on a plain env and on ``RerunRecorder`` writing a real ``.rrd`` file, in
alternating blocks of 5 episodes, so a slow spell of a shared machine hits both alike.
Each episode is timed from ``reset`` to its end, the recorder's end-of-episode work
included (it hands the buffered columns to a worker thread; the time that thread takes
from the next episode's stepping is part of what is measured). ``overhead`` is the median
over block pairs of recorded / plain - 1 (robust to bursts of other load); ``total`` the
ratio of the summed times. The one-time cost (opening the file, logging the board,
waiting for the last send, closing and renaming the file) is reported apart.

    python benchmarks/record_overhead.py           # full run, about 40 s
    python benchmarks/record_overhead.py --quick   # a few seconds, a smoke test
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import gymnasium as gym
import numpy as np

import tolins  # noqa: F401  (registers the env ids)
from tolins.policies.experts import SafeExpert
from tolins.record import RerunRecorder
from tolins.rollouts.episodes import run_episode

#: Square is the cheapest to simulate, so the worst case for the relative overhead.
ENVS = ("tolins/Square-v1", "tolins/Hexagon-v1", "tolins/Circle2x2-v1", "tolins/Circle2x8-v1")
TARGET = 0.10


BLOCK = 5


def _timed_block(env: gym.Env, seeds: range) -> tuple[float, list[int]]:
    start = time.perf_counter()
    steps = [run_episode(env, SafeExpert(), seed=seed).steps for seed in seeds]
    return time.perf_counter() - start, steps


def measure(env_id: str, blocks: int, folder: Path) -> dict[str, float]:
    """Alternating blocks of plain and recorded episodes of ``env_id``; times in ms."""
    plain_env = gym.make(env_id)
    start = time.perf_counter()
    recorder = RerunRecorder(gym.make(env_id), folder / "bench.rrd", policy_name="safe")
    recorder.reset(seed=0)  # logs the board: part of the one-time cost
    setup = time.perf_counter() - start
    _timed_block(plain_env, range(2))  # warm-up of both
    _timed_block(recorder, range(2))
    plain, recorded, steps = [], [], []
    for block in range(blocks):
        seeds = range(block * BLOCK, (block + 1) * BLOCK)
        t_plain, n_plain = _timed_block(plain_env, seeds)
        t_recorded, n_recorded = _timed_block(recorder, seeds)
        if n_plain != n_recorded:
            raise RuntimeError(f"{env_id} seeds {seeds}: {n_plain} vs {n_recorded} steps")
        plain.append(t_plain)
        recorded.append(t_recorded)
        steps += n_plain
    start = time.perf_counter()
    recorder.close()
    close = time.perf_counter() - start
    episodes = blocks * BLOCK
    plain_a, recorded_a = np.array(plain), np.array(recorded)
    return {
        "steps": float(np.mean(steps)),
        "plain_ms": 1e3 * plain_a.sum() / episodes,
        "recorded_ms": 1e3 * recorded_a.sum() / episodes,
        "overhead": float(np.median(recorded_a / plain_a) - 1),
        "total": float(recorded_a.sum() / plain_a.sum() - 1),
        "one_time_ms": 1e3 * (setup + close),
        "kib_per_episode": (folder / "bench.rrd").stat().st_size / 1024 / (episodes + 3),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="few episodes, two envs")
    parser.add_argument("--blocks", type=int, default=16, help="block pairs per env")
    args = parser.parse_args()
    envs, blocks = (ENVS[:2], 2) if args.quick else (ENVS, args.blocks)
    print(
        "| env | steps | plain ms/episode | recorded ms/episode | overhead (median) "
        "| overhead (total) | one-time ms | KiB/episode |"
    )
    print("|---|--:|--:|--:|--:|--:|--:|--:|")
    worst = 0.0
    for env_id in envs:
        with tempfile.TemporaryDirectory() as folder:
            r = measure(env_id, blocks, Path(folder))
        worst = max(worst, r["overhead"])
        print(
            f"| {env_id} | {r['steps']:.1f} | {r['plain_ms']:.1f} | {r['recorded_ms']:.1f} "
            f"| {100 * r['overhead']:+.1f} % | {100 * r['total']:+.1f} % "
            f"| {r['one_time_ms']:.0f} | {r['kib_per_episode']:.0f} |"
        )
    verdict = "met" if worst <= TARGET else "NOT met"
    print(f"\nworst overhead {100 * worst:+.1f} % (target ≤ {100 * TARGET:.0f} %: {verdict})")


if __name__ == "__main__":
    main()

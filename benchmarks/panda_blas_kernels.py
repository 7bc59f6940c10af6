"""How the Panda's trajectories depend on the CPU: the numpy law against the compiled one
under OpenBLAS's kernels of three CPU families.

Usage::

    python benchmarks/panda_blas_kernels.py [--episodes 20] [--expert safe]
        [--envs Circle2x2,Circle2x2Fit50] [--version 3]

numpy's matrix products and solves go through OpenBLAS, which picks its kernels by CPU
(``SkylakeX``: AVX-512, e.g. a Zen 4; ``Haswell``: AVX2 with FMA, e.g. a Zen 3;
``Sandybridge``: AVX without FMA). ``OPENBLAS_CORETYPE`` forces a family, so one machine
shows what another would compute. Each (law, kernel) runs ``--episodes`` episodes of the
expert (seeds 0 …) in a fresh process; printed per workpiece and law: the episodes whose
observations differ in any bit from the same law under this machine's own kernels, and
those whose outcome (success, steps) differs.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import subprocess
import sys

KERNELS = ("", "SkylakeX", "Haswell", "Sandybridge")


def _episodes(env_id: str, expert: str, compiled: bool, count: int) -> list[tuple]:
    """``(success, steps, observations' hash)`` of each episode (in this process)."""
    import gymnasium as gym

    import tolins  # noqa: F401  (registers the ids)
    from tolins.policies import EXPERTS

    env = gym.make(env_id).unwrapped
    env.backend._batch.sims.compiled = compiled
    out = []
    for seed in range(count):
        policy = EXPERTS[expert]()
        observation, _ = env.reset(seed=seed)
        digest, done, steps = hashlib.sha256(observation.tobytes()), False, 0
        while not done:
            observation, _, terminated, truncated, info = env.step(policy(observation))
            digest.update(observation.tobytes())
            steps += 1
            done = terminated or truncated or "error" in info
        out.append((bool(info["is_success"]), steps, digest.hexdigest()))
    return out


def run_under(kernel: str, env_id: str, expert: str, compiled: bool, count: int) -> list:
    """:func:`_episodes` in a fresh process with OpenBLAS's ``kernel`` (``""``: its own)."""
    env = {**os.environ, "OPENBLAS_CORETYPE": kernel} if kernel else dict(os.environ)
    args = json.dumps([env_id, expert, compiled, count])
    code = f"import json, sys; sys.path.insert(0, {os.path.dirname(__file__)!r}); "
    code += "from panda_blas_kernels import _episodes; "
    code += f"print(json.dumps(_episodes(*json.loads({args!r}))))"
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    if done.returncode:
        raise RuntimeError(done.stderr[-2000:])
    return json.loads(done.stdout.splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=20)
    parser.add_argument("--expert", default="safe")
    parser.add_argument("--envs", default="Circle2x2,Circle2x2Fit50")
    parser.add_argument("--version", type=int, default=3)
    args = parser.parse_args()
    print(
        "| workpiece | law | kernels | episodes with a bit differing | outcomes differing | "
        "success |\n|---|---|---|--:|--:|--:|"
    )
    for name in args.envs.split(","):
        env_id = f"tolins/{name}Panda-v{args.version}"
        for compiled in (False, True):
            law = "compiled" if compiled else "numpy"
            runs = {k: run_under(k, env_id, args.expert, compiled, args.episodes) for k in KERNELS}
            own = runs[""]
            for kernel in KERNELS:
                bits = sum(a[2] != b[2] for a, b in zip(own, runs[kernel], strict=True))
                outcomes = sum(a[:2] != b[:2] for a, b in zip(own, runs[kernel], strict=True))
                success = sum(r[0] for r in runs[kernel]) / len(own)
                print(
                    f"| {name} | {law} | {kernel or 'this machine'} | {bits} | {outcomes} "
                    f"| {success:.2f} |",
                    flush=True,
                )


if __name__ == "__main__":
    main()

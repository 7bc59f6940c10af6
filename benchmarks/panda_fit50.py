"""The experts at 50 µm on the Panda against the free body, with confidence intervals.

Usage::

    python benchmarks/panda_fit50.py [--episodes 100] [--experts efficient,safe]
        [--envs Circle2x2Fit50,Circle2x8Fit50,SquareFit50] [--variants default,...]
        [--workers 2] [--version 2]

``panda_validation.py`` runs 20 episodes per row, where a success rate of 0.8 has a 95 %
interval of ±0.18: too wide to tell whether the arm is within 0.05 of the free body. This
runs ``--episodes`` episodes (seeds 0 …, the same initial poses for both bodies, so the
difference is paired) per expert and workpiece, and prints per row the success with its
Wilson 95 % interval, the Panda's success less the free body's with a paired bootstrap
95 % interval, how the Panda's failures ended (out of the horizon with the part on the
board or partly in; a fault), and the mean steps of its successes.

``--variants`` runs the Panda with other law gains (:class:`~tolins.physics.arm.Gains`)
beside the default, to see what a change of the law would buy before any is made:
``side2`` (the sideways spring force limit doubled, 40 N), ``stiff2`` / ``soft2`` (the
stiffness doubled / halved, the damping still critical), ``down2`` / ``down_half`` (the
downward force limit doubled / halved: 10 N, 2.5 N), ``xy4`` / ``xy8`` / ``xy16`` (the
stiffness along x and y alone 4, 8 or 16 times; over the grip's task inertia, 7.4 kg
along x and 5.7 kg along y at a reset over the 2*2, the default is 148 and 113 N/mm, the
free body's servos 200 N/mm), ``tilt4`` (the stiffness about x and y alone four times:
the hand tilts less under the pins' drag); and two that change the
model: ``noslip`` (the default gains with MuJoCo's no-slip solver: friction without the
soft constraints' creep, so that the part does not slide in the hand) and ``firm_pads``
(the pads' contacts with the handle alone stiffer, :func:`firm_pads_world`: a grip that
barely creeps, everything else as the ids have it). Gains and a model change together:
``xy8+firm_pads``. ``--horizon`` (the paper's 40 control steps by default) gives both
bodies more time. ``--version 3`` runs the Panda's ``-v3`` ids (their grip and gains are
``firm_pads`` and ``xy8``'s; a variant of gains then replaces theirs).
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from concurrent.futures import ProcessPoolExecutor

import gymnasium as gym
import numpy as np

import tolins  # noqa: F401  (registers the ids)
from tolins.mjcf.panda import grip_firmly, panda_world
from tolins.paper import HORIZON
from tolins.physics import panda as panda_physics
from tolins.physics.arm import Gains
from tolins.physics.panda import PandaBackend
from tolins.policies import EXPERTS
from tolins.rollouts.collectors import Poses
from tolins.rollouts.episodes import run_episode

DEFAULT = Gains()


def stiffer(gains: Gains, axes: tuple[int, ...], factor: float) -> Gains:
    """``gains`` with the stiffness of task ``axes`` (x, y, z, then rotations) times
    ``factor``, the damping still critical."""
    stiffness = [factor * k if axis in axes else k for axis, k in enumerate(gains.stiffness)]
    return dataclasses.replace(gains, stiffness=tuple(stiffness))


VARIANTS = {
    "default": DEFAULT,
    "side2": dataclasses.replace(
        DEFAULT,
        force_limit=(
            2 * DEFAULT.force_limit[0],
            2 * DEFAULT.force_limit[1],
            DEFAULT.force_limit[2],
        ),
    ),
    "stiff2": DEFAULT.scaled(2.0, None),
    "soft2": DEFAULT.scaled(0.5, None),
    "down2": dataclasses.replace(
        DEFAULT, force_limit=(*DEFAULT.force_limit[:2], 2 * DEFAULT.force_limit[2])
    ),
    "down_half": dataclasses.replace(
        DEFAULT, force_limit=(*DEFAULT.force_limit[:2], 0.5 * DEFAULT.force_limit[2])
    ),
    "xy4": stiffer(DEFAULT, (0, 1), 4.0),
    "xy8": stiffer(DEFAULT, (0, 1), 8.0),
    "xy16": stiffer(DEFAULT, (0, 1), 16.0),
    "tilt4": stiffer(DEFAULT, (3, 4), 4.0),
}
#: The variants that change the model, not the gains.
MODEL_VARIANTS = ("noslip", "firm_pads")
#: The ``noslip`` variant's iterations of MuJoCo's no-slip solver (the part cannot creep
#: in the hand, nor the pins on the board: every contact's friction holds while it can).
NOSLIP_ITERATIONS = 10


def split_variant(variant: str) -> tuple[Gains, str]:
    """A ``--variants`` entry's gains and its model change (``""``: none); ``ValueError``
    naming what is allowed."""
    name, _, model_change = variant.partition("+")
    if name in MODEL_VARIANTS and not model_change:
        name, model_change = "default", name
    if name not in VARIANTS or model_change not in ("", *MODEL_VARIANTS):
        raise ValueError(
            f"--variants: {variant!r}; allowed: one of {', '.join(VARIANTS)}, "
            f"{', '.join(MODEL_VARIANTS)}, or gains+{'|'.join(MODEL_VARIANTS)}"
        )
    return VARIANTS[name], model_change


def firm_pads_world(socket, **kwargs):
    """:func:`~tolins.mjcf.panda.panda_world` with the ``-v3`` ids' firm grip
    (:func:`~tolins.mjcf.panda.grip_firmly`) on a version without it."""
    world = panda_world(socket, **kwargs)
    grip_firmly(world)
    return world


def episodes(
    env_id: str, expert: str, seeds: range, variant: str | None, horizon: int = HORIZON
) -> dict:
    """Per episode of ``seeds``: success, steps, and how it ended (``variant``: the Panda's
    gains or grip, ``None``: the free body)."""
    env = gym.make(env_id, horizon=horizon).unwrapped
    if variant is not None and variant != "default":
        gains, model_change = split_variant(variant)
        # The candidate grip has no option on the ids: the world builder is swapped while
        # the backend compiles (the pool's workers run one job after another).
        panda_physics.panda_world = firm_pads_world if model_change == "firm_pads" else panda_world
        try:
            version = env.settings.physics_version
            env.backend = PandaBackend(env.nominal_socket, env.control_dt, version, gains=gains)
        finally:
            panda_physics.panda_world = panda_world
        if model_change == "noslip":
            env.backend.model.opt.noslip_iterations = NOSLIP_ITERATIONS
    success, steps, ending = [], [], []
    began = time.perf_counter()
    for seed in seeds:
        episode = run_episode(env, EXPERTS[expert](), seed, (Poses(),))
        success.append(episode.success)
        steps.append(episode.steps)
        if episode.error is not None:
            ending.append("fault")
        elif episode.success:
            ending.append("inserted")
        else:
            ending.append("partly in" if episode.poses[-1][3] < -0.01 else "on the board")
    return {
        "success": np.array(success),
        "steps": np.array(steps),
        "ending": ending,
        "seconds": time.perf_counter() - began,
    }


def wilson(successes: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """The Wilson score interval of a success rate."""
    p = successes / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * np.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return centre - half, centre + half


def paired_interval(a: np.ndarray, b: np.ndarray, resamples: int = 10_000) -> tuple[float, float]:
    """A bootstrap 95 % interval of ``mean(a - b)`` over paired episodes."""
    rng = np.random.default_rng(0)
    diff = a.astype(float) - b.astype(float)
    means = diff[rng.integers(0, len(diff), (resamples, len(diff)))].mean(axis=1)
    return float(np.quantile(means, 0.025)), float(np.quantile(means, 0.975))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--experts", default="efficient,safe")
    parser.add_argument("--envs", default="Circle2x2Fit50,Circle2x8Fit50,SquareFit50")
    parser.add_argument(
        "--variants",
        default="default",
        help=f"of {', '.join(VARIANTS)}, {', '.join(MODEL_VARIANTS)} (gains+model change too)",
    )
    parser.add_argument("--horizon", type=int, default=HORIZON, help="control steps")
    parser.add_argument("--version", type=int, choices=(2, 3), default=2, help="the Panda ids'")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    seeds = range(args.episodes)
    variants = args.variants.split(",")
    for variant in variants:
        try:
            split_variant(variant)
        except ValueError as error:
            parser.error(str(error))
    jobs = {
        (name, expert, variant): (
            f"tolins/{name}-v2" if variant is None else f"tolins/{name}Panda-v{args.version}",
            expert,
            seeds,
            variant,
            args.horizon,
        )
        for name in args.envs.split(",")
        for expert in args.experts.split(",")
        for variant in [None, *variants]
    }
    with ProcessPoolExecutor(args.workers) as pool:
        futures = {key: pool.submit(episodes, *job) for key, job in jobs.items()}
        results = {key: future.result() for key, future in futures.items()}
    print(
        "| workpiece | expert | robot | success [95 % CI] | − free body [95 % CI] | failures: "
        "on the board / partly in / fault | steps of successes | s per episode |\n"
        "|---|---|---|--:|--:|--:|--:|--:|"
    )
    for (name, expert, variant), result in results.items():
        success = result["success"]
        low, high = wilson(int(success.sum()), len(success))
        free = results[(name, expert, None)]["success"]
        if variant is None:
            versus = "–"
        else:
            d_low, d_high = paired_interval(success, free)
            versus = f"{success.mean() - free.mean():+.2f} [{d_low:+.2f}, {d_high:+.2f}]"
        endings = result["ending"]
        failures = " / ".join(
            str(endings.count(kind)) for kind in ("on the board", "partly in", "fault")
        )
        robot = "free" if variant is None else f"Panda ({variant})"
        print(
            f"| {name} | {expert} | {robot} | {success.mean():.2f} [{low:.2f}, {high:.2f}] "
            f"| {versus} | {failures} | {result['steps'][success].mean():.1f} "
            f"| {result['seconds'] / len(success):.2f} |",
            flush=True,
        )


if __name__ == "__main__":
    main()

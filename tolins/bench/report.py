"""The files of a benchmark run: ``results.json``, ``results.md``, ``run.json``, plots,
recordings and the inference study, all rewritten from the finished stages."""

from __future__ import annotations

import csv
import datetime
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from tolins.atomic import atomic_json, atomic_write
from tolins.bench import plots, robustness
from tolins.bench.baselines import env_step_curves
from tolins.bench.claims import ClaimCheck
from tolins.bench.config import BACKENDS, RECORDING, BenchRun
from tolins.bench.evaluation import FIRST_SEED
from tolins.bench.integrity import StageFileError, read_array
from tolins.bench.results import read_results, results_document
from tolins.bench.statistics import one_seed_margin
from tolins.bench.table import PAPER, ROWS, TRAININGS
from tolins.bench.training import Trainer
from tolins.envs.tasks import TASKS

_FIGURES = (("reward", 2), ("success", 2), ("steps", 2), ("collisions", 2))


def write_reports(run: BenchRun, trainer: Trainer, seeds: int) -> list[Path]:
    """Write every output of ``run`` into ``run.config.out``; the paths written."""
    out = Path(run.config.out)
    backend = run.config.backend
    document = results_document(
        run.results, source="bench", backend=backend, profile=run.config.profile
    )
    document["claims"] = {check.claim.name: check.to_json() for check in run.claims}
    if run.robustness is not None:
        document[robustness.KEY] = run.robustness
    written = [
        atomic_json(out / "results.json", document),
        atomic_json(out / f"results.{backend}.json", document),
    ]
    if run.study is not None:
        written.append(atomic_json(out / "inference.json", run.study))
        written.append(_copy(run.stage_folders["inference-study"] / "inference_study.png", out))
    else:  # an earlier run's study would read as this run's (its stage stays cached)
        (out / "inference.json").unlink(missing_ok=True)
        (out / "inference_study.png").unlink(missing_ok=True)
    written += _recordings(run, out)
    if run.robustness is not None:
        written.append(robustness.plot_robustness(out / "robustness.png", run.robustness))
    else:  # an earlier run's table would read as this run's
        (out / "robustness.png").unlink(missing_ok=True)
    written += _figures(run, trainer, out)
    written.append(atomic_json(out / "run.json", _run_record(run, seeds)))
    text = format_markdown(run, _other_backend(out, backend))
    written.append(atomic_write(out / "results.md", lambda file: file.write(text), mode="w"))
    return written


def _copy(source: Path, folder: Path, name: str | None = None) -> Path:
    data = source.read_bytes()
    return atomic_write(folder / (name or source.name), lambda file: file.write(data))


def _recordings(run: BenchRun, out: Path) -> list[Path]:
    from tolins.record import RrdError, check_rrd

    written = []
    for row_id in run.results:
        source = run.stage_folders[f"eval-{row_id}-seed0"] / RECORDING
        if source.is_file():
            try:  # a truncated recording is not shipped as the row's
                check_rrd(source)
            except RrdError as error:
                raise StageFileError(f"{error}: delete {source.parent} to rerun it") from error
            written.append(_copy(source, out / "recordings", f"{row_id}.rrd"))
    return written


def _other_backend(out: Path, backend: str) -> tuple[str, dict[str, Any]] | None:
    other = next(b for b in BACKENDS if b != backend)
    path = out / f"results.{other}.json"
    return (other, read_results(path)["rows"]) if path.is_file() else None


def _run_record(run: BenchRun, seeds: int) -> dict[str, Any]:
    import mujoco
    import torch

    import tolins

    return {
        "date": datetime.date.today().isoformat(),
        "config": asdict(run.config),
        "profile": asdict(run.profile),
        "seeds": seeds,
        "wall_s": run.wall_s,
        "stage_wall_s": run.stage_wall_s,
        "cached_stages": run.cached,
        "claims": {check.claim.name: check.to_json() for check in run.claims},
        "versions": {
            "tolins": tolins.__version__,
            "mujoco": mujoco.__version__,
            "torch": torch.__version__,
        },
    }


# --- figures -------------------------------------------------------------------------


def _figures(run: BenchRun, trainer: Trainer, out: Path) -> list[Path]:
    results = run.results
    written = [plots.plot_table(out / "table.png", results, PAPER)]
    curves = _learning_curves(run)
    if curves:
        written.append(plots.plot_learning_curves(out / "learning_curves.png", curves))
    step_curves = env_step_curves(run.stage_folders)
    if step_curves:
        written.append(plots.plot_env_step_curves(out / "env_step_curves.png", step_curves))
    trajectories = _training_trajectories(run, trainer)
    if trajectories is not None:
        written.append(trajectories)
    env_ids = []
    for row in ROWS:
        if row.id in results:
            env_ids += [*(t for tr in row.trainings for t in tr.env_ids), row.eval_env]
    from tolins.bench.force_plot import plot_row_profiles

    written += plot_row_profiles(run.stage_folders, list(results), out)
    sockets = {t.name: t.socket for t in TASKS if t.gym_id in env_ids}
    written.append(plots.plot_tolerance_images(out / "tolerance_images.png", sockets))
    for check in run.claims:
        path = out / "claims" / f"{check.claim.name}.png"
        if check.comparisons:
            written.append(plots.plot_claim(path, check, results))
        else:  # an earlier run's plot would read as this run's
            path.unlink(missing_ok=True)
    return written


def _learning_curves(run: BenchRun) -> dict[str, list[dict[str, float]]]:
    curves = {}
    for stage, folder in run.stage_folders.items():
        path = folder / "curves.csv"
        if stage.startswith("pi_") and path.is_file():
            with open(path) as file:
                curves[stage] = [{k: float(v) for k, v in r.items()} for r in csv.DictReader(file)]
    return curves


def _training_trajectories(run: BenchRun, trainer: Trainer) -> Path | None:
    """The paper's Fig. 4a: one episode of π_n (safe expert, 2*2, seed 0) at iterations
    across its training, beside the expert's."""
    import gymnasium as gym

    from tolins.learning.policy import load_policy
    from tolins.learning.runs import MEANS
    from tolins.policies import EXPERTS
    from tolins.rollouts.episodes import episode_poses

    folder = run.stage_folders.get(trainer.stage_name("pi_n_safe", 0))
    if folder is None or not (folder / MEANS).is_file():
        return None
    training = TRAININGS["pi_n_safe"]
    policy, _ = load_policy(folder / "policy.pt", kind="nominal")
    means = read_array(folder / MEANS)
    last = len(means) - 1
    picks = sorted(set(np.linspace(0, last, 5).round().astype(int).tolist()))
    env = gym.make(training.env_ids[0], backend=run.config.backend)
    trajectories = {"expert (safe)": episode_poses(env, EXPERTS["safe"](), FIRST_SEED)}
    for k in picks:
        label = "π_bc (iteration 0)" if k == 0 else f"iteration {k}"
        actor = policy.with_flat(means[k]).bind()
        trajectories[label] = episode_poses(env, actor, FIRST_SEED)
    env.close()
    title = f"π_n over RS-GAIL training on {training.env_ids[0]} ({run.config.backend})"
    path = Path(run.config.out) / "trajectories.png"
    return plots.plot_training_trajectories(path, trajectories, title)


# --- Markdown ------------------------------------------------------------------------


def _pm(mean: float, std: float, digits: int = 2) -> str:
    return f"{mean:.{digits}f} ± {std:.{digits}f}"


#: Figures whose 95 % CI (and, for reward, IQM) get columns of their own in the table.
_WITH_CI = ("reward", "success")


def _ci(entry: dict[str, Any], key: str, digits: int = 2) -> str:
    low, high = entry.get(key) or (None, None)
    return "–" if low is None else f"[{low:.{digits}f}, {high:.{digits}f}]"


def format_results_table(results: dict[str, dict[str, Any]]) -> str:
    """Table 1 as Markdown: each figure of this run beside the paper's; reward and success
    with the 95 % CI of their mean, reward with the IQM of the per-seed means."""
    header = "| ID | policy | train env | eval env |"
    rule = "|---|---|---|---|"
    for name, _ in _FIGURES:
        extra = " 95 % CI |" + (" IQM |" if name == "reward" else "") if name in _WITH_CI else ""
        header += f" {name} |{extra} paper |"
        rule += "---|" * (2 + extra.count("|"))
    lines = [header, rule]
    for row_id, entry in results.items():
        cells = [row_id, entry["policy"], entry["train_env"], _short(entry["eval_env"])]
        for name, digits in _FIGURES:
            cells.append(_pm(entry[f"{name}_mean"], entry[f"{name}_std"], digits))
            if name in _WITH_CI:
                cells.append(_ci(entry, f"{name}_ci", digits))
            if name == "reward":
                iqm = entry.get("reward_iqm")
                cells.append("–" if iqm is None else f"{iqm:.{digits}f}")
            cells.append(_pm(*PAPER[row_id][name]) if row_id in PAPER else "–")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def format_claims(claims: list[ClaimCheck]) -> str:
    """One bullet per claim: the verdict, what it rests on (training seeds, or the one-seed
    caveat), and each pair's difference [95 % CI] and P(better > worse) [95 % CI]."""
    lines = []
    for check in claims:
        evidence = "; ".join(c.describe() for c in check.comparisons)
        line = f"- **{check.claim.statement}: {check.verdict}** ({check.basis})."
        lines.append(f"{line} {evidence}" if evidence else line)
    return "\n".join(lines)


def format_backends(
    backend: str, results: dict[str, Any], other: str, other_results: dict[str, Any]
) -> str:
    """Each row's means on the kinematic simulator → on MuJoCo, with the change the contact
    physics makes in brackets."""
    physics, kinematic = (
        (results, other_results) if backend == "mujoco" else (other_results, results)
    )
    lines = [
        "| ID | policy | eval env | reward | success rate | steps | collisions |",
        "|---|---|---|---|---|---|---|",
    ]
    for row_id, entry in physics.items():
        if row_id not in kinematic:
            continue
        cells = [row_id, entry["policy"], _short(entry["eval_env"])]
        for name, digits in _FIGURES:
            before, after = kinematic[row_id][f"{name}_mean"], entry[f"{name}_mean"]
            cells.append(f"{before:.{digits}f} → {after:.{digits}f} ({after - before:+.{digits}f})")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def format_markdown(run: BenchRun, other: tuple[str, dict[str, Any]] | None = None) -> str:
    """``results.md``: the table beside the paper, the claims, the study, the figures."""
    config = run.config
    seeds = run.results[next(iter(run.results))]["seeds"] if run.results else 0
    episodes = run.profile.eval_episodes
    parts = [
        f"# tolins bench: Table 1 on the {config.backend} backend ({config.profile} profile)",
        "",
        f"{datetime.date.today().isoformat()}, `{_command(config)}`: "
        f"{run.wall_s / 60:.1f} min ({len(run.cached)} of {len(run.stage_wall_s)} stages "
        f"cached; the stages took {sum(run.stage_wall_s.values()) / 60:.1f} min when they ran, "
        f"evaluations {config.workers} at a time). "
        f"{seeds} training seed(s), {episodes} evaluation episodes per row and seed "
        f"(seeds {FIRST_SEED}…); ± is the std over "
        f"{'seeds' if seeds > 1 else 'episodes'} (the paper's: over its runs). "
        f"{_interval_note(seeds)}",
        "",
        format_results_table(run.results),
        "",
        "![reward and success beside the paper](table.png)",
        "",
        *_force_section(run.results),
        "## The paper's claims in this run",
        "",
        _VERDICT_RULE,
        "",
        format_claims(run.claims),
        "",
        *(f"![{c.claim.name}](claims/{c.claim.name}.png)" for c in run.claims if c.comparisons),
    ]
    if run.study is not None:
        from tolins.inference.report import format_markdown as format_study

        parts += ["", "## Inference study", "", format_study(run.study), ""]
        parts += ["![inference study](inference_study.png)"]
    parts += robustness.format_section(run.robustness)
    if other is not None:
        parts += [
            "",
            f"## Backends side by side ({config.backend} vs {other[0]})",
            "",
            "Means of the same pipeline (same profile, seeds and evaluation seeds) on the "
            "paper's kinematic simulator → on MuJoCo contact physics, the change in "
            f"brackets (`results.{other[0]}.json`: the other backend's last run in this "
            "folder).",
            "",
            format_backends(config.backend, run.results, *other),
        ]
    parts += [
        "",
        "## Figures and recordings",
        "",
        "- `learning_curves.png`: RS-GAIL's curves of every trained policy.",
        "- `env_step_curves.png`: sparse reward against env steps of RS-GAIL's π_n and "
        "the deep-RL baselines (PPO, SAC; rows R1.x).",
        "- `trajectories.png`: π_n's trajectories over training (the paper's Fig. 4a).",
        "- `tolerance_images.png`: the tolerance images of the workpieces.",
        "- `force_profiles/{ID}.png`: each row's normal force against insertion depth over "
        "its evaluation episodes (training seed 0), successes and failures coloured.",
        "- `recordings/{ID}.rrd`: evaluation episodes of each row; "
        "`tolins replay recordings/C2.3.rrd`.",
        "",
    ]
    return "\n".join(parts)


def _force_section(results: dict[str, dict[str, Any]]) -> list[str]:
    """``results.md``'s "Contact forces" section (nothing when no row has the figures)."""
    from tolins.bench.force_table import FORCE_NOTE, format_force_table

    table = format_force_table(results)
    return ["## Contact forces", "", FORCE_NOTE, "", table, ""] if table else []


_VERDICT_RULE = (
    "Each pair: the difference of mean reward [its 95 % stratified-bootstrap CI] and "
    "P(better > worse) [95 % CI] (rliable). *held*: the CI of the difference lies above 0; "
    "*did not hold*: below 0; *inconclusive*: it contains 0. With one training seed the CIs "
    "are over episodes and decide only beyond the training noise they cannot show "
    f"(±{one_seed_margin(2)} reward for two trained rows, ±{one_seed_margin(1)} for a "
    "trained row against an expert). A claim holds when every pair held and does not when "
    "any did not."
)


def _interval_note(seeds: int) -> str:
    if seeds > 1:
        return (
            f"[CI]: the 95 % stratified-bootstrap CI of the mean over the {seeds} training "
            "seeds (rliable, 2000 resamples); IQM: the interquartile mean of the per-seed means."
        )
    return (
        "[CI]: the 95 % bootstrap CI over the episodes of the one training seed (training "
        "variance not measured); IQM: over those episodes."
    )


def _short(env_id: str) -> str:
    return env_id.removeprefix("tolins/").removesuffix("-v1")


def _command(config) -> str:
    parts = ["tolins bench", f"--profile {config.profile}", f"--backend {config.backend}"]
    if config.rows:
        parts.append(f"--rows {config.rows}")
    if config.seeds:
        parts.append(f"--seeds {config.seeds}")
    parts.append(f"--out {config.out}")
    return " ".join(parts)

"""``results.md`` of a benchmark run: Table 1 beside the paper, the claims, the contact
forces, the study, the robustness table, the backends side by side and the figures."""

from __future__ import annotations

import datetime
from typing import TYPE_CHECKING, Any

from tolins.bench.machine import describe_machine
from tolins.bench.reference import PREFIX, reference_path
from tolins.bench.reports.delicate import format_delicate_section
from tolins.bench.reports.robustness import format_robot_section, format_section
from tolins.bench.table.baselines import CurveSummary, summarise_curves
from tolins.bench.table.claims import CEILING, SMALLEST_EFFECT, ClaimCheck
from tolins.bench.table.force_table import FORCE_NOTE, format_force_table
from tolins.bench.table.results import SCHEMA, read_results
from tolins.bench.table.rows import BASELINE_ROWS, PAPER, SB3_METHODS, TRAININGS
from tolins.bench.table.seeds import FIRST_SEED
from tolins.bench.table.statistics import one_seed_margin
from tolins.envs.tasks import env_label

if TYPE_CHECKING:
    from tolins.bench.pipeline.config import BenchRun

_FIGURES = (("reward", 2), ("success", 2), ("steps", 2), ("collisions", 2))


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
        cells = [row_id, entry["policy"], entry["train_env"], env_label(entry["eval_env"])]
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
        needs = f"; {check.seeds_to_decide} seeds would decide" if check.seeds_to_decide else ""
        basis = f"{check.basis}; δ = {check.claim.delta:g} reward{needs}"
        line = f"- **{check.claim.statement}: {check.verdict}** ({basis})."
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
        cells = [row_id, entry["policy"], env_label(entry["eval_env"])]
        for name, digits in _FIGURES:
            before, after = kinematic[row_id][f"{name}_mean"], entry[f"{name}_mean"]
            cells.append(f"{before:.{digits}f} → {after:.{digits}f} ({after - before:+.{digits}f})")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def format_curve_summaries(summaries: list[CurveSummary], settings: dict[str, str]) -> str:
    """Each training's learning curve in a line: where each seed's success left 0, and
    the last point, so that RS-GAIL and the baselines compare at equal env steps
    (``settings``: training name → how it was trained)."""
    lines = [
        "| training | reward learnt from | settings | env steps | success > 0 from (per seed) "
        "| last reward | last success |",
        "|---|---|---|--:|---|--:|--:|",
    ]
    for summary in summaries:
        reward = TRAININGS[summary.training].reward_mode or "sparse + discriminator (RS-GAIL)"
        firsts = ", ".join("never" if f is None else f"{f:,.0f}" for f in summary.first_success)
        lines.append(
            f"| {summary.training} | {reward} | {settings.get(summary.training, '–')} "
            f"| {summary.env_steps:,.0f} | {firsts} "
            f"| {summary.last_reward:.2f} | {summary.last_success:.2f} |"
        )
    return "\n".join(lines)


def _training_settings(run: BenchRun) -> dict[str, str]:
    """How each RS-GAIL π_n and deep-RL training of ``run`` was trained, in a line."""
    profile, backend = run.profile, run.config.backend
    settings = {}
    for training in TRAININGS.values():
        if training.method in SB3_METHODS:
            env_id, reward = training.env_ids[0], training.reward_mode
            config = profile.sb3(training.method, env_id, backend, 0, reward)
            settings[training.name] = config.settings()
        elif training.method == "rs-gail":
            settings[training.name] = (
                f"RS-GAIL from BC: {profile.nominal_iterations} iterations of "
                f"{profile.iteration_episodes} episodes"
            )
    return settings


def _baselines_section(run: BenchRun, curves: dict[str, Any]) -> list[str]:
    """``results.md``'s deep-RL section: this run's curves at equal env steps, or, when the
    profile trains no baseline, their rows from ``reference:paper``."""
    heading = ["## Deep RL from scratch against RS-GAIL at equal env steps", ""]
    ids = [row.id for row in BASELINE_ROWS]
    if any(row_id in run.results for row_id in ids):
        return [
            *heading,
            "R1.x learn from the paper's sparse reward (what its claim is about), R2.x from "
            "the dense one (tolins.envs.reward); every row is evaluated on the sparse reward. "
            "Their curves (deterministic policy, sparse reward) beside RS-GAIL's π_n:",
            "",
            format_curve_summaries(summarise_curves(curves), _training_settings(run)),
            "",
            "![RS-GAIL against PPO and SAC at equal env steps](env_step_curves.png)",
            "",
        ]
    lead = (
        f"The {run.config.profile} profile trains no deep-RL baseline (at its budgets their "
        "curves on the sparse reward stay at 0)"
        if not run.profile.baselines
        else "This run has no deep-RL row (`--rows`)"
    )
    document = read_results(reference_path("paper"))
    shipped = {row_id: document["rows"][row_id] for row_id in ids if row_id in document["rows"]}
    if not shipped or document.get("schema") != SCHEMA:
        note = (
            f"{lead}, and `{PREFIX}paper` ({document.get('date')}) holds none of today's "
            "R rows yet (R1.x on the sparse reward, R2.x on the dense one)."
        )
        return [*heading, note, ""]
    seeds = next(iter(shipped.values()))["seeds"]
    return [
        *heading,
        f"{lead}; these rows are `{PREFIX}paper`'s ({document['date']}, {seeds} training "
        f"seeds, tolins {document['tolins_version']}):",
        "",
        format_results_table(shipped),
        "",
    ]


def stage_minutes(stage_wall_s: dict[str, float]) -> float:
    """The stages' wall times (s, by name) summed, in minutes: a run's work, which a
    reader can scale by the speed of another machine and divide by its cores."""
    return sum(stage_wall_s.values()) / 60


def format_markdown(
    run: BenchRun,
    other: tuple[str, dict[str, Any]] | None = None,
    curves: dict[str, Any] | None = None,
    machine: dict[str, Any] | None = None,
) -> str:
    """``results.md``: the table beside the paper, the claims, the deep-RL curves, the
    study, the figures (``curves``: the env-step curves of the run's stages; ``machine``:
    :func:`tolins.bench.machine.machine` of the machine it ran on)."""
    config = run.config
    seeds = run.results[next(iter(run.results))]["seeds"] if run.results else 0
    episodes = run.profile.eval_episodes
    where = "" if machine is None else f" on {describe_machine(machine)}"
    parts = [
        f"# tolins bench: Table 1 on the {config.backend} backend ({config.profile} profile)",
        "",
        f"{datetime.date.today().isoformat()}, `{_command(config)}`: "
        f"{run.wall_s / 60:.1f} min{where} ({len(run.cached)} of {len(run.stage_wall_s)} "
        f"stages cached; {stage_minutes(run.stage_wall_s):.1f} stage-minutes: the stages' "
        f"wall times summed, as they ran, evaluations {config.workers} at a time). "
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
        "",
        *_baselines_section(run, curves or {}),
    ]
    if run.study is not None:
        from tolins.inference.report import format_markdown as format_study

        parts += ["", "## Inference study", "", format_study(run.study), ""]
        parts += ["![inference study](inference_study.png)"]
    parts += format_section(run.robustness)
    parts += format_robot_section(run.robot)
    parts += format_delicate_section(run.delicate)
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
    if not config.figures:  # `--no-figures`: no links to figures it did not draw
        parts = [part for part in parts if not (part.startswith("![") and part.endswith(".png)"))]
        parts += [
            "",
            "## Recordings",
            "",
            f"{_RECORDINGS} (figures: run again without `--no-figures`).",
            "",
        ]
        return "\n".join(parts)
    parts += [
        "",
        "## Figures and recordings",
        "",
        "- `learning_curves.png`: RS-GAIL's curves of every trained policy.",
        "- `env_step_curves.png`: sparse reward and success against env steps of RS-GAIL's "
        "π_n and the deep-RL baselines (PPO, SAC; rows R1.x and R2.x); `curves.json`: "
        "their points.",
        "- `trajectories.png`: π_n's trajectories over training (the paper's Fig. 4a).",
        "- `tolerance_images.png`: the tolerance images of the workpieces.",
        "- `force_profiles/{ID}.png`: each row's normal force against insertion depth over "
        "its evaluation episodes (training seed 0), successes and failures coloured.",
        f"- {_RECORDINGS}.",
        "",
    ]
    return "\n".join(parts)


#: What results.md says of the run's recordings.
_RECORDINGS = (
    "`recordings/{ID}.rrd`: evaluation episodes of each row; `tolins replay recordings/C2.3.rrd`"
)


def _force_section(results: dict[str, dict[str, Any]]) -> list[str]:
    """``results.md``'s "Contact forces" section (nothing when no row has the figures)."""
    table = format_force_table(results)
    return ["## Contact forces", "", FORCE_NOTE, "", table, ""] if table else []


_VERDICT_RULE = (
    "Each pair: the difference of mean reward [its 95 % stratified-bootstrap CI] and "
    "P(better > worse) [95 % CI] (rliable). *held*: the CI of the difference lies above 0; "
    "*did not hold*: below 0; *no practical difference*: inside [−δ, +δ], the claim's "
    f"smallest effect of interest (δ = {SMALLEST_EFFECT:g} reward: one control step of 40 "
    "saved on a successful insertion; an equivalence test, TOST-style); *inconclusive*: "
    "otherwise, with the training seeds that would decide it at the spread observed. With "
    "one training seed the CIs are over episodes and decide only beyond the training noise "
    f"they cannot show (±{one_seed_margin(2)} reward for two trained rows, "
    f"±{one_seed_margin(1)} for a trained row against an expert), which also rules out "
    "equivalence. A claim did not hold when any pair did not, shows no practical difference "
    "when (otherwise) any pair does, is inconclusive when any pair is, and held when every "
    f"pair held. Head-room: the sparse-return ceiling ({CEILING:.2f}: success in the fewest "
    "steps a full-speed descent takes, no collision) minus the worse row's reward, ours and "
    "the paper's: a claim against a demonstrator near the ceiling has less room to hold."
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


def _command(config) -> str:
    parts = ["tolins bench", f"--profile {config.profile}", f"--backend {config.backend}"]
    if config.rows:
        parts.append(f"--rows {config.rows}")
    if config.seeds:
        parts.append(f"--seeds {config.seeds}")
    parts.append(f"--out {config.out}")
    if not config.figures:
        parts.append("--no-figures")
    return " ".join(parts)

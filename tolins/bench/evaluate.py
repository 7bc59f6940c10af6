"""Score any policy on the bench's protocol (``tolins evaluate``, :func:`evaluate_policy`).

Same evaluation as every Table 1 row (:mod:`tolins.bench.jobs.row_evaluation`): the
sparse reward of the paper, episodes from the seeds of training seed 0 (``10000, 10001,
...``), the same summary (:func:`tolins.bench.table.results.row_entry`) and the same
``results.json`` schema.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from tolins.atomic import atomic_json
from tolins.bench.jobs.policy_episodes import evaluate
from tolins.bench.table.results import read_results, results_document, row_entry
from tolins.bench.table.rows import PAPER, ROWS, Row
from tolins.bench.table.seeds import eval_seeds
from tolins.envs.tasks import env_ids, env_label
from tolins.physics import BACKENDS

#: Episodes of a row in every bench profile but ``tiny``.
EPISODES = 100


def evaluate_policy(
    policy: Any,
    env_id: str,
    *,
    episodes: int = EPISODES,
    backend: str = "mujoco",
    name: str | None = None,
    profile_plot: str | Path | None = None,
) -> dict[str, Any]:
    """The ``results.json`` entry of ``policy`` on ``env_id``, evaluated like a bench row
    (and, with ``profile_plot``, its force profile drawn there:
    :mod:`tolins.bench.reports.force_plot`).

    ``policy``: a string as ``tolins evaluate --policy`` takes it (an expert name, a tolins
    policy file, an SB3 ``PATH.zip``, ``MODULE:NAME``;
    :func:`tolins.learning.agents.actors.make_actor`) or a Python object following
    :mod:`tolins.learning.agents.external`'s protocol (a callable ``observation -> action``,
    or an object with ``predict``/``act``). The entry's
    ``policy`` is that string (or the object's type name); ``name`` is the row's id in
    :func:`write_evaluation` (e.g. ``C2.3``, to line it up with that bench row in
    ``tolins compare``).

    Raises ``ValueError`` for an unknown env id or backend, a bad episode count or a
    policy that cannot be loaded or returns a malformed action.
    """
    allowed = env_ids(generic=False)  # the generic id needs a socket= it cannot be given
    if env_id not in allowed:
        raise ValueError(f"env {env_id!r} is unknown; allowed: {', '.join(allowed)}")
    if backend not in BACKENDS:
        raise ValueError(f"backend {backend!r}; allowed: {', '.join(BACKENDS)}")
    if not isinstance(episodes, int) or isinstance(episodes, bool) or episodes < 1:
        raise ValueError(f"episodes={episodes!r}; allowed: an integer ≥ 1")
    entry: Any = policy
    text = policy if isinstance(policy, str) else type(policy).__name__
    if not isinstance(policy, str):
        from tolins.learning.agents.external import as_actor

        entry = as_actor(policy, name=name or text)
    label = name or text
    row = Row(label, text, "user", env_id, "-")
    # A user's own code (an object, MODULE:NAME) may keep state between calls: its episodes
    # run one after another; experts, policy files and SB3 models side by side.
    stateless = isinstance(policy, str) and (":" not in policy or Path(policy).exists())
    episodes_run = evaluate(
        entry,
        env_id,
        backend,
        eval_seeds(0, episodes),
        policy_name=label,
        vectorized=stateless,
    )
    if profile_plot is not None:
        from tolins.bench.reports.force_plot import plot_force_profile

        plot_force_profile(profile_plot, episodes_run, f"{label} on {env_id}")
    return row_entry(row, [episodes_run])


def write_evaluation(out: str | Path, name: str, entry: dict[str, Any], *, backend: str) -> Path:
    """``out/results.json`` holding the one row ``name`` (schema of the bench's)."""
    document = results_document({name: entry}, source="evaluate", backend=backend, profile=None)
    return atomic_json(Path(out) / "results.json", document)


def _same_env(a: object, b: str) -> bool:
    """Whether ``a`` names ``b``'s workpiece in any physics version (their outcomes agree)."""
    return isinstance(a, str) and env_label(a) == env_label(b)


def reference_rows(
    env_id: str, reference: str | Path | None = None, *, backend: str = "mujoco"
) -> tuple[str, dict[str, dict[str, Any]]]:
    """Rows evaluated on ``env_id`` to show beside a scored policy, and where they are from:
    those of ``reference`` (a results folder or file, or ``reference:NAME`` shipped in
    :mod:`tolins.bench.reference`); without one, the first shipped reference measured on
    ``backend`` that has such rows, else the paper's Table 1."""
    from tolins.bench.reference import PREFIX, reference_names, reference_path

    if reference is not None:
        text = str(reference)
        path = reference_path(text[len(PREFIX) :]) if text.startswith(PREFIX) else reference
        document = read_results(path)
        rows = {k: v for k, v in document["rows"].items() if _same_env(v.get("eval_env"), env_id)}
        return f"{text} ({document.get('backend') or 'unknown backend'})", rows
    for name in reference_names():
        document = read_results(reference_path(name))
        rows = {k: v for k, v in document["rows"].items() if _same_env(v.get("eval_env"), env_id)}
        if rows and document.get("backend") == backend:
            return f"{PREFIX}{name} (shipped, {backend})", rows
    rows = {}
    for row in ROWS:
        if _same_env(row.eval_env, env_id):
            figures = PAPER[row.id]
            rows[row.id] = {
                "policy": row.policy,
                "train_env": row.train_env,
                "eval_env": row.eval_env,
                **{f"{k}_mean": mean for k, (mean, _) in figures.items()},
                **{f"{k}_std": std for k, (_, std) in figures.items()},
            }
    return "the paper's Table 1 (its simulator)", rows


def format_rows(rows: dict[str, dict[str, Any]]) -> str:
    """Rows as a Markdown table: mean ± std of reward, success rate, steps, collisions."""
    lines = [
        "| ID | policy | eval env | reward | success rate | steps | collisions |",
        "|---|---|---|---|---|---|---|",
    ]
    for row_id, entry in rows.items():
        cells = [row_id, entry["policy"], entry["eval_env"].removeprefix("tolins/")]
        for figure in ("reward", "success", "steps", "collisions"):
            cells.append(f"{entry[f'{figure}_mean']:.2f} ± {entry[f'{figure}_std']:.2f}")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)

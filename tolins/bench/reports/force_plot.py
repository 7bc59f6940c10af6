"""The force profile of a row: normal force against insertion depth over its evaluation
episodes, successes and failures in two colours (``force_profiles/{ID}.png`` of a bench,
``force_profile.png`` of ``tolins evaluate --out``)."""

from __future__ import annotations

from pathlib import Path

from tolins.bench.reports.plots import pyplot, save_figure
from tolins.rollouts.episodes import Episode

_COLOURS = {True: ("tab:green", "success"), False: ("tab:red", "failure")}


def has_profiles(episodes: list[Episode]) -> bool:
    """Whether every episode kept its per-step force profile."""
    return bool(episodes) and all(e.profile is not None for e in episodes)


def plot_force_profile(path: str | Path, episodes: list[Episode], title: str) -> Path:
    """One line per episode through its steps' ``(depth, peak normal force)``: depth of the
    pin tips below the board's top (mm; negative above it), the step's peak summed normal
    force between the pins and the board (N). Raises ``ValueError`` without profiles."""
    if not has_profiles(episodes):
        raise ValueError(f"{title}: episodes without force profiles; allowed: tolins ≥ 0.4's")
    plt = pyplot()
    figure, axis = plt.subplots(figsize=(7, 4))
    labelled: set[bool] = set()
    for episode in sorted(episodes, key=lambda e: e.success):  # successes drawn on top
        depth = [p[0] for p in episode.profile]
        force = [p[1] for p in episode.profile]
        colour, label = _COLOURS[episode.success]
        counts = sum(e.success == episode.success for e in episodes)
        name = None if episode.success in labelled else f"{label} ({counts})"
        labelled.add(episode.success)
        axis.plot(depth, force, color=colour, alpha=0.35, linewidth=1, marker=".", label=name)
    axis.axvline(0.0, color="grey", linewidth=0.8, linestyle="--")
    axis.set_xlabel("insertion depth below the board's top (mm)")
    axis.set_ylabel("peak normal force in the step (N)")
    axis.set_title(f"{title}: {len(episodes)} evaluation episodes")
    axis.grid(alpha=0.3)
    axis.legend()
    figure.tight_layout()
    return save_figure(figure, path)


def plot_row_profiles(episodes: dict[str, list[Episode]], out: Path) -> list[Path]:
    """``out/force_profiles/{ID}.png`` of each row from ``episodes`` (row id -> the
    episodes of its first training seed; rows whose episodes have no profiles: none)."""
    written = []
    for row_id, row_episodes in episodes.items():
        path = out / "force_profiles" / f"{row_id}.png"
        if has_profiles(row_episodes):
            title = f"{row_id} (training seed 0)"
            written.append(plot_force_profile(path, row_episodes, title))
        else:  # an earlier run's plot would read as this run's
            path.unlink(missing_ok=True)
    return written

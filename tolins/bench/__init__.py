"""The benchmark suite: the paper's Table 1, its robustness table and inference study
(``tolins bench``), and any policy scored on the same protocol (``tolins evaluate``).

Entry point: :func:`tolins.bench.pipeline.runner.run_bench` with a
:class:`tolins.bench.pipeline.config.BenchConfig`. Its parts, each importing only those
listed before it:

- :mod:`.table`: what is measured and how it is summarised: Table 1's rows and trainings
  and the paper's figures, the evaluation seeds, the robustness table, a row's figures
  (``results.json``), interval estimates, the paper's claims, ``tolins compare``.
- :mod:`.store`: the config-hash stage cache and the checked reads of stage files.
- :mod:`.jobs`: the stage bodies: demonstrations, trainings, the evaluation of one row,
  the robustness stages, the inference study, π_n's trajectories.
- :mod:`.reports`: the files of a run (``results.md``, plots, recordings) from its
  finished stages; they run no episode.
- :mod:`.pipeline`: a run: its budgets (profiles), the stages planned once with their
  settings, the executors, the progress bar, the timeline.

:mod:`.evaluate` is ``tolins evaluate``'s engine; :mod:`.reference` holds the shipped
results.
"""


def __getattr__(name: str):
    # evaluate_policy imports gymnasium and torch: only on use, and without import cycles
    if name == "evaluate_policy":
        from tolins.bench.evaluate import evaluate_policy

        return evaluate_policy
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["evaluate_policy"]

"""The benchmark suite: the paper's Table 1 and inference study (``tolins bench``).

Entry point: :func:`tolins.bench.runner.run_bench` with a
:class:`tolins.bench.config.BenchConfig`. Layout: :mod:`.table` (the rows and the paper's
figures), :mod:`.profiles` (budgets), :mod:`.stages` (the config-hash cache),
:mod:`.training` and :mod:`.evaluation` (the stages), :mod:`.results` and :mod:`.claims`
(figures and verdicts), :mod:`.report` and :mod:`.plots` (the files).
"""


def __getattr__(name: str):
    # evaluate_policy imports gymnasium and torch: only on use, and without import cycles
    if name == "evaluate_policy":
        from tolins.bench.scoring import evaluate_policy

        return evaluate_policy
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["evaluate_policy"]

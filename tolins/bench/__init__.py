"""The benchmark suite: the paper's Table 1 and inference study (``tolins bench``).

Entry point: :func:`tolins.bench.runner.run_bench` with a
:class:`tolins.bench.config.BenchConfig`. Layout: :mod:`.table` (the rows and the paper's
figures), :mod:`.profiles` (budgets), :mod:`.stages` (the config-hash cache),
:mod:`.training` and :mod:`.evaluation` (the stages), :mod:`.results` and :mod:`.claims`
(figures and verdicts), :mod:`.report` and :mod:`.plots` (the files).
"""

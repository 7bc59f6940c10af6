"""The files of a bench run, rewritten from its finished stages: ``results.json``,
``run.json`` and the recordings (:mod:`.writer`), ``results.md`` (:mod:`.markdown`), the
figures (:mod:`.figures`, drawn by :mod:`.plots`, :mod:`.force_plot` and
:mod:`.robustness`). Nothing here runs an episode."""

"""The stage bodies of ``tolins bench``, each a job of
:mod:`tolins.bench.pipeline.executor` that runs the planned stage it is handed
(:class:`~tolins.bench.store.cache.Stage`: its name, its config, its settings) into its
folder of the cache: the expert demonstrations (:mod:`.demonstrations`), the trainings
(:mod:`.training`), the evaluation of one row and training seed (:mod:`.row_evaluation`),
the robustness stages (:mod:`.robustness`), the inference study (:mod:`.study`) and π_n's
trajectories over its training (:mod:`.trajectories`). Their episodes run through
:mod:`.policy_episodes`."""

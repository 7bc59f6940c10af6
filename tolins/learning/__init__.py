"""Learning (torch, CPU). Imports the layers below it (geometry up to datasets); never
inference, bench, record, dmc or the cli.

Three parts, each importing only those before it:

* :mod:`tolins.learning.embedding`: the tolerance autoencoder and ``encode(spec)`` with the
  shipped checkpoints (users import it as :mod:`tolins.embedding`);
* :mod:`tolins.learning.imitation`: behaviour cloning, the GAIL discriminator, RS-GAIL, the
  tolerance-guided policy, and the runs of ``tolins train``;
* :mod:`tolins.learning.agents`: policies from outside tolins (stable-baselines3 runs and
  zips, Python objects) and :func:`~tolins.learning.agents.actors.make_actor`, which turns
  any policy a command line names into an actor.

Shared by all three: ``artefacts`` (atomic torch saves, checked loads, run metadata) and
``curves`` (learning curves as CSV and PNG).
"""

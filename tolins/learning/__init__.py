"""Learning (torch, CPU). Imports geometry, mjcf and envs; never record, dmc or the cli.

The tolerance autoencoder: ``ranges`` (the workpieces of each family), ``embedding_data``
(their tolerance images), ``autoencoder`` (network and loss), ``embedding_config`` and
``embedding_train`` (``tolins embed train``), ``checkpoint`` (atomic save, checked load),
``embedding_eval`` (IoU and θ error). Its public entry point is :mod:`tolins.embedding`.
"""

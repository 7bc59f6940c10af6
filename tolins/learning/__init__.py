"""Learning (torch, CPU). Imports geometry, mjcf and envs; never record, dmc or the cli.

The tolerance autoencoder: ``ranges`` (the workpieces of each family), ``embedding_data``
(their tolerance images), ``autoencoder`` (network and loss), ``embedding_config`` and
``embedding_train`` (``tolins embed train``), ``checkpoint`` (atomic save, checked load),
``embedding_eval`` (IoU and θ error), ``embedding`` (``encode(spec)`` with the shipped
checkpoints; users import it as :mod:`tolins.embedding`).
"""

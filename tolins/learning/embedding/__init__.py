"""The tolerance autoencoder: a workpiece's tolerance image to its 5-d embedding ψ and back.

``ranges`` (the workpieces of each family), ``data`` (their tolerance images),
``autoencoder`` (network and loss), ``config`` and ``train`` (``tolins embed train``),
``checkpoint`` (atomic save, checked load), ``evaluation`` (IoU and θ error), ``encoding``
(``encode(spec)`` with the shipped checkpoints; users import it as :mod:`tolins.embedding`).

Importing this package loads nothing: ``config`` and ``ranges`` stay free of torch.
"""

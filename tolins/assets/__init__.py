"""The tolerance embedding's shipped checkpoints (package data, no code):
``embedding_<family>.pt`` (the paper's) and ``embedding_<family>_graded.pt``, read by
:mod:`tolins.learning.embedding.encoding` through :func:`tolins.resources.package_path`."""

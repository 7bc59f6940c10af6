"""``tolins.embedding``: the paper's 5-d tolerance embedding ψ(ε) of a workpiece.

``encode(spec)`` is the embedding of ``spec``'s tolerance image; ``decode`` and
``reconstruct`` run the decoder; ``model="graded"`` picks the graded checkpoints. This
module is the users' name for :mod:`tolins.learning.embedding.encoding`, which holds the code and
documents it; the names below are the same objects (one cache of loaded models).
"""

from tolins.learning.embedding.encoding import (
    ASSETS,
    ExtrapolationWarning,
    checkpoint_path,
    decode,
    encode,
    load_model,
    reconstruct,
)

__all__ = [
    "ASSETS",
    "ExtrapolationWarning",
    "checkpoint_path",
    "decode",
    "encode",
    "load_model",
    "reconstruct",
]

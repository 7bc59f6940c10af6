"""Scripted policies: the paper's experts."""

from tolins.policies.experts import EXPERTS, EfficientExpert, SafeExpert

__all__ = ["EXPERTS", "EfficientExpert", "SafeExpert"]

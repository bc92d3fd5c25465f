"""Stability classification of a swept Dataset: unstable points and regimes A, B, C (§4.2)."""
from __future__ import annotations

__all__ = ["classify"]


def classify(ds):
    """Add the classification variables to ``ds`` when its metrics allow it."""
    return ds

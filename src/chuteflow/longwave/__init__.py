"""Long-wave (kinematic-wave) theory: α(k) = α1 k + α2 k² + O(k³) by perturbation theory."""

from .theory import LongWave, longwave
from .transverse import TransverseResult, transverse, transverse_longwave

__all__ = ["LongWave", "longwave", "TransverseResult", "transverse", "transverse_longwave"]

"""Long-wave (kinematic-wave) theory: α(k) = α1 k + α2 k² + O(k³) by perturbation theory."""

from .spanwise import TransverseResult, transverse, transverse_longwave
from .theory import LongWave, longwave

__all__ = ["LongWave", "longwave", "TransverseResult", "transverse", "transverse_longwave"]

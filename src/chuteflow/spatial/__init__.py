"""Spatial stability of the chute flow: inlet forcing, the signalling problem, absolute versus
convective instability (the temporal analysis of the paper, §4, continued to complex k)."""

from ._core import DEFAULT_SPATIAL_POLICY, SpatialPolicy
from .absolute import AbsoluteResult, absolute_instability
from .branches import SpatialPoint, spatial_dispersion, spatial_point
from .inlet_forcing import SignallingResult, signalling

__all__ = [
    "DEFAULT_SPATIAL_POLICY",
    "AbsoluteResult",
    "absolute_instability",
    "SpatialPolicy",
    "SignallingResult",
    "SpatialPoint",
    "signalling",
    "spatial_dispersion",
    "spatial_point",
]

"""Closures: constitutive relations (Lun et al.; Garzó & Dufty), g0(ν) and floor conditions (Johnson–Jackson).

Each kind of closure has a registry (:class:`Registry`): :data:`RADIALS` (g0),
:data:`WALLS` (floor conditions) and :data:`TRANSPORTS` (kinetic-theory transport closures).
:class:`ChuteModel` carries one of each with the material and floor parameters.
"""

from .garzo_dufty import GarzoDuftyClosure, GarzoDuftyMfixClosure, garzo_dufty_reduced
from .kinetic import (
    TRANSPORTS,
    LunClosure,
    LunFullClosure,
    MfixLunClosure,
    TransportClosure,
    lun_functions,
    register_transport,
)
from .model import (
    CLOSURES,
    FIELDS,
    FLOOR,
    FUNCTIONS,
    ORDERS,
    PARAMETERS,
    PRESETS,
    TRANSPORT,
    ChuteModel,
)
from .radial import (
    RADIALS,
    CarnahanStarling,
    LunSavage,
    MaAhmadi,
    RadialDistribution,
    register_radial,
)
from .registry import Registry
from .walls import WALLS, JohnsonJackson, WallCondition, register_wall

__all__ = [
    "CLOSURES",
    "FIELDS",
    "FLOOR",
    "FUNCTIONS",
    "ORDERS",
    "PARAMETERS",
    "RADIALS",
    "TRANSPORT",
    "TRANSPORTS",
    "WALLS",
    "CarnahanStarling",
    "ChuteModel",
    "JohnsonJackson",
    "GarzoDuftyClosure",
    "GarzoDuftyMfixClosure",
    "LunClosure",
    "LunFullClosure",
    "LunSavage",
    "MaAhmadi",
    "MfixLunClosure",
    "PRESETS",
    "RadialDistribution",
    "Registry",
    "TransportClosure",
    "WallCondition",
    "garzo_dufty_reduced",
    "lun_functions",
    "register_radial",
    "register_transport",
    "register_wall",
]

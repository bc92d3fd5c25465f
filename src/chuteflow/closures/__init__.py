"""Closures: constitutive relations (Lun et al.), g0(ν) and floor conditions (Johnson–Jackson)."""
from .kinetic import LunClosure, lun_functions
from .model import FLOOR, FUNCTIONS, ORDERS, TRANSPORT, ChuteModel
from .radial import CarnahanStarling, LunSavage, RadialDistribution
from .walls import JohnsonJackson

__all__ = ["ChuteModel", "LunClosure", "lun_functions", "LunSavage", "CarnahanStarling",
           "RadialDistribution", "JohnsonJackson", "TRANSPORT", "FLOOR", "FUNCTIONS", "ORDERS"]

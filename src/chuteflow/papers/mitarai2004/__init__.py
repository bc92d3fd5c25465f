"""Mitarai & Nakanishi (2004): linear stability of rapid granular flow down a slope.

N. Mitarai and H. Nakanishi, "Linear stability analysis of rapid granular flow down a slope
and density wave formation", J. Fluid Mech. (2004). What is specific to this paper:

- :mod:`.points`: the named points P1–P5, Q1–Q3 and the ranges and grids of its diagrams;
- :mod:`.checks`: its statements about the stability diagrams (section 4.2), checked on a
  sweep Dataset; :mod:`.edges`: the least dense flow of each θ contour, for one of them;
- :mod:`.stages`: the reproduction stages ``steady``, ``stability``, ``diagrams`` and
  ``reduced`` run by ``chuteflow reproduce``.

Equation numbers cited in this package are the printed ones (docs/paper-labels.md); the
misprints the code corrects are listed in docs/errata.md.
"""

from .points import PAPER_UNSTABLE, POINTS, NamedPoint, markers, point

__all__ = ["POINTS", "PAPER_UNSTABLE", "NamedPoint", "markers", "point"]

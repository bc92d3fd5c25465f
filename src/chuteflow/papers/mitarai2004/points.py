"""The paper's named parameter points and the defaults of its diagrams, defined once.

Mitarai & Nakanishi mark eight steady flows in their stability diagrams (figures 6 and 12,
section 4.2): P1–P5 for the roughness φ = 0.05 and Q1–Q3 for φ = 0.10. Everything in
:mod:`chuteflow.papers.mitarai2004` that needs them (the markers of the diagram sweeps, the
dispersion-relation and eigenfunction figures, the checkpoints) takes them from here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = [
    "NamedPoint",
    "POINTS",
    "PAPER_UNSTABLE",
    "ROUGHNESSES",
    "DIAGRAM_RANGES",
    "DIAGRAM_SHAPE",
    "LONGWAVE_STRIDE",
    "REDUCED_SHAPE",
    "FIGURES",
    "figure",
    "markers",
    "point",
]


@dataclass(frozen=True)
class NamedPoint:
    """A steady flow named in the paper.

    Attributes
    ----------
    name : str
        The paper's name (``"P1"`` … ``"P5"``, ``"Q1"`` … ``"Q3"``).
    theta : float
        Inclination θ in degrees.
    nu0 : float
        Floor packing fraction ν0(0).
    roughness : float
        Floor roughness φ.
    """

    name: str
    theta: float
    nu0: float
    roughness: float

    def marker(self) -> tuple[str, float, float]:
        """``(name, theta, nu0)``: the form of :attr:`chuteflow.sweep.SweepConfig.markers`."""
        return (self.name, self.theta, self.nu0)


#: The paper's points (section 4.2; figures 6 and 12 mark them in the (h, ν̄) plane).
POINTS: dict[str, NamedPoint] = {
    p.name: p
    for p in (
        NamedPoint("P1", 16.0, 0.05, 0.05),
        NamedPoint("P2", 16.0, 0.08, 0.05),
        NamedPoint("P3", 16.0, 0.10, 0.05),
        NamedPoint("P4", 14.0, 0.05, 0.05),
        NamedPoint("P5", 17.0, 0.10, 0.05),
        NamedPoint("Q1", 20.0, 0.10, 0.10),
        NamedPoint("Q2", 20.0, 0.15, 0.10),
        NamedPoint("Q3", 20.0, 0.17, 0.10),
    )
}

#: The paper's verdicts (section 4.2): unstable (True) or stable for all k (False). P1 lies
#: in regime B, P4 in A, P5 in C; Q3 is unstable; Q1 and Q2 are not stated.
PAPER_UNSTABLE: dict[str, bool] = {"P1": True, "P2": False, "P3": False, "P4": True, "P5": True, "Q3": True}

#: The two roughness values of the paper's diagrams (figures 6 and 12).
ROUGHNESSES: tuple[float, ...] = (0.05, 0.10)

#: (θ range in degrees, ν0(0) range) of the paper's stability diagrams (figures 6 and 12):
#: the band where steady flows exist, found by scanning with :mod:`chuteflow.steady`.
DIAGRAM_RANGES: dict[float, tuple[tuple[float, float], tuple[float, float]]] = {
    0.05: ((12.0, 18.0), (0.01, 0.25)),
    0.10: ((16.5, 22.5), (0.01, 0.30)),
}

#: (n_theta, n_nu0) of the stability diagrams, by quick mode: 40 × 40 in quick mode, 100 ×
#: 100 in full mode (the long-wave coefficient on every third row and column, and exactly
#: wherever those do not decide its sign: chuteflow.papers.mitarai2004.adaptive).
DIAGRAM_SHAPE: dict[bool, dict[float, tuple[int, int]]] = {
    True: {0.05: (40, 40), 0.10: (40, 40)},
    False: {0.05: (100, 100), 0.10: (100, 100)},
}

#: Stride of the coarse grid on which the sweep computes the long-wave coefficient.
LONGWAVE_STRIDE: dict[bool, int] = {True: 3, False: 3}

#: (n_theta, n_nu0) of the 1D model's diagrams (figure 17) when the full model's diagram of
#: the same run is not available (otherwise its grid is used, point by point).
REDUCED_SHAPE: dict[bool, tuple[int, int]] = {True: (7, 7), False: (60, 60)}


def point(name: str) -> NamedPoint:
    """The named point; ``KeyError`` naming the available ones if there is none."""
    try:
        return POINTS[name]
    except KeyError:
        raise KeyError(f"no point {name!r} in the paper (have {', '.join(POINTS)})") from None


def markers(roughness: float) -> tuple[tuple[str, float, float], ...]:
    """The points of one roughness as sweep markers ``(name, theta, nu0)`` (none for a
    roughness the paper does not treat)."""
    return tuple(
        p.marker() for p in POINTS.values() if math.isclose(float(roughness), p.roughness, rel_tol=1e-9)
    )


#: The paper's figures by LaTeX label → number as printed (docs/paper-labels.md).
FIGURES: dict[str, int] = {
    "slope": 1,
    "steadyphase005": 2,
    "steady": 3,
    "steadyphase010": 4,
    "steady01": 5,
    "phase005": 6,
    "disp": 7,
    "dispmag": 8,
    "disp-AC": 9,
    "eigens": 10,
    "eigenu": 11,
    "phase010": 12,
    "disp01": 13,
    "eigenu01": 14,
    "phaseoned": 15,
}


def figure(label: str, panels: str = "") -> str:
    """How the paper's figure ``label`` is cited: ``figure("disp", "(a)")`` → ``"figure 7(a)"``."""
    return f"figure {FIGURES[label]}{panels}"

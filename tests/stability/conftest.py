"""The paper's checkpoints as (θ, ν0(0)) pairs for the stability tests; the steady flows
themselves are the session fixtures ``p1_flow`` and ``flows`` of ``tests/conftest.py``."""

from __future__ import annotations

from chuteflow.papers.mitarai2004.points import POINTS

#: (θ in degrees, ν0(0)) of the checkpoints, φ = 0.05 (§4.2, figures 7–9)
P1, P2, P3, P4, P5 = ((POINTS[n].theta, POINTS[n].nu0) for n in ("P1", "P2", "P3", "P4", "P5"))
#: φ = 0.10 (figure 13)
Q3 = (POINTS["Q3"].theta, POINTS["Q3"].nu0)

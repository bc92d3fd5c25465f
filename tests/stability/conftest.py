"""Shared steady flows of the paper's checkpoints (solved once per session)."""

from __future__ import annotations

import pytest

from chuteflow.closures import ChuteModel
from chuteflow.steady import solve_steady

#: (θ in degrees, ν0(0)) of the checkpoints, φ = 0.05 (§4.2, figures 7–9)
P1, P2, P3, P4, P5 = (16.0, 0.05), (16.0, 0.08), (16.0, 0.10), (14.0, 0.05), (17.0, 0.10)
#: φ = 0.10 (figure 13)
Q3 = (20.0, 0.17)


@pytest.fixture(scope="session")
def p1_flow():
    return solve_steady(*P1)


@pytest.fixture(scope="session")
def flows():
    """Lazily solved checkpoint flows: flows('P3')."""
    cache = {}
    spec = {
        "P1": (P1, 0.05),
        "P2": (P2, 0.05),
        "P3": (P3, 0.05),
        "P4": (P4, 0.05),
        "P5": (P5, 0.05),
        "Q3": (Q3, 0.10),
    }

    def get(name):
        if name not in cache:
            (theta, nu0), phi = spec[name]
            cache[name] = solve_steady(theta, nu0, ChuteModel(roughness=phi))
        return cache[name]

    return get

"""The eigenfunction diagnostics' mass balance, derived from the equations, against the
hand-written form it replaces.

``eigenfunction_diagnostics`` used to restate the linearised mass balance (Appendix A,
first equation) as −ν0 (ik û + v̂') and −ν0' v̂; it now takes those terms from the compiled
equations (:func:`chuteflow.stability.equation_terms`). :func:`hand_written` keeps the old
code as the reference.
"""

from __future__ import annotations

import numpy as np
import pytest

from chuteflow.figures.stability import eigenfunction_diagnostics
from chuteflow.stability import least_stable
from chuteflow.stability.operator import base_on_grid


@pytest.fixture(scope="module")
def modes(flows):
    p1, p5 = flows("P1"), flows("P5")
    return [(p1, least_stable(p1, 2e-3)), (p1, least_stable(p1, 2e-2)), (p5, least_stable(p5, 1e-2))]


def hand_written(mode, flow):
    """(compression, vertical_advection) as computed by hand before (commit f630553)."""
    g = mode.grid  # the mode's collocation grid (sinh-mapped by default since issue 9)
    fields = mode.fields
    j = int(np.argmax(np.abs(fields["nu"])))
    c = np.conj(fields["nu"][j]) / abs(fields["nu"][j]) ** 2
    nu, u, v = (c * np.asarray(fields[f]) for f in ("nu", "u", "v"))
    base = base_on_grid(flow, g.y)
    div = 1j * mode.k * u + g.D @ v
    norm = float(g.integrate(np.abs(nu) ** 2))
    comp = float(g.integrate((np.conj(nu) * (-base["nu"] * div)).real)) / norm
    vert = float(g.integrate((np.conj(nu) * (-base["nu_y"] * v)).real)) / norm
    return comp, vert


def test_mass_balance_terms_equal_hand_written(modes):
    """To round-off of the integrands (measured ≲ 1e-15 relative)."""
    for flow, mode in modes:
        d = eigenfunction_diagnostics(mode, flow)
        comp, vert = hand_written(mode, flow)
        scale = abs(comp) + abs(vert)
        assert abs(d["compression"] - comp) <= 1e-12 * scale
        assert abs(d["vertical_advection"] - vert) <= 1e-12 * scale
        assert d["identity_residual"] < 1e-6

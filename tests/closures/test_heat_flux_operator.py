"""The stability operator with a density-gradient heat flux (κ_h ≠ 0, ``lun_full``) keeps
the identities the 2D and 3D operators are tested for (tests/stability/test_three_d.py):
k_z = 0 reproduces the 2D operator, α is even in k_z, and the k = 0 null vector ∂X0/∂β
(Appendix B) is annihilated. And κ_h enters the equations where q = −κ∇T − κ_h∇ν puts it.
"""

from __future__ import annotations

import numpy as np
import pytest

from chuteflow import ChuteModel, solve_steady
from chuteflow.equations import compiled_equations
from chuteflow.longwave.theory import tangent_vector
from chuteflow.stability import StabilityOperator
from chuteflow.steady import steady_tangent

N = 40


@pytest.fixture(scope="module")
def flow():
    return solve_steady(theta=16.0, nu0=0.05, model=ChuteModel(roughness=0.05, transport="lun_full"))


@pytest.fixture(scope="module")
def ops(flow):
    return StabilityOperator(flow, N), StabilityOperator(flow, N, three_d=True)


def _blocks(op):
    m = N + 1
    return {f: slice(i * m, (i + 1) * m) for i, f in enumerate(op.fields)}


def test_kz0_is_2d_and_even_in_kz(ops):
    op2, op3 = ops
    b = _blocks(op3)
    keep = np.r_[b["nu"], b["u"], b["v"], b["T"]]
    for kx in (0.0, 0.01, 0.7):
        assert np.array_equal(op3.matrix(kx, 0.0)[np.ix_(keep, keep)], op2.matrix(kx))
    s = np.ones(op3.size)
    s[b["w"]] = -1.0
    for kx, kz in ((0.0, 0.3), (0.02, 0.05)):
        assert np.array_equal(op3.matrix(kx, -kz), s[:, None] * op3.matrix(kx, kz) * s[None, :])


def test_null_vector_annihilated(ops, flow):
    """A(0, 0) ∂X0/∂β = 0: relative residual below 1e-9 as with κ_h = 0 (5.8e-11 there)."""
    op2, op3 = ops
    tg = steady_tangent(flow)
    for op, A in ((op2, op2.matrix(0.0)), (op3, op3.matrix(0.0, 0.0))):
        V = tangent_vector(op, tg)
        assert np.abs(A @ V).max() / (np.abs(A).max() * np.abs(V).max()) < 1e-9


def test_energy_equation_carries_kappa_h():
    """−∇·q with q_y = −κ T_y − κ_h ν_y: the energy residual's coefficient of ν_yy is κ_h;
    the floor energy condition −(q_y + …) has κ_h as the coefficient of ν_y; with the lun
    closure (κ_h = 0) both vanish."""
    eqs = compiled_equations()
    names = ("nu", "nu_y", "nu_yy", "u", "u_y", "u_yy", "T", "T_y", "T_yy")
    values = (0.1, -0.02, 0.003, 5.0, 0.2, -0.01, 2.0, -0.05, 0.004)
    base = {b: np.array([v]) for b, v in zip(names, values)}
    for transport in ("lun", "lun_full", "garzo_dufty"):
        part = ChuteModel(transport=transport).evaluate(base["nu"], base["T"])
        kh = float(part["kappa_h"][(0, 0)][0])
        assert (kh == 0.0) == (transport == "lun")
        for name, c in (("energy", 2), ("floor_energy", 1)):
            ce = eqs[name]
            _, coefs = ce.evaluate(base, part, 0.27, 0.96)
            idx = [i for i, t in enumerate(ce.terms) if (t.field, t.a, t.b, t.c, t.d) == ("nu", 0, 0, c, 0)]
            assert len(idx) == 1
            assert float(np.ravel(coefs[idx[0]])[0]) == pytest.approx(kh, rel=1e-14, abs=0.0)

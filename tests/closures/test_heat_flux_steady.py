"""The steady equations with κ_h ≠ 0 as the shooting scan integrates them
(chuteflow.steady.shooting.ode.SteadyODE): its right-hand side and floor values satisfy the
compiled energy balance (eq. (3.6) with −∇·q, q_y = −κT_y − κ_h ν_y) and floor energy
condition (2.10), where ν0'' = d/dy ν0'(ν0, T0, T0') brings T0'' into the κ_h term.
An independent check: the residuals of chuteflow.equations at the state the ODE gives.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from chuteflow import ChuteModel
from chuteflow.equations import compiled_equations
from chuteflow.steady.shooting.ode import SteadyODE

THETA = 16.0


def _nu_y(ode, nu, u, T, Ty):
    return nu * ode.rhs(0.0, [math.log(nu), u, T, Ty])[0]


@pytest.mark.parametrize("transport", ["lun_full", "garzo_dufty"])
def test_ode_rhs_satisfies_the_energy_balance(transport):
    model = ChuteModel(transport=transport)
    ode = SteadyODE(THETA, model)
    nu, u, T, Ty = 0.12, 5.0, 2.0, -0.03
    dlnu, u_y, _, Tyy = ode.rhs(0.0, [math.log(nu), u, T, Ty])
    nu_y = nu * dlnu
    # ν0'' by the chain rule, partials by central differences (relative step 1e-6)
    h = 1e-6
    g_nu = (_nu_y(ode, nu * (1 + h), u, T, Ty) - _nu_y(ode, nu * (1 - h), u, T, Ty)) / (2 * h * nu)
    g_T = (_nu_y(ode, nu, u, T * (1 + h), Ty) - _nu_y(ode, nu, u, T * (1 - h), Ty)) / (2 * h * T)
    g_Ty = (_nu_y(ode, nu, u, T, Ty * (1 + h)) - _nu_y(ode, nu, u, T, Ty * (1 - h))) / (2 * h * Ty)
    nu_yy = g_nu * nu_y + g_T * Ty + g_Ty * Tyy
    base = {
        k: np.array([v])
        for k, v in dict(nu=nu, nu_y=nu_y, nu_yy=nu_yy, u=u, u_y=u_y, u_yy=0.0, T=T, T_y=Ty, T_yy=Tyy).items()
    }
    part = model.evaluate(base["nu"], base["T"])
    th = math.radians(THETA)
    eq = compiled_equations()
    res, coefs = eq["energy"].evaluate(base, part, math.sin(th), math.cos(th))
    # scale: the largest single contribution, κ T0''
    scale = abs(part["kappa"][(0, 0)][0] * Tyy)
    assert abs(float(np.ravel(res)[0])) < 1e-7 * scale
    # and without the ν0'' term (κ_h's T0'' contribution dropped) the balance fails
    base["nu_yy"] = np.array([g_nu * nu_y + g_T * Ty])
    res_wrong, _ = eq["energy"].evaluate(base, part, math.sin(th), math.cos(th))
    assert abs(float(np.ravel(res_wrong)[0])) > 1e-4 * scale
    ymom, _ = eq["ymom"].evaluate(base, part, math.sin(th), math.cos(th))
    assert abs(float(np.ravel(ymom)[0])) < 1e-13


@pytest.mark.parametrize("transport", ["lun_full", "garzo_dufty"])
def test_floor_values_satisfy_the_floor_energy_condition(transport):
    """T0'(0) of SteadyODE.floor_values with ν0'(0) from the y-momentum balance (3.5)."""
    model = ChuteModel(transport=transport)
    ode = SteadyODE(THETA, model)
    nu0, u0 = 0.2, 3.0
    T0, Ty0 = ode.floor_values(nu0, u0)
    nu_y = _nu_y(ode, nu0, u0, T0, Ty0)
    th = math.radians(THETA)
    p = model.evaluate(np.array([nu0]), np.array([T0]))
    u_y = math.tan(th) * p["p"][(0, 0)][0] / p["mu"][(0, 0)][0]
    base = {
        k: np.array([v])
        for k, v in dict(
            nu=nu0, nu_y=nu_y, nu_yy=0.0, u=u0, u_y=u_y, u_yy=0.0, T=T0, T_y=Ty0, T_yy=0.0
        ).items()
    }
    res, _ = compiled_equations()["floor_energy"].evaluate(base, p, math.sin(th), math.cos(th))
    kh_term = abs(p["kappa_h"][(0, 0)][0] * nu_y)
    assert kh_term > 1e-3 * abs(p["kappa"][(0, 0)][0] * Ty0)  # the κ_h term is not negligible here
    assert abs(float(np.ravel(res)[0])) < 1e-12 * max(kh_term, abs(p["kappa"][(0, 0)][0] * Ty0))

"""Independent reference: the paper's shooting method with scipy (solve_ivp + brentq).

Nothing here comes from chuteflow: Table 1 (f1 … f7 with the Lun–Savage g0) is transcribed
again in plain Python, the ν-derivatives are taken by complex step (exact to round-off), and
the steady equations are integrated in the paper's ODE form

    ν0' = −(f1 T0' + ν0 cosθ) / (f1,ν T0)                        (eq:nu0)
    u0' = f1 T0^½ tanθ / f2                                       (eq:u00)
    T0'' = [(1 − e²) f5 T0 − f2 (u0')² − f4,ν ν0' T0' − f4 (T0')²/(2T0)] / f4
                                         (eq:T00, with the ERRATA fix (u0')²)

from the floor values eq:T0b, eq:dT0b, shooting on u0(0) until T0' = 0 where ν0 reaches
``nu_top`` (paper: |T0'(y_max)| < 1e-7). Following the ERRATA, the root is bracketed by the
sign change of T0' coming down from large u0(0), not by the smallness of T0' (which a thin
cold layer with u0(0) → 0 also has). Also used as the benchmark's plain baseline.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

SQPI = math.sqrt(math.pi)


@dataclass(frozen=True)
class Material:
    e: float = 0.7
    nu_m: float = 0.6
    phi: float = 0.05
    Phi: float = 0.39


def _table1(nu, mat: Material):
    """f1, f2, f4, f5, f6, f7 of Table 1 (works for complex ν)."""
    eta = (1 + mat.e) / 2
    g0 = (1 - nu / mat.nu_m) ** (-2.5 * mat.nu_m)
    f1 = nu * (1 + 4 * eta * nu * g0)
    f2 = (
        5
        * SQPI
        / (96 * eta * (2 - eta))
        * (1 + 1.6 * eta * nu * g0)
        * (1 / g0 + 1.6 * eta * (3 * eta - 2) * nu)
        + 8 / (5 * SQPI) * eta * nu**2 * g0
    )
    f4 = (
        25
        * SQPI
        / (16 * eta * (41 - 33 * eta))
        * (1 + 2.4 * eta * nu * g0)
        * (1 / g0 + 2.4 * eta**2 * (4 * eta - 3) * nu)
        + 4 / SQPI * eta * nu**2 * g0
    )
    f5 = 12 / SQPI * nu**2 * g0
    f6 = math.sqrt(3) * math.pi * nu * g0 / (2 * mat.nu_m * f4)
    f7 = math.pi * nu * g0 / (2 * math.sqrt(3) * mat.nu_m * f2)
    return f1, f2, f4, f5, f6, f7


def _with_derivatives(nu, mat):
    """Table 1 at real ν and d/dν of f1, f4 by complex step."""
    h = 1e-20 * max(nu, 1e-300)
    c = _table1(complex(nu, h), mat)
    vals = [v.real for v in c]
    return vals, c[0].imag / h, c[2].imag / h


def _rhs(theta_deg, mat):
    th = math.radians(theta_deg)
    c, tn, loss = math.cos(th), math.tan(th), 1 - mat.e**2

    def rhs(y, z):
        s, u, T, Tp, rho, q = z
        T = max(T, 1e-300)
        nu = math.exp(s)
        (f1, f2, f4, f5, _, _), f1p, f4p = _with_derivatives(nu, mat)
        nup = -(f1 * Tp + nu * c) / (f1p * T)
        up = f1 * math.sqrt(T) * tn / f2
        Tpp = (loss * f5 * T - f2 * up * up - f4p * nup * Tp - f4 * Tp * Tp / (2 * T)) / f4
        return [nup / nu, up, Tp, Tpp, nu, nu * u]

    return rhs


def floor_values(theta_deg, nu0, u0, mat):
    """T0(0) from eq:T0b and T0'(0) from eq:dT0b."""
    tn = math.tan(math.radians(theta_deg))
    f1, f2, _, _, f6, f7 = _table1(nu0, mat)
    T0 = (mat.phi * f2 * f7 * u0 / (f1 * tn)) ** 2
    return T0, -f6 * (mat.phi * u0**2 / 3 - 0.5 * mat.Phi * T0)


def shoot(theta_deg, nu0, u0, mat, nu_top=1e-9, rtol=1e-11, dense=False, y_cap=1e5):
    """Integrate from the floor until ν0 = nu_top (or T0 → 0, or y_cap)."""
    T0, Tp0 = floor_values(theta_deg, nu0, u0, mat)
    top = lambda y, z: z[0] - math.log(nu_top)  # noqa: E731
    top.terminal = True
    cold = lambda y, z: z[2] - 1e-10 * T0  # noqa: E731
    cold.terminal = True
    return solve_ivp(
        _rhs(theta_deg, mat),
        (0.0, y_cap),
        [math.log(nu0), u0, T0, Tp0, 0.0, 0.0],
        method="DOP853",
        rtol=rtol,
        atol=1e-14,
        events=[top, cold],
        dense_output=dense,
    )


def _miss(theta_deg, nu0, u0, mat, nu_top, rtol):
    """Signed miss of the top condition: T0' where ν0 reaches nu_top; + if the layer never
    thins out (T0 grows), − if it cools to zero."""
    sol = shoot(theta_deg, nu0, u0, mat, nu_top, rtol)
    if len(sol.t_events[0]):
        return float(sol.y_events[0][0][3])
    return -1.0 if len(sol.t_events[1]) else 1.0


@dataclass(frozen=True)
class ShotFlow:
    u_floor: float
    T_floor: float
    y_max: float
    rho_bar: float
    Q: float
    h: float
    shots: int


def solve_by_shooting(
    theta_deg, nu0, mat=Material(), *, nu_top=1e-9, rtol=1e-11, u_hi=200.0, n_scan=40, xtol=1e-13
):
    """The physical steady flow by shooting on u0(0); ρ̄0 and Q0 include the tail above
    y_max as in chuteflow's definition (∫ν dy above = p(y_max)/cosθ, u0 constant there)."""
    us = np.geomspace(u_hi, 1e-2, n_scan)
    shots = 0
    prev = None
    for u in us:
        m = _miss(theta_deg, nu0, u, mat, nu_top, 1e-8)
        shots += 1
        if prev is not None and prev[1] > 0 >= m:
            lo, hi = u, prev[0]
            break
        prev = (u, m)
    else:
        raise RuntimeError(f"no sign change of T0' for u0(0) in [1e-2, {u_hi}]")
    count = [0]

    def f(u):
        count[0] += 1
        return _miss(theta_deg, nu0, u, mat, nu_top, rtol)

    u0 = brentq(f, lo, hi, xtol=xtol, rtol=4 * np.finfo(float).eps)
    sol = shoot(theta_deg, nu0, u0, mat, nu_top, rtol, dense=True)
    s, u, T = sol.y[0], sol.y[1], sol.y[2]
    L = float(sol.t[-1])
    f1_top = _table1(math.exp(s[-1]), mat)[0]
    c = math.cos(math.radians(theta_deg))
    tail = f1_top * T[-1] / c
    rho = float(sol.y[4, -1]) + tail
    Q = float(sol.y[5, -1]) + u[-1] * tail
    # h: ν0 = 1 % of its maximum above the maximum (monotonic here: the floor)
    i = int(np.argmax(s))
    target = s[i] + math.log(0.01)
    yy = np.linspace(sol.t[i], L, 20001)
    ss = sol.sol(yy)[0]
    j = int(np.nonzero(ss <= target)[0][0])
    h = brentq(lambda y: sol.sol(y)[0] - target, yy[j - 1], yy[j], xtol=1e-13)
    return ShotFlow(u0, float(T[0]), L, rho, Q, h, shots + count[0])

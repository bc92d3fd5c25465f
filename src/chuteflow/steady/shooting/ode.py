"""The steady equations of §3 as a first-order system in y for the shooting scan."""

from __future__ import annotations

import math

import numpy as np

from ...closures import ChuteModel
from ...closures.model import FUNCTIONS, ORDERS, SCALAR_ORDERS
from ...equations import BASE, compiled_equations
from .._scalar_ode import compiled_kernel, scalar_rhs
from .dopri_compiled import _Kernel


def _term_index(eq, field_name: str, c: int) -> int:
    """Position of the coefficient of d^c(field)/dy^c among a compiled equation's terms."""
    for i, t in enumerate(eq.terms):
        if (t.field, t.a, t.b, t.c, t.d) == (field_name, 0, 0, c, 0):
            return i
    raise KeyError(f"{eq.name} has no term d^{c} {field_name}/dy^{c}")


class SteadyODE:
    """The steady equations of §3 as a first-order system in y for (ln ν0, u0, T0, T0').

    Parameters
    ----------
    theta : float
        Inclination θ in degrees.
    model : ChuteModel
        Closure parameters.
    """

    def __init__(self, theta: float, model: ChuteModel):
        th = math.radians(theta)
        self.sin, self.cos = math.sin(th), math.cos(th)
        self.tan = self.sin / self.cos
        self.model = model
        # the right-hand side, called ~10⁴ times per point with scalars: one generated
        # function of Python floats (steady/_scalar_ode.py, derived from the same residuals)
        self._rhs = scalar_rhs(*model.closures)
        self._params = model._params
        self._trailing = (*model._params, self.sin, self.cos)  # the generated rhs's last arguments
        # the same right-hand side compiled with the Dormand–Prince loop around it (None
        # where no C compiler is available: scipy's dopri5 calls rhs_bounded instead)
        lib = compiled_kernel(*model.closures)
        self.kernel = _Kernel(lib, self._trailing) if lib is not None else None
        # the floor values (a few calls per trial): the compiled floor conditions with the
        # flat argument list that equations.arguments would build, the closures' partials
        # from the model's scalar evaluator (first order: all the floor conditions use).
        # The slots of the second-order partials hold NaN: they enter only coefficients
        # that are not used here, and any use would show as NaN
        # (tests/steady/test_existence.py compares with an independent transcription).
        eqs = compiled_equations()
        self._floor_x, self._floor_energy = eqs["floor_x"], eqs["floor_energy"]
        self._i_floor_u = _term_index(self._floor_x, "u", 0)
        self._i_floor_T_y = _term_index(self._floor_energy, "T", 1)
        # the coefficient of ν0' in the floor energy condition: κ_h of q = −κ∇T − κ_h∇ν
        # (zero for the paper's closure, where the result below is that of −R(0)/R_T')
        self._i_floor_nu_y = _term_index(self._floor_energy, "nu", 1)
        self._fast = model.scalar_evaluator(SCALAR_ORDERS)
        nb, no = len(BASE), len(ORDERS)
        self._pos = tuple(nb + k * no + ORDERS.index(o) for k in range(len(FUNCTIONS)) for o in SCALAR_ORDERS)
        self._template = [0.0] * nb + [math.nan] * (len(FUNCTIONS) * no) + [self.sin, self.cos]
        slot = {b: i for i, b in enumerate(BASE)}
        self._i_p = FUNCTIONS.index("p") * len(SCALAR_ORDERS)
        self._i_mu = FUNCTIONS.index("mu") * len(SCALAR_ORDERS)
        self._s_nu, self._s_u, self._s_T = slot["nu"], slot["u"], slot["T"]
        self._s_u_y, self._s_T_y = slot["u_y"], slot["T_y"]

    def _arguments(self, nu: float, u: float, T: float, T_y: float) -> list:
        """The compiled equations' argument list at a point of a trajectory (ν0' = T0'' = 0
        and the other second derivatives 0; u0' from eq. (3.7)), floats."""
        flat = self._fast(nu, T)
        args = self._template.copy()
        for i, v in zip(self._pos, flat):
            args[i] = v
        args[self._s_nu], args[self._s_u], args[self._s_T], args[self._s_T_y] = nu, u, T, T_y
        args[self._s_u_y] = self.tan * flat[self._i_p] / flat[self._i_mu]  # eq. (3.7)
        return args

    def rhs(self, y, z):
        """d/dy of (ln ν0, u0, T0, T0'). Outside the closures' domain (trial stages of the
        integrator) the result is NaN, which makes the integrator shorten its step."""
        s, u, T, T_y = z.tolist() if isinstance(z, np.ndarray) else map(float, z)
        try:
            nu_y, u_y, T_yy = self._rhs(math.exp(s), u, T, T_y, *self._params, self.sin, self.cos)
            return [float(nu_y), float(u_y), T_y, float(T_yy)]
        except (ArithmeticError, ValueError, TypeError):
            # math-module domain errors; complex numbers (ν0 > ν_m) fail in float()
            return [math.nan] * 4

    def rhs_bounded(self, y, z):
        """:meth:`rhs` with every non-finite value replaced by ±1e300, for the compiled
        Dormand–Prince loop of :func:`~chuteflow.steady.shooting.dopri_scipy.integrate` (a huge
        derivative makes its error estimate reject the trial step and shorten it, as NaN does in
        scipy's Python loop). Called ~10⁵ times per scan with the integrator's array: one call
        level, no checks beyond the finiteness of the result."""
        s, u, T, T_y = z.tolist()
        try:
            nu_y, u_y, T_yy = self._rhs(math.exp(s), u, T, T_y, *self._trailing)
            out = [float(nu_y), float(u_y), T_y, float(T_yy)]
        except (ArithmeticError, ValueError, TypeError):
            return [1e300] * 4
        if math.isfinite(out[0] + out[1] + out[2] + out[3]):
            return out
        return [v if math.isfinite(v) else 1e300 if math.isnan(v) else math.copysign(1e300, v) for v in out]

    def floor_velocity(self, nu0: float, T0: float) -> float:
        """u0(0) from eq. (2.9) (floor_x is linear in u0) given ν0(0) and T0(0)."""
        try:
            out = self._floor_x._fun(*self._arguments(nu0, 0.0, T0, 0.0))
            return -float(out[0]) / float(out[1 + self._i_floor_u])
        except (ArithmeticError, ValueError, TypeError):
            return math.nan

    def floor_values(self, nu0: float, u0: float) -> tuple[float, float]:
        """T0(0) and T0'(0) from the floor conditions eqs (2.9), (2.10) (eqs 3.11, 3.12).

        T0(0) solves u0(0) = floor_velocity(ν0, T0) by Newton in ln T0 (one step for the
        kinetic closures, where u0(0) ∝ √T0); T0'(0) then follows from the floor energy
        condition, affine in T0'.
        """
        x, lnu = 0.0, math.log(u0)
        for _ in range(60):
            h = 1e-6
            g = math.log(self.floor_velocity(nu0, math.exp(x))) - lnu
            dg = (math.log(self.floor_velocity(nu0, math.exp(x + h))) - lnu - g) / h
            dx = -g / dg if dg != 0 else 0.0
            dx = max(-5.0, min(5.0, dx))
            x += dx
            if abs(dx) < 1e-12:
                break
        T0 = math.exp(x)
        try:
            args = self._arguments(nu0, u0, T0, 0.0)
            out = self._floor_energy._fun(*args)
            # q_y has −κ_h ν0'(0), and ν0'(0) = a + b T0'(0) by eq. (3.5)
            c_nu = float(out[1 + self._i_floor_nu_y])
            if c_nu == 0.0:
                return T0, -float(out[0]) / float(out[1 + self._i_floor_T_y])
            flat = self._fast(nu0, T0)
            p_nu, p_T = flat[self._i_p + 1], flat[self._i_p + 2]
            a, b = -nu0 * self.cos / p_nu, -p_T / p_nu
            return T0, -(float(out[0]) + c_nu * a) / (float(out[1 + self._i_floor_T_y]) + c_nu * b)
        except (ArithmeticError, ValueError, TypeError):
            return T0, math.nan

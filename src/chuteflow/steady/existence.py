"""Existence of the steady flow, decided by shooting on the floor velocity u0(0) (paper §3).

The paper finds the steady flow by shooting: given ν0(0) and a trial slip velocity u0(0),
the floor conditions (eqs 3.11, 3.12) fix T0(0) and T0'(0), the steady equations are
integrated upwards, and u0(0) is adjusted until T0' = 0 where ν0 reaches ``nu_top``
(eq. 3.13). Here that integration is used as a cheap, loose-tolerance *scan* that decides
whether a flow exists and, if so, gives the Chebyshev–Newton solver of
:mod:`chuteflow.steady.solver` a starting profile.

Each trial is classified by the direction in which it misses the top condition:

* **hot** (+): ν0 reaches ``nu_top`` with T0' > 0, or the layer never thins out (T0 grows,
  ν0 does not reach ``nu_top`` below ``y_cap``);
* **cold** (−): ν0 reaches ``nu_top`` with T0' ≤ 0, or T0 → 0, or ν0 → ν_m (the layer
  collapses or packs).

Large u0(0) heats the layer, small u0(0) lets it cool, so the physical flow is the first
sign change hot → cold coming down from large u0(0) (docs/errata.md, numerical note on shooting:
the smallness of |T0'(y_max)| alone is also met by a thin cold layer as u0(0) → 0, whose
trajectories are not followed). No such sign change over the admissible range of u0(0) is a
verdict: every trial hot (the layer cannot be kept cold enough to thin out: at small θ the
thin cold layer has T0'(y_max) > 0), the angle is too small; every trial cold (the layer
collapses or packs at any floor velocity), the angle is too large. A hot → cold change
across which no trial reaches ``nu_top`` is a separatrix (a jump of the miss, not a root:
e.g. a band that packs to ν_m and then either collapses or heats up), not a solution.
A solution thinner than one diameter (§3.2) is reported as such.

The steady ODEs are not typed again here: ν0' follows from the y-momentum residual and T0''
from the energy residual of the derived equations (:mod:`chuteflow.equations`; both are
affine in that highest derivative, so the residual with it set to zero and its coefficient
give it exactly), u0' = tanθ p/μ is the integrated x-momentum balance eq. (3.7) as used by
the Newton solver — derived symbolically once and generated as scalar code
(:mod:`chuteflow.steady._scalar_ode`) — and the floor values come from the floor_x and
floor_energy residuals (eqs 2.9, 2.10) of :func:`chuteflow.equations.compiled_equations`, with
the closures' partials of :meth:`ChuteModel.scalar_evaluator`.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..closures import ChuteModel
from ..closures.model import FUNCTIONS, ORDERS, SCALAR_ORDERS
from ..equations import BASE, compiled_equations
from ..spectral import ChebyshevGrid
from ._roots import brent_root
from ._scalar_ode import FULL, NEQ, STOPPED, compiled_kernel, scalar_rhs
from .solver import NewtonState, validate_point

#: Default admissible range of the floor slip velocity u0(0) (units of √(gσ)). At the
#: paper's parameters the physical flows have u0(0) between ≈ 0.5 and ≈ 150.
U_RANGE = (1e-2, 1e3)

#: A trial whose temperature falls below this fraction of T0(0) is cold (collapsing). Near
#: the upper existence boundary the physical flow has a packed band (ν0 ≈ 0.59) whose
#: temperature is 1e-4–1e-6 of the floor's below a dilute hot top (φ = 0.10, θ = 22.34°,
#: ν0(0) = 0.1039: tests/steady/test_existence_map.py), so the threshold is as low as the
#: independent reference's (tests/steady/shooting.py).
_COLD = 1e-10


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
        Dormand–Prince loop of :func:`integrate` (a huge derivative makes its error estimate
        reject the trial step and shorten it, as NaN does in scipy's Python loop). Called
        ~10⁵ times per scan with the integrator's array: one call level, no checks beyond
        the finiteness of the result."""
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


class Trajectory:
    """One trial integration: the accepted steps (heights ``t``, states ``y`` of shape
    4 × steps, the last one at the event that stopped it) and, if dense, ``sol``: the
    piecewise cubic Hermite interpolant through them (states and derivatives at the step
    ends, third order like the integrator's own dense output), called as ``sol(y)`` with
    values of shape 4 × len(y) (None otherwise).

    Attributes
    ----------
    t : ndarray
        Heights of the accepted steps.
    y : ndarray
        States (ln ν0, u0, T0, T0') there, shape (4, len(t)).
    event : str or None
        The event that stopped the integration ("top", "cold", "packed", "hot"); None if it
        reached ``y_cap`` (``status`` 0) or the integrator gave up (``status`` −1).
    status : int
        0: ended at an event or at ``y_cap``; −1: the step size fell below round-off (a
        finite-height singularity).
    sol : callable or None
        The dense interpolant.
    """

    def __init__(self, t, y, event, status, sol):
        self.t, self.y, self.event, self.status, self.sol = t, y, event, status, sol


def _hermite(t0, t1, y0, y1, f0, f1, t):
    """Cubic Hermite interpolant of one step at t ∈ [t0, t1]."""
    h = t1 - t0
    s = (t - t0) / h
    h00, h10 = (1 + 2 * s) * (1 - s) ** 2, s * (1 - s) ** 2
    h01, h11 = s * s * (3 - 2 * s), s * s * (s - 1)
    return h00 * y0 + h10 * h * f0 + h01 * y1 + h11 * h * f1


def _crossing(a, b, direction) -> bool:
    """Whether an event function changes sign from a to b in ``direction`` (−1: from
    positive to non-positive; +1: from negative to non-negative; 0: either)."""
    if direction < 0:
        return a > 0 >= b
    if direction > 0:
        return a < 0 <= b
    return (a > 0 >= b) or (a < 0 <= b)


def integrate(fun, z0, y_cap: float, rtol: float, events, *, dense: bool = False) -> Trajectory:
    """Integrate dz/dy = fun(y, z) from y = 0 with scipy's Dormand–Prince 5(4) (``dopri5``
    of :class:`scipy.integrate.ode`, Hairer's Fortran code: the same method, error norm and
    step control as ``solve_ivp(method="RK45")``, with the stepping loop compiled) until
    one of ``events`` changes sign across an accepted step or y = ``y_cap``.

    ``events`` is a sequence of (name, g, direction) with g(z) a scalar function of the
    state; direction −1 stops only where g goes from positive to non-positive, +1 from
    negative to non-negative, 0 either way (as ``solve_ivp``'s terminal events, which also
    look at the step ends only). The crossing is located on the step's cubic Hermite
    interpolant (by bisection to round-off); the earliest triggered event wins.
    """
    import warnings

    # scipy.integrate costs ~0.3 s to import: only the existence scan needs it
    from scipy.integrate import ode

    ts: list[float] = []
    zs: list[np.ndarray] = []
    hit: list = []
    stop: list = []  # the step where an event triggered: t_old, z_old, crossing estimate, t

    g_prev: list = []  # the events' values at the last accepted step

    def solout(t, z):
        z = np.array(z, dtype=float)
        g_now = [g(z) for _, g, _ in events]
        if ts:
            t_old, z_old = ts[-1], zs[-1]
            found = [(name, g) for (name, g, d), a, b in zip(events, g_prev, g_now) if _crossing(a, b, d)]
            if found:
                f0 = np.asarray(fun(t_old, z_old), dtype=float)
                f1 = np.asarray(fun(t, z), dtype=float)
                best = None
                for name, g in found:
                    lo, hi = t_old, t
                    glo = g(z_old)
                    for _ in range(100):
                        mid = 0.5 * (lo + hi)
                        if mid <= lo or mid >= hi:
                            break
                        gm = g(_hermite(t_old, t, z_old, z, f0, f1, mid))
                        if (gm > 0) == (glo > 0) and gm != 0:
                            lo, glo = mid, gm
                        else:
                            hi = mid
                    if best is None or hi < best[1]:
                        best = (name, hi)
                assert best is not None  # found is not empty
                hit.append(best[0])
                stop.extend([t_old, z_old, best[1], float(t)])
                return -1
        ts.append(float(t))
        zs.append(z)
        g_prev[:] = g_now
        return 0

    r = ode(fun).set_integrator("dopri5", rtol=rtol, atol=1e-12, nsteps=10**6)
    r.set_solout(solout)
    r.set_initial_value(np.asarray(z0, dtype=float), 0.0)
    with warnings.catch_warnings():
        # "step size becomes too small": reported through status −1
        warnings.simplefilter("ignore", UserWarning)
        r.integrate(y_cap)
    if hit:
        # the crossing on the step's interpolant is accurate to O(h⁴); two secant steps on
        # g(z(t)), each integrating afresh from the start of that step to the estimate (the
        # integrator ends exactly there), bring it to the integration's own tolerance, as
        # solve_ivp's events on its dense output
        t_old, z_old, t_ev, t_step = stop
        g = next(gg for name, gg, _ in events if name == hit[0])

        def state_at(t_end):
            if t_end <= t_old:
                return z_old
            rr = ode(fun).set_integrator("dopri5", rtol=rtol, atol=1e-12, nsteps=10**4)
            rr.set_initial_value(z_old, t_old)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", UserWarning)
                return np.array(rr.integrate(t_end), dtype=float)

        t_ev, z_ev = _secant_event(
            g, lambda t, z: np.asarray(fun(t, z), dtype=float), state_at, t_old, t_ev, t_step
        )
        ts.append(t_ev)
        zs.append(z_ev)
    status = 0 if (hit or r.successful()) else -1
    t = np.array(ts)
    y = np.array(zs).T
    sol = None
    if dense and len(t) > 1:
        sol = _hermite_output(t, y.T, np.array([fun(ti, zi) for ti, zi in zip(t, y.T)], dtype=float))
    return Trajectory(t, y, hit[0] if hit else None, status, sol)


def _secant_event(g, rhs, state_at, t_old, t_ev, t_step):
    """The event g(z(t)) = 0 in the step (t_old, t_step] from its estimate ``t_ev`` on the
    step's interpolant: two secant steps (``rhs(t, z)`` = dz/dt), each integrating afresh
    from the step's start (``state_at``), brought to the integration's own tolerance.
    Returns (t, z(t))."""
    z_ev = state_at(t_ev)
    for _ in range(2):
        f_ev = rhs(t_ev, z_ev)
        eps = 1e-7 * max(1.0, float(np.abs(z_ev).max())) / max(float(np.abs(f_ev).max()), 1e-300)
        slope = (g(z_ev + eps * f_ev) - g(z_ev)) / eps
        if not (math.isfinite(slope) and slope != 0):
            break
        t_new = t_ev - g(z_ev) / slope
        if not (t_old < t_new < 2 * t_step - t_old) or t_new == t_ev:
            break
        t_ev, z_ev = t_new, state_at(t_new)
    return t_ev, z_ev


def _hermite_output(t, zs, fs):
    """Dense output through the accepted steps: the piecewise cubic Hermite interpolant of
    states ``zs`` and derivatives ``fs`` (both steps × 4), called as ``sol(y)`` → 4 × len(y).

    The spline is built at the first call: of the ~20 trials of a scan's bisection, each
    with its dense output, only the one closest to the root is evaluated (building scipy's
    spline for every trial cost a quarter of a scan)."""
    spline = None

    def sol(yy):
        nonlocal spline
        if spline is None:
            from scipy.interpolate import CubicHermiteSpline

            spline = CubicHermiteSpline(t, zs, fs, axis=0, extrapolate=True)
        return np.asarray(spline(yy)).T

    return sol


def _level(k: int, c: float):
    """The event function z ↦ z[k] − c."""
    return lambda z: z[k] - c


class _Kernel:
    """The compiled shooting integrator (:func:`~chuteflow.steady._scalar_ode.compiled_kernel`)
    for one θ and model: :meth:`integrate` does what :func:`integrate` does with scipy's
    dopri5 and :meth:`SteadyODE.rhs_bounded`, the stepping loop and the right-hand side in C
    (one call per trajectory instead of ~10³ Python calls)."""

    def __init__(self, lib, params):
        import ctypes

        self.lib = lib
        self._dp = ctypes.POINTER(ctypes.c_double)
        self._par = np.array(params, dtype=float)
        self._z = np.empty(NEQ)
        self._f = np.empty(NEQ)
        self._out = np.empty(1 + 2 * NEQ)
        self._nrec = ctypes.c_long(0)
        self._hit = ctypes.c_int(0)
        self._p_par, self._p_z, self._p_f, self._p_out = map(
            self._ptr, (self._par, self._z, self._f, self._out)
        )
        self._p_nrec, self._p_hit = ctypes.byref(self._nrec), ctypes.byref(self._hit)
        self._grow(4096)

    def _grow(self, cap: int) -> None:
        self._cap = cap
        self._ts = np.empty(cap)
        self._zs = np.empty(cap * NEQ)
        self._fs = np.empty(cap * NEQ)
        self._p_ts, self._p_zs, self._p_fs = map(self._ptr, (self._ts, self._zs, self._fs))

    def _ptr(self, a: np.ndarray):
        return a.ctypes.data_as(self._dp)

    def rhs(self, z) -> np.ndarray:
        """d/dy of z (a copy), bounded as :meth:`SteadyODE.rhs_bounded`."""
        self._z[:] = z
        self.lib.cf_rhs(self._p_par, self._p_z, self._p_f)
        return self._f.copy()

    def _run(self, t0, z0, t_end, rtol, nmax, levels, record):
        import ctypes

        ne = len(levels)
        ek = (ctypes.c_int * max(ne, 1))(*[k for _, k, _, _ in levels])
        ec = (ctypes.c_double * max(ne, 1))(*[c for _, _, c, _ in levels])
        ed = (ctypes.c_int * max(ne, 1))(*[d for _, _, _, d in levels])
        self._z[:] = z0
        while True:
            status = self.lib.cf_integrate(
                self._p_par,
                float(t0),
                self._p_z,
                float(t_end),
                float(rtol),
                1e-12,
                int(nmax),
                ne,
                ek,
                ec,
                ed,
                self._cap if record else 0,
                self._p_ts,
                self._p_zs,
                self._p_fs,
                self._p_nrec,
                self._p_hit,
                self._p_out,
            )
            if status != FULL:
                return status
            self._grow(4 * self._cap)  # deterministic: the same run with room for it

    def state_at(self, t0, z0, t_end, rtol) -> np.ndarray:
        """The state at ``t_end`` integrated from (t0, z0) (no events; scipy's dopri5 with
        ``nsteps = 10**4`` in :func:`integrate`)."""
        self._run(t0, z0, t_end, rtol, 10**4, (), record=False)
        return self._out[1 : 1 + NEQ].copy()

    def integrate(self, z0, y_cap: float, rtol: float, levels, *, dense: bool = False) -> Trajectory:
        """:func:`integrate` of the steady ODE from y = 0 with the events z[k] − c of
        ``levels`` ((name, k, c, direction), in order of priority for simultaneous
        crossings at the same height as in :func:`integrate`)."""
        status = self._run(0.0, z0, y_cap, rtol, 10**6, levels, record=True)
        n = self._nrec.value
        t = self._ts[:n].copy()
        zs = self._zs[: n * NEQ].reshape(n, NEQ).copy()
        fs = self._fs[: n * NEQ].reshape(n, NEQ).copy()
        hit = None
        if status == STOPPED:
            # the crossing on the step's cubic Hermite interpolant (bisection to round-off),
            # then two secant steps each integrating afresh from the step's start, exactly
            # as integrate() does
            t_old, z_old, f0 = float(t[-1]), zs[-1], fs[-1]
            t_new = float(self._out[0])
            z_new, f1 = self._out[1 : 1 + NEQ].copy(), self._out[1 + NEQ :].copy()
            mask = self._hit.value
            best = None
            for j, (name, k, c, _) in enumerate(levels):
                if not mask & (1 << j):
                    continue
                lo, hi = t_old, t_new
                glo = float(z_old[k]) - c
                y0, y1, d0, d1 = float(z_old[k]), float(z_new[k]), float(f0[k]), float(f1[k])
                for _ in range(100):
                    mid = 0.5 * (lo + hi)
                    if mid <= lo or mid >= hi:
                        break
                    gm = _hermite(t_old, t_new, y0, y1, d0, d1, mid) - c
                    if (gm > 0) == (glo > 0) and gm != 0:
                        lo, glo = mid, gm
                    else:
                        hi = mid
                if best is None or hi < best[1]:
                    best = (name, hi, k, c)
            assert best is not None  # the mask names at least one event
            hit, t_ev, k, c = best

            def state_at(t_end):
                return self.state_at(t_old, z_old, t_end, rtol) if t_end > t_old else z_old

            t_ev, z_ev = _secant_event(_level(k, c), lambda _t, z: self.rhs(z), state_at, t_old, t_ev, t_new)
            t = np.append(t, t_ev)
            zs = np.vstack([zs, z_ev])
            fs = np.vstack([fs, self.rhs(z_ev)])
        traj_status = 0 if (hit is not None or status > 0) else -1
        y = zs.T
        sol = _hermite_output(t, zs, fs) if dense and len(t) > 1 else None
        return Trajectory(t, y, hit, traj_status, sol)


@dataclass(frozen=True)
class Shot:
    """One trial integration from the floor."""

    u_floor: float
    sign: int  # +1 hot, −1 cold
    kind: str  # "top" (reached nu_top), "hot" (never thinned out), "cold", "packed"
    dT_top: float  # T0' where ν0 = nu_top (nan if not reached)
    y_end: float
    solution: Any = field(default=None, repr=False)

    @property
    def miss(self) -> float:
        """Signed miss of the top condition (T0'(y_max) if reached, else ±1)."""
        return self.dT_top if self.kind == "top" else float(self.sign)


def shoot(
    ode: SteadyODE,
    nu0: float,
    u_floor: float,
    *,
    nu_top: float = 1e-9,
    rtol: float = 1e-6,
    y_cap: float = 1e5,
    dense: bool = False,
) -> Shot:
    """Integrate the steady equations upwards from the floor at trial ``u_floor``.

    Stops where ν0 = ``nu_top`` (the top), where T0 falls below 1e-10 T0(0) (cold collapse),
    where ν0 reaches 0.999 ν_m (packing), where T0 exceeds 100 T0(0) or at ``y_cap`` (the
    layer heats up and never thins: hot). The physical flows are hottest at the floor or
    close to it (T0 ≤ T0(0) at the paper's points), so these thresholds only cut short
    trials that have already chosen their direction.
    """
    T0, T0p = ode.floor_values(nu0, u_floor)
    ln_top = math.log(nu_top)
    ln_pack = math.log(0.999 * ode.model.nu_max)

    z0 = [math.log(nu0), u_floor, T0, T0p]
    # (name, component k, constant c, direction): the event z[k] − c
    levels = (
        ("top", 0, ln_top, -1),
        ("cold", 2, _COLD * T0, 0),
        ("packed", 0, ln_pack, 0),
        ("hot", 2, 100.0 * T0, 0),
    )
    if not all(map(math.isfinite, z0)):
        # the floor conditions have no solution at this trial (outside the closures'
        # domain): nothing to integrate, and no sign of cooling, so hot (as a trajectory
        # whose integrator gives up at once with T0' not negative, below)
        start = Trajectory(np.zeros(1), np.array(z0, dtype=float)[:, None], None, -1, None)
        return Shot(u_floor, 1, "hot", math.nan, 0.0, start)
    if ode.kernel is not None:
        sol = ode.kernel.integrate(z0, y_cap, rtol, levels, dense=dense)
    else:
        events = tuple((name, _level(k, c), d) for name, k, c, d in levels)
        with np.errstate(all="ignore"):
            sol = integrate(ode.rhs_bounded, z0, y_cap, rtol, events, dense=dense)
    y_end = float(sol.t[-1])
    if sol.event == "top":
        d = float(sol.y[3, -1])
        return Shot(u_floor, 1 if d > 0 else -1, "top", d, y_end, sol)
    if sol.event in ("cold", "packed"):
        return Shot(u_floor, -1, sol.event, math.nan, y_end, sol)
    if sol.event == "hot" or sol.status == 0:
        return Shot(u_floor, 1, "hot", math.nan, y_end, sol)
    # the integrator gave up: a finite-height singularity. Cooling with T0' → −∞ is the
    # collapse of a cold layer; otherwise the temperature blows up (hot).
    last_T_y = float(sol.y[3, -1])
    if last_T_y < 0:
        return Shot(u_floor, -1, "cold", math.nan, y_end, sol)
    return Shot(u_floor, 1, "hot", math.nan, y_end, sol)


@dataclass(frozen=True)
class ExistenceVerdict:
    """Outcome of :func:`steady_existence`.

    Attributes
    ----------
    exists : bool
        Whether the steady equations have a solution (a hot → cold sign change in u0(0)).
    physical : bool
        ``exists`` and the layer is at least ``min_thickness`` thick.
    kind : str
        ``"flow"``, ``"thin"`` (a solution thinner than ``min_thickness``),
        ``"too_small"`` (every trial hot), ``"too_large"`` (every trial cold) or
        ``"no_sign_change"`` (neither: no hot → cold change from above).
    reason : str
        One sentence for the user, naming the parameters.
    u_floor : float
        u0(0) of the solution (nan when none).
    bracket : tuple
        (cold, hot) trial values of u0(0) enclosing it.
    h, y_max : float
        Thickness (ν0 at 1 % of its maximum) and top of the shot solution.
    shots : int
        Number of trial integrations.
    seconds : float
        Wall time of the scan.
    """

    exists: bool
    physical: bool
    kind: str
    reason: str
    u_floor: float = math.nan
    bracket: tuple = (math.nan, math.nan)
    h: float = math.nan
    y_max: float = math.nan
    shots: int = 0
    seconds: float = 0.0
    solution: Any = field(default=None, repr=False, compare=False)

    def starting_state(self, n: int = 64) -> NewtonState:
        """The shot profile on n + 1 Chebyshev nodes of [0, y_max], as a Newton start."""
        if self.solution is None:
            raise ValueError("no shot profile: " + self.reason)
        grid = ChebyshevGrid(n, 0.0, self.y_max)
        z = self.solution.sol(grid.y)
        return NewtonState(n, z[0].copy(), z[1].copy(), z[2].copy(), self.y_max)


class _Separatrix(Exception):
    """The bracket shrinks without any trial reaching the top."""


def _where(theta, nu0, model):
    return (
        f"theta = {theta:g} deg, nu0 = {nu0:g}, roughness = {model.roughness:g}, "
        f"wall_loss = {model.wall_loss:g}"
    )


def _thickness(sol, y_max) -> float:
    """Height where ν0 falls to 1 % of its maximum above the maximum (as SteadyFlow.h)."""
    y = np.linspace(0.0, y_max, 4001)
    s = sol.sol(y)[0]
    i = int(np.argmax(s))
    target = s[i] + math.log(0.01)
    below = np.nonzero(s[i:] <= target)[0]
    if not len(below):
        return y_max
    j = i + int(below[0])
    return float(brent_root(lambda t: sol.sol(t)[0] - target, y[j - 1], y[j], xtol=1e-10))


def steady_existence(
    theta: float,
    nu0: float,
    model: ChuteModel | None = None,
    *,
    nu_top: float = 1e-9,
    u_range: tuple[float, float] = U_RANGE,
    ratio: float = 2.0,
    rtol: float = 1e-4,
    fine_rtol: float = 1e-6,
    min_thickness: float = 1.0,
) -> ExistenceVerdict:
    """Decide whether a steady flow exists at (``theta``, ``nu0``) by a shooting scan.

    Trials u0(0) = u_max, u_max/ratio, … (down to u_min) are integrated from the floor at
    loose tolerance and classified hot/cold (module docstring). Each hot → cold change,
    coming down from u_max, is refined by Brent's method on the signed miss T0'(y_max) (±1
    for trials that do not reach ``nu_top``) at ``fine_rtol``; the first change where a
    trial reaches ``nu_top`` with T0'(y_max) small (|T0'| y_max < 1e-3 T0(y_max)) is the
    physical flow, and that trial's dense output is what
    :meth:`ExistenceVerdict.starting_state` samples for Newton. A change where no trial
    reaches the top is a separatrix (typically a dense band packing to ν_m that either
    collapses or heats up above it), not a solution, and the scan goes on below it.

    Cost: about 18 coarse trials plus 10–30 refining ones, 0.02–0.4 s per point on one core
    (the right-hand side is generated scalar code, :mod:`chuteflow.steady._scalar_ode`, ~5 µs
    a call, and the stepping loop is scipy's compiled ``dopri5``, :func:`integrate`: most of
    the time is now the right-hand side's Python calls).

    Parameters
    ----------
    theta : float
        Inclination θ in degrees.
    nu0 : float
        Floor packing fraction ν0(0).
    model : ChuteModel, optional
        Closure parameters (paper defaults).
    nu_top : float
        ν0 at the top of the domain (paper: 1e-9).
    u_range : (float, float)
        Admissible floor velocities (u_min, u_max) scanned.
    ratio : float
        Ratio of consecutive trials of the coarse scan.
    rtol : float
        Relative tolerance of the scan's integrations (loose: it needs signs only).
    fine_rtol : float
        Relative tolerance of the integrations that locate the solution in the bracket.
    min_thickness : float
        A solution thinner than this (diameters) is reported as ``physical = False``
        (paper §3.2: decay length below one particle diameter).

    Returns
    -------
    ExistenceVerdict
    """
    t_start = time.perf_counter()
    model = model or ChuteModel()
    theta, nu0 = validate_point(theta, nu0, model, nu_top)
    ode = SteadyODE(theta, model)
    where = _where(theta, nu0, model)
    u_min, u_max = map(float, u_range)
    n_trials = int(math.ceil(math.log(u_max / u_min) / math.log(ratio))) + 1
    trials = np.geomspace(u_max, u_min, n_trials)
    count = [0]

    def trial(u):
        count[0] += 1
        return shoot(ode, nu0, float(u), nu_top=nu_top, rtol=rtol)

    def done(kind, reason, **kw):
        return ExistenceVerdict(
            exists=kind in ("flow", "thin"),
            physical=kind == "flow",
            kind=kind,
            reason=reason,
            shots=count[0],
            seconds=time.perf_counter() - t_start,
            **kw,
        )

    def refine(cold, hot, tol=fine_rtol):
        """Brent on the signed miss in ln u0(0) at ``tol``; trials that do not reach
        nu_top count as ±1. Every trial keeps its dense output: the closest one to the root
        that reached the top is returned (None: a separatrix, see below)."""
        lo, hi = math.log(cold.u_floor), math.log(hot.u_floor)
        ends = {lo: cold, hi: hot}

        def miss(x):
            count[0] += 1
            shot = shoot(ode, nu0, math.exp(x), nu_top=nu_top, rtol=tol, dense=True)
            ends[x] = shot
            if len(ends) > 14 and not any(sh.kind == "top" for sh in ends.values()):
                raise _Separatrix
            return shot.miss

        # the miss jumps at separatrices: scipy's brentq (imported with scipy.integrate, which
        # only a failed cold start needs) bisects those robustly; through the forwarder of
        # chuteflow._memory, so that the shots of this scan are freed with it
        from .._memory import brentq

        try:
            x = brentq(miss, lo, hi, xtol=1e-10, rtol=1e-12, maxiter=60)
        except (ValueError, RuntimeError, _Separatrix):
            x = 0.5 * (lo + hi)
        # brentq starts with both ends: the scan's trials again, at tol
        fine = (ends[lo], ends[hi])
        # a scan trial within ~1e-4 of the root can change sign with the tolerance (θ =
        # 17.161°, ν0(0) = 0.16556, φ = 0.0455, Φ = 0.469, e_p = 0.688: the trial u0(0) =
        # 17.1907 is cold at 1e-4 and hot at 1e-6, the root 17.1887 lies below it): then
        # both ends have one sign at tol, and the scan's trial keeps its end of the bracket
        # here (the caller goes on from the trial at tol)
        if not any(sh.sign < 0 for sh in ends.values()):
            ends[lo] = cold
        if not any(sh.sign > 0 for sh in ends.values()):
            ends[hi] = hot
        cold_u = max(math.exp(v) for v, sh in ends.items() if sh.sign < 0)
        hot_u = min(math.exp(v) for v, sh in ends.items() if sh.sign > 0)
        # a trial that solves the top condition eq. (3.13): T0' small on the scale of the
        # layer (T0(y_max)/y_max); one far from it is a stray trial beside a separatrix
        reached = [
            v
            for v, sh in ends.items()
            if sh.kind == "top"
            and sh.solution.sol is not None
            and abs(sh.dT_top) * sh.y_end < 1e-3 * float(sh.solution.y[2, -1])
        ]
        best = ends[min(reached, key=lambda v: abs(v - x))] if reached else None
        x_cold = max(v for v, sh in ends.items() if sh.sign < 0)
        x_hot = min(v for v, sh in ends.items() if sh.sign > 0)
        a, b = ends[x_cold], ends[x_hot]
        if (
            best is None
            and a.kind == b.kind == "top"
            and abs(x_hot - x_cold) < 1e-7
            and a.solution.sol is not None
            and b.solution.sol is not None
        ):
            # T0'(y_max) changes sign between two trials that both reach the top, 1e-7
            # apart: a root of a continuous miss, not a separatrix — only too sensitive
            # (a packed, very cold band under the top) for |T0'| to become small
            best = a if abs(a.dT_top) <= abs(b.dT_top) else b
        nu_peak = max(math.exp(float(sh.solution.y[0].max())) for sh in ends.values())
        return best, (cold_u, hot_u), nu_peak, fine

    # the first hot → cold change coming down from u_max that brackets a solution; a change
    # without a trial reaching nu_top is a separatrix (a discontinuity of the miss, e.g. a
    # band packing to nu_max that either collapses or heats up above it), and the scan goes on
    prev = pprev = None
    signs = []
    final = separatrix = None
    for u in trials:
        shot = trial(u)
        signs.append(shot.sign)
        if prev is not None and prev.sign > 0 > shot.sign:
            best, bracket, nu_peak, (lo_fine, hi_fine) = refine(shot, prev)
            if best is None and lo_fine.sign > 0 and hi_fine.sign > 0:
                # this trial heats up at fine_rtol: the change lies below it, the scan goes
                # on from it as a hot trial
                signs[-1] = 1
                pprev, prev = prev, lo_fine
                continue
            cools = lo_fine.sign < 0 and hi_fine.sign < 0
            if best is None and cools and pprev is not None and pprev.sign > 0:
                # the trial above cools at fine_rtol: the change lies above it
                best, bracket, nu_peak, _ = refine(hi_fine, pprev)
            if best is None:
                # near the upper existence boundary the flow packs to within a hair of
                # nu_max below a dilute top, and a trial at fine_rtol can pack spuriously:
                # a separatrix is only believed when it persists at 1e-9 (as the
                # independent reference of tests/steady checks at 1e-11)
                best, bracket, nu_peak, _ = refine(shot, prev, 1e-9)
            if best is not None:
                final = best
                break
            separatrix = separatrix or (bracket, nu_peak)
        pprev, prev = prev, shot
    if final is None and separatrix is not None:
        bracket, nu_peak = separatrix
        packs = nu_peak > 0.95 * model.nu_max
        return done(
            "too_large" if packs else "no_sign_change",
            (
                f"no steady flow at {where}: the change from a heating to a cooling layer at "
                f"u0(0) ≈ {math.sqrt(bracket[0] * bracket[1]):.6g} is a separatrix, not a "
                f"solution — no trial there reaches nu0 = {nu_top:g}"
                + (
                    f" (the density piles up to {nu_peak:.3g}, close to nu_max = "
                    f"{model.nu_max:g}): the angle is too large for this floor density"
                    if packs
                    else ""
                )
            ),
            bracket=bracket,
        )
    if final is None:
        rng = f"u0(0) in [{u_min:g}, {u_max:g}]"
        if all(s > 0 for s in signs):
            return done(
                "too_small",
                (
                    f"no steady flow at {where}: shooting finds no sign change of T0' at the top "
                    f"for {rng} — every trial layer heats up (T0' > 0 where nu0 reaches "
                    f"{nu_top:g}, even the thin cold layer): the angle is too small for this "
                    "roughness and floor density"
                ),
            )
        if all(s < 0 for s in signs):
            return done(
                "too_large",
                (
                    f"no steady flow at {where}: shooting finds no sign change of T0' at the top "
                    f"for {rng} — every trial layer cools and collapses or packs to nu_max: "
                    "the angle is too large for this roughness and floor density"
                ),
            )
        return done(
            "no_sign_change",
            (
                f"no steady flow at {where}: shooting finds no change from a heating to a "
                f"cooling layer as u0(0) decreases over {rng}"
            ),
        )
    kw = {"bracket": bracket}
    kw["u_floor"] = final.u_floor
    y_max = final.y_end
    h = _thickness(final.solution, y_max)
    kw.update(h=h, y_max=y_max, solution=final.solution)
    if h < min_thickness:
        return done(
            "thin",
            (
                f"no steady flow at {where}: the only solution (u0(0) = {final.u_floor:.4g}) "
                f"has thickness h = {h:.3g}, below {min_thickness:g} particle diameter, which the "
                "hydrodynamics cannot describe — the angle is too small for this roughness (or "
                "the floor density too low)"
            ),
            **kw,
        )
    return done("flow", (f"steady flow at {where}: u0(0) = {final.u_floor:.6g}, h = {h:.4g}"), **kw)

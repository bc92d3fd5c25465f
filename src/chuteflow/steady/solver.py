"""Steady flows uniform along the slope (paper §3): Chebyshev–Newton on a free top boundary.

For given θ and floor density ν0(0) the unknowns are ν0, u0, T0 at the Chebyshev nodes of
[0, y_max] and the height y_max itself, fixed by ν0(y_max) = ``nu_top`` (paper: 1e-9). The
equations are the uniform-state residuals of :mod:`chuteflow.equations` (x- and y-momentum
and energy, eq:steady1–3), the floor conditions eq:bc1 and eq:bc2 (equivalent to eq:T0b,
eq:dT0b), stress-free top (u0' = 0, T0' = 0, eq:bcinf) and ν0(0) given. The Jacobian is the
exact linearisation from the same equations, so Newton converges quadratically.

Unlike the paper's shooting on u0(0), no growing mode is integrated, so there is nothing to
tune by hand; the cold start is an isothermal estimate of the layer (closed form in T).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
from scipy.integrate import quad

from ..closures import ChuteModel
from ..equations import BASE, base_state, compiled_equations
from ..errors import ConvergenceError, NoSteadyFlowError, ParameterError
from ..spectral import ChebyshevGrid

_STEADY_EQS = ("xmom", "ymom", "energy", "floor_x", "floor_energy")
_FIELDS = ("nu", "u", "T")


@dataclass
class _State:
    """Nodal unknowns: s = ln ν0 (keeps relative accuracy over nine decades), u0, T0, y_max."""

    n: int
    s: np.ndarray
    u: np.ndarray
    T: np.ndarray
    L: float

    @property
    def nu(self):
        return np.exp(self.s)

    def pack(self):
        return np.concatenate([self.s, self.u, self.T, [self.L]])

    @classmethod
    def unpack(cls, n, X):
        m = n + 1
        return cls(n, X[:m].copy(), X[m:2 * m].copy(), X[2 * m:3 * m].copy(), float(X[-1]))


def _validate(theta, nu0, model, nu_top):
    try:
        theta = float(theta)
        nu0 = float(nu0)
    except (TypeError, ValueError):
        raise ParameterError("theta and nu0 must be numbers") from None
    if not (0.0 < theta < 90.0) or not math.isfinite(theta):
        raise ParameterError(f"theta = {theta!r} is outside (0, 90) degrees: the slope "
                             "angle must be positive for a flow down the incline")
    if not (0.0 < nu0 < model.nu_max):
        raise ParameterError(f"nu0 = {nu0!r} is outside (0, nu_max = {model.nu_max:g}): the "
                             "floor packing fraction must be positive and below maximum packing")
    if not (0.0 < nu_top < 1e-3 * nu0):
        raise ParameterError(f"nu_top = {nu_top!r} must lie in (0, 1e-3·nu0): it is the "
                             "density at which the domain ends (paper: 1e-9)")
    return theta, nu0


def _profile_weights(model, nu0):
    """Isothermal layer in the scaled height ỹ = y cosθ / T: ν(ỹ) from p' = −ν cosθ."""
    f1 = model.f

    def dy_dlnnu(lnnu):  # dỹ/d(ln ν) = −f1'(ν)
        return -float(f1(math.exp(lnnu))["f1"][1])
    return dy_dlnnu


def isothermal_guess(theta_deg, nu0, model, nu_top, grid):
    """Cold start: isothermal layer with T fixed by the depth-integrated energy balance.

    With T constant, ν(y) depends on y/T only, every floor term scales as T^{3/2} and every
    bulk integral as T^{5/2}; the energy balance η* u_f² − Γ* = ∫(Γ − μ u'²) dy then fixes T
    in closed form.
    """
    th = math.radians(theta_deg)
    s, c = math.sin(th), math.cos(th)
    # ν as a function of ỹ = y c / T on a log-spaced ν grid
    lnnu = np.linspace(math.log(nu0), math.log(nu_top), 400)
    nus = np.exp(lnnu)
    f1p = model.f(nus)["f1"][1]
    ytil = np.concatenate([[0.0], np.cumsum(0.5 * (f1p[1:] + f1p[:-1]) * -np.diff(lnnu))])
    ev = model.evaluate(nus, 1.0)
    tan = s / c
    bulk_integrand = ev["Gamma"][(0, 0)] - tan**2 * ev["p"][(0, 0)] ** 2 / ev["mu"][(0, 0)]
    b = np.trapezoid(bulk_integrand, ytil) / c  # ∫ … dy = (T/c) ∫ … dỹ, per T^{5/2}
    e0 = model.evaluate(nu0, 1.0)
    uf1 = tan * e0["p"][(0, 0)] / e0["eta_star"][(0, 0)]  # u_f per √T
    a = float(e0["eta_star"][(0, 0)] * uf1**2 - e0["Gamma_star"][(0, 0)])
    T = a / b if (a > 0 and b > 0) else 1.0
    L = T * ytil[-1] / c
    y = grid.y * L
    nu = np.exp(np.interp(y * c / T, ytil, lnnu))
    ev = model.evaluate(nu, T)
    uprime = tan * ev["p"][(0, 0)] / ev["mu"][(0, 0)]
    g = ChebyshevGrid(grid.n, 0.0, L)
    u = uf1 * math.sqrt(T) + g.cumulative(uprime)
    return _State(grid.n, np.log(nu), u, np.full_like(nu, T), L)


class _Newton:
    """Residual and exact Jacobian of the steady free-boundary problem on n + 1 nodes."""

    def __init__(self, n, theta_deg, nu0, model, nu_top):
        self.n = n
        self.ref = ChebyshevGrid(n, 0.0, 1.0)
        th = math.radians(theta_deg)
        self.sin, self.cos = math.sin(th), math.cos(th)
        self.ln0, self.model, self.lntop = math.log(nu0), model, math.log(nu_top)
        self.eqs = compiled_equations()

    def evaluate(self, st: _State, jac=True):
        n, m, L = self.n, self.n + 1, st.L
        Dx, Dx2 = self.ref.D, self.ref.D2
        D1, D2 = Dx / L, Dx2 / L**2
        nu = np.exp(st.s)
        s1, s2 = D1 @ st.s, D2 @ st.s
        base = {"nu": nu, "nu_y": nu * s1, "nu_yy": nu * (s2 + s1**2), "u": st.u,
                "u_y": D1 @ st.u, "u_yy": D2 @ st.u, "T": st.T, "T_y": D1 @ st.T,
                "T_yy": D2 @ st.T}
        part = self.model.evaluate(nu, st.T)
        eye = np.eye(m)
        mats = (eye, D1, D2)
        # d(ν-jet c)/ds: chain rule through ν = e^s
        dnu = (np.diag(nu), nu[:, None] * (np.diag(s1) + D1),
               nu[:, None] * (np.diag(s2 + s1**2) + D2 + 2.0 * s1[:, None] * D1))
        jets = {"u": (st.u, base["u_y"], base["u_yy"]), "T": (st.T, base["T_y"], base["T_yy"]),
                "nu": (nu, base["nu_y"], base["nu_yy"])}
        out = {}
        for name in _STEADY_EQS:
            ce = self.eqs[name]
            res, coefs = ce.evaluate(base, part, self.sin, self.cos)
            res = np.broadcast_to(res, (m,))
            blocks = {f: np.zeros((m, m)) for f in _FIELDS}
            dL = np.zeros(m)
            if jac:
                for t, cf in zip(ce.terms, coefs):
                    if t.a or t.b or t.d or t.field not in blocks:
                        continue
                    cf = np.broadcast_to(cf, (m,))
                    blocks[t.field] += cf[:, None] * (dnu[t.c] if t.field == "nu" else mats[t.c])
                    if t.c:
                        dL += cf * (-t.c / L) * jets[t.field][t.c]
            out[name] = (res, blocks, dL)
        N = 3 * m + 1
        R = np.zeros(N)
        J = np.zeros((N, N)) if jac else None
        scale_nu = 1.0 / nu
        # x-momentum carries (μu0')' whose round-off is absolute, not relative to ν: a
        # constant scale keeps the dilute top from amplifying it
        scale_u = np.full(m, 1.0 / nu[0])
        scale_T = 1.0 / part["kappa"][(0, 0)]

        kap = part["kappa"]

        def put(row, eq, idx, kind):
            # rows are scaled pointwise (by 1/ν or 1/κ); the scale's own derivative is kept
            # so that J is the exact Jacobian of the scaled residual
            res, blocks, dL = out[eq]
            scale = {"nu": scale_nu, "T": scale_T, "u": scale_u}[kind][idx]
            R[row] = scale * res[idx]
            if jac:
                for k, f in enumerate(_FIELDS):
                    J[row, k * m:(k + 1) * m] = scale * blocks[f][idx]
                J[row, -1] = scale * dL[idx]
                if kind == "nu":
                    J[row, idx] -= res[idx] * scale  # d(1/ν)/ds = −1/ν
                elif kind == "T":
                    J[row, idx] -= res[idx] * scale**2 * kap[(1, 0)][idx] * nu[idx]
                    J[row, 2 * m + idx] -= res[idx] * scale**2 * kap[(0, 1)][idx]

        # ν block: ν(0) = ν0; y-momentum at nodes 1..n
        R[0] = st.s[0] - self.ln0
        if jac:
            J[0, 0] = 1.0
        for i in range(1, m):
            put(i, "ymom", i, "nu")
        # u block: floor momentum (eq:bc1); x-momentum inside; u' = 0 on top
        put(m, "floor_x", 0, "u")
        for i in range(1, n):
            put(m + i, "xmom", i, "u")
        R[m + n] = (D1 @ st.u)[n]
        if jac:
            J[m + n, m:2 * m] = D1[n]
            J[m + n, -1] = -R[m + n] / L
        # T block: floor energy (eq:bc2); energy inside; T' = 0 on top
        put(2 * m, "floor_energy", 0, "T")
        for i in range(1, n):
            put(2 * m + i, "energy", i, "T")
        R[2 * m + n] = (D1 @ st.T)[n]
        if jac:
            J[2 * m + n, 2 * m:3 * m] = D1[n]
            J[2 * m + n, -1] = -R[2 * m + n] / L
        # free boundary: ln ν(y_max) = ln ν_top
        R[-1] = st.s[n] - self.lntop
        if jac:
            J[-1, n] = 1.0
        return R, J

    def solve(self, st: _State, tol=1e-10, maxiter=60, y_cap=1e5):
        """Damped Newton. Converged when the scaled residual is below ``tol``, or when the
        relative Newton step falls below 1e-11 with the residual at its round-off floor."""
        hist = []
        R, J = self.evaluate(st)
        res = np.abs(R).max()
        for it in range(maxiter):
            hist.append(res)
            if not np.isfinite(res):
                break
            try:
                dX = -sla.lu_solve(sla.lu_factor(J, check_finite=False), R, check_finite=False)
            except (ValueError, np.linalg.LinAlgError):
                break
            X0 = st.pack()
            step = np.abs(dX).max() / max(np.abs(X0).max(), 1.0)
            stalled = len(hist) > 2 and res > 0.5 * hist[-2] and res < 1e-7
            if res < tol or (step < 1e-11 and res < 1e-6) or stalled:
                return st, it, res, hist
            lam = 1.0
            while lam > 1e-6:
                trial = _State.unpack(self.n, X0 + lam * dX)
                if (trial.T > 0).all() and 0 < trial.L < y_cap:
                    Rt, Jt = self.evaluate(trial)
                    rt = np.abs(Rt).max()
                    if np.isfinite(rt) and (rt < (1 - 0.1 * lam) * res or (lam == 1.0 and rt < 1e-6)):
                        st, R, J, res = trial, Rt, Jt, rt
                        break
                lam *= 0.5
            else:
                break
        hist.append(res)
        raise _NewtonFailure(st, hist)


class _NewtonFailure(Exception):
    def __init__(self, state, history):
        super().__init__("Newton did not converge")
        self.state, self.history = state, history


def _resample(st: _State, n: int) -> _State:
    """Interpolate a state to n + 1 nodes on the same [0, y_max] (log ν for positivity)."""
    if st.n == n:
        return _State(n, st.nu.copy(), st.u.copy(), st.T.copy(), st.L)
    old = ChebyshevGrid(st.n, 0.0, 1.0)
    new = ChebyshevGrid(n, 0.0, 1.0).y
    return _State(n, old.interpolate(st.s, new), old.interpolate(st.u, new),
                  old.interpolate(st.T, new), st.L)


def solve_state(theta, nu0, model, nu_top, n, guess=None, tol=1e-11):
    """Solve the steady problem; returns (state, iterations, residual). Raises on failure."""
    newton = _Newton(n, theta, nu0, model, nu_top)
    if guess is None:
        guess = isothermal_guess(theta, nu0, model, nu_top, newton.ref)
    else:
        guess = _resample(guess, n)
        guess.s = guess.s + (math.log(nu0) - guess.s[0])  # exact floor value, same shape
    try:
        st, it, res, _ = newton.solve(guess, tol=tol)
    except _NewtonFailure as fail:
        raise _diagnose(theta, nu0, model, fail) from None
    return st, it, res


def _diagnose(theta, nu0, model, fail):
    """Turn a failed Newton solve into an error that says which case it is."""
    st = fail.state
    where = (f"theta = {theta:g} deg, nu0 = {nu0:g}, roughness = {model.roughness:g}, "
             f"wall_loss = {model.wall_loss:g}")
    if st.L > 2e3:
        return NoSteadyFlowError(
            f"no steady flow at {where}: the density decay length diverges (y_max grew past "
            f"{st.L:.3g} diameters) — the angle is too large for this roughness")
    if st.L < 2.0 or st.T.min() < 1e-3:
        return NoSteadyFlowError(
            f"no steady flow at {where}: the layer collapses (decay length {st.L:.2g} "
            "diameters, below one particle diameter) — the angle is too small for this "
            "roughness, or the floor density too low")
    return ConvergenceError(
        f"steady solver did not converge at {where}: Newton stalled with residual "
        f"{fail.history[-1]:.2e} after {len(fail.history)} iterations")

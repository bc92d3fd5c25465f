"""Nonlinear density waves of the 1D model (eqs 5.10, 5.11) on a periodic slope of length L.

Discretisation: finite volumes on a staggered periodic grid of N cells, dx = L/N. The density
ρ̄ lives at cell centres x_i = (i + ½) dx, the momentum m = ρ̄ū on the faces x_{i+½}
(staggering couples neighbouring cells in the pressure gradient, so no odd–even modes):

    dρ_i/dt = −(m_{i+½} − m_{i−½}) / dx,
    dm_{i+½}/dt = −(Π_{i+1} − Π_i) / dx + ρ_{i+½} sin θ − a(ρ_{i+½}) u_{i+½},
    Π_i = ρ_i ū_i² + ρ_i T̄(ρ_i) − μ̄(ρ_i) (u_{i+½} − u_{i−½}) / dx,

with ρ_{i+½} the mean of the two cells, u_{i+½} = m_{i+½}/ρ_{i+½} and ū_i the mean of the two
face velocities. Second order in space. Mass Σ ρ_i dx changes only by a telescoping sum, so
it is conserved to round-off by the semi-discrete system.

Time: scipy's Radau IIA (implicit Runge–Kutta of order 5, L-stable; error control by
``rtol``) with the exact sparse Jacobian of the discrete right-hand side. L-stability matters:
the grid-scale acoustic modes are weakly damped and strongly oscillatory (Re α ≈ −0.3,
Im α ≈ ±7 at θ = 14°, dx ≈ 1), where BDF of order 3–5 is unstable and crawls at dt ≈ 0.1;
Radau's steps are limited by accuracy only. Because the exact Jacobian has the same
telescoping structure as the right-hand side (its mass rows sum to zero), every simplified-
Newton update conserves mass to round-off too — unlike a finite-difference Jacobian, whose
column sums vanish only to ~1e-9.

The fluxes Π, the source and their partial derivatives come from the one statement of the
model in :mod:`chuteflow.reduced.equations`; :func:`_assemble` applies the chain rule over
the stencil, and the same assembly on the operators' Fourier symbols gives the closed-form
symbol of the linearised scheme (:meth:`WaveSolver.symbol`).

Structure: :class:`WaveSolver` is the semi-discrete system (right-hand side, Jacobian,
linear modes); :class:`WaveSimulation` checks the input, fixes the grid and the frame and
steps the integrator; trackers watch the steps and may stop the run (in the style of
py-pde's ``solve(..., tracker=[...])``), the same trackers as the full model's simulation
(:mod:`chuteflow.trackers`): :class:`SnapshotTracker`, :class:`SaturationStop`,
:class:`ProgressTracker`, :class:`LeaveFamilyStop` (:class:`~chuteflow.trackers.ValidityStop`),
:class:`~chuteflow.trackers.ResolutionMonitor`, or a subclass of :class:`Tracker`.
:func:`simulate` is the convenience wrapper returning an xarray Dataset.
"""

from __future__ import annotations

import math
import time as _time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from scipy.integrate import BDF, Radau

from ..errors import ConvergenceError, NoSteadyFlowError, ParameterError
from ..trackers import (
    ProgressTracker,
    SaturationStop,
    SnapshotTracker,
    Tracker,
    ValidityStop,
)
from . import equations as eq
from .model import LocalCoefficients, ReducedModel

__all__ = [
    "WaveSolver",
    "WaveSimulation",
    "InitialState",
    "RunInfo",
    "Step",
    "Tracker",
    "SnapshotTracker",
    "SaturationStop",
    "ProgressTracker",
    "LeaveFamilyStop",
    "simulate",
    "default_cells",
    "growth_rate_fit",
    "wave_diagnostics",
]

#: The 1D model's name of :class:`chuteflow.trackers.ValidityStop`: its validity is the range
#: of the steady family.
LeaveFamilyStop = ValidityStop


def _closures(rm: ReducedModel, rho_c: np.ndarray, rho_f: np.ndarray, deriv: bool) -> tuple:
    """Closure values of the scheme: T̄, μ̄ (and slopes) at centres, a (and a') at faces; NaN
    outside the family (no raise)."""
    sT, sa = rm._splines["Tbar"], rm._splines["a"]
    T = np.exp(sT(rho_c))
    a = np.exp(sa(rho_f))
    dT = T * sT(rho_c, 1) if deriv else 0.0
    mu, dmu = eq.viscosity(T, dT, rm.theta, rm.f2_0)
    centres = eq.ClosureValues(Tbar=T, dTbar=dT, mu_bar=mu, dmu_bar=dmu)
    faces = eq.ClosureValues(a=a, da=a * sa(rho_f, 1) if deriv else None)
    return centres, faces


def _assemble(ops, diag, flux, source, u, rho_f, c: float) -> list:
    """Jacobian blocks [[∂ρ̇/∂ρ, ∂ρ̇/∂m], [∂ṁ/∂ρ, ∂ṁ/∂m]] of the staggered scheme.

    Chain rule over the stencil: Π_i = f_m(ρ_i, ū_i, (δu)_i) with ū = A_fc u, δu = D_fc u,
    u = m/ρ_f, ρ_f = A_cf ρ; S at faces; ``flux`` and ``source`` are the pointwise partials
    of the statement (:mod:`.equations`), ``ops`` = (A_cf, D_cf, A_fc, D_fc). With sparse
    matrices (``diag`` = sparse diagonal) this is the exact Jacobian; with the operators'
    Fourier symbols on a set of modes (diagonal over the modes) it is the discrete symbol.
    A frame moving at speed ``c`` adds the fluxes −cρ and −c m (face mean at centres).
    """
    A_cf, D_cf, A_fc, D_fc = ops
    dudr = diag(-u / rho_f) @ A_cf  # ∂u_f/∂ρ of both cells
    dudm = diag(1.0 / rho_f)
    G = diag(flux.u) @ A_fc + diag(flux.ux) @ D_fc  # ∂Π/∂u_f
    dPi_r = diag(flux.rho) + G @ dudr
    dPi_m = G @ dudm
    dS_r = diag(source.rho) @ A_cf + diag(source.u) @ dudr
    dS_m = diag(source.u) @ dudm
    return [[(D_fc @ A_cf) * c, -D_fc], [-D_cf @ dPi_r + dS_r, -D_cf @ dPi_m + dS_m + (D_cf @ A_fc) * c]]


class _ModeDiagonal(np.ndarray):
    """Diagonal operator over a set of Fourier modes (its diagonal): ``@`` multiplies."""

    def __matmul__(self, other):
        return np.multiply(self, other)


class WaveSolver:
    """Semi-discrete 1D model on a periodic domain: right-hand side, Jacobian, linear modes.

    Parameters
    ----------
    reduced : ReducedModel
        F, T̄, a of the 1D model at the chosen θ.
    length : float
        Domain length L (particle diameters).
    n_cells : int
        Number of finite-volume cells N.
    """

    def __init__(self, reduced: ReducedModel, length: float, n_cells: int, frame_speed: float = 0.0):
        if not (math.isfinite(length) and length > 0):
            raise ParameterError(f"length = {length!r} must be a positive number of diameters")
        if int(n_cells) != n_cells or n_cells < 8:
            raise ParameterError(f"n_cells = {n_cells!r} must be an integer >= 8")
        self.rm = reduced
        self.L, self.N = float(length), int(n_cells)
        self.dx = self.L / self.N
        self.sin = math.sin(math.radians(reduced.theta))
        self.x = (np.arange(self.N) + 0.5) * self.dx
        self.x_face = (np.arange(self.N) + 1.0) * self.dx
        N, h = self.N, 1.0 / self.dx
        i = np.arange(N)
        ip = (i + 1) % N
        im = (i - 1) % N
        ones = np.ones(N)
        # face j = j+½ from cells j, j+1; cell i from faces i−½ (= face i−1) and i+½ (= face i)
        self.A_cf = sp.csr_matrix((np.r_[ones, ones] * 0.5, (np.r_[i, i], np.r_[i, ip])), shape=(N, N))
        self.D_cf = sp.csr_matrix((np.r_[-ones, ones] * h, (np.r_[i, i], np.r_[i, ip])), shape=(N, N))
        self.A_fc = sp.csr_matrix((np.r_[ones, ones] * 0.5, (np.r_[i, i], np.r_[im, i])), shape=(N, N))
        self.D_fc = sp.csr_matrix((np.r_[-ones, ones] * h, (np.r_[i, i], np.r_[im, i])), shape=(N, N))
        # frame moving down the slope at speed c: ∂t|ξ = ∂t|x + c ∂x, in flux form
        # (fluxes m − cρ and ρu² − c m), so mass stays conserved to round-off
        self.c = float(frame_speed)
        self.n_rhs = 0
        self.n_jac = 0
        self.out_of_range: tuple[float, float] | None = None

    # -- state helpers -----------------------------------------------------------------
    def split(self, y):
        return y[: self.N], y[self.N :]

    def mass(self, y) -> float:
        """Total mass Σ ρ_i dx = ∫ ρ̄ dx."""
        return float(np.sum(y[: self.N]) * self.dx)

    def uniform(self, rho0: float) -> np.ndarray:
        """The uniform state ρ̄ = ρ0, ū = U(ρ0): an exact equilibrium of the discrete system."""
        U0 = float(self.rm.U(rho0))
        return np.concatenate([np.full(self.N, rho0), np.full(self.N, rho0 * U0)])

    def velocity(self, y) -> tuple[np.ndarray, np.ndarray]:
        """Face velocities u_{i+½} and their cell-centre means ū_i."""
        rho, m = self.split(y)
        rf = 0.5 * (rho + np.roll(rho, -1))
        u = m / rf
        return u, 0.5 * (u + np.roll(u, 1))

    # -- right-hand side and Jacobian ---------------------------------------------------
    def rhs(self, t, y) -> np.ndarray:
        """d(ρ, m)/dt. NaN (never an exception) if ρ leaves the family: BDF then cuts the
        step; a real excursion ends the run with a clear error in :func:`simulate`."""
        self.n_rhs += 1
        N, h = self.N, 1.0 / self.dx
        rho, m = y[:N], y[N:]
        rf = 0.5 * (rho + np.roll(rho, -1))
        lo, hi = self.rm.rho_range
        if not (rho.min() >= lo and rho.max() <= hi):
            bad = rho.min() if rho.min() < lo else rho.max()
            self.out_of_range = (float(t), float(bad))
            return np.full_like(y, np.nan)
        centres, faces = _closures(self.rm, rho, rf, deriv=False)
        u = m / rf
        uc = 0.5 * (u + np.roll(u, 1))
        du = (u - np.roll(u, 1)) * h
        Pi = eq.momentum_flux(rho, uc, du, centres)
        out = np.empty_like(y)
        if self.c:
            Pi -= self.c * 0.5 * (m + np.roll(m, 1))
            flux = m - self.c * rf
        else:
            flux = m
        out[:N] = -(flux - np.roll(flux, 1)) * h
        out[N:] = -(np.roll(Pi, -1) - Pi) * h + eq.source(rf, u, self.sin, faces)
        return out

    def jacobian(self, t, y) -> sp.csc_matrix:
        """Exact Jacobian of :meth:`rhs` (sparse, periodic band)."""
        self.n_jac += 1
        N = self.N
        # the Jacobian only steers Newton: outside the family use the nearest defined state
        rho, m = np.clip(y[:N], *self.rm.rho_range), y[N:]
        rf = 0.5 * (rho + np.roll(rho, -1))
        centres, faces = _closures(self.rm, rho, rf, deriv=True)
        u = m / rf
        uc = 0.5 * (u + np.roll(u, 1))
        du = (u - np.roll(u, 1)) / self.dx
        blocks = _assemble(
            (self.A_cf, self.D_cf, self.A_fc, self.D_fc),
            sp.diags,
            eq.flux_partials(rho, uc, du, centres),
            eq.source_partials(rf, u, self.sin, faces),
            u,
            rf,
            self.c,
        )
        return sp.bmat(blocks, format="csc")

    # -- linear theory of the discrete system ---------------------------------------------
    def mode_vectors(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """Fourier mode n on centres (for ρ) and on faces (for m): exp(i k x), k = 2πn/L."""
        k = 2 * math.pi * n / self.L
        return np.exp(1j * k * self.x), np.exp(1j * k * self.x_face)

    def mode_matrix(self, rho0: float, n: int, *, numerical: bool = True, eps: float = 1e-7) -> np.ndarray:
        """2×2 block of the linearised discrete operator on Fourier mode ``n`` about the
        uniform state, in the variables (ρ̂, m̂).

        ``numerical=True`` linearises :meth:`rhs` by central differences along the mode
        (independent of :meth:`jacobian`); otherwise the exact Jacobian is used.
        """
        y0 = self.uniform(rho0)
        er, ef = self.mode_vectors(n)
        N = self.N
        cols = []
        for comp in (0, 1):
            v = np.zeros(2 * N, dtype=complex)
            if comp == 0:
                v[:N] = er
            else:
                v[N:] = ef
            if numerical:
                scale = eps * max(abs(y0[comp * N]), 1.0)
                Jv = np.zeros(2 * N, dtype=complex)
                for part, fac in ((v.real, 1.0), (v.imag, 1j)):
                    Jv += (
                        fac * (self.rhs(0, y0 + scale * part) - self.rhs(0, y0 - scale * part)) / (2 * scale)
                    )
            else:
                Jv = self.jacobian(0, y0) @ v
            cols.append([np.vdot(er, Jv[:N]) / N, np.vdot(ef, Jv[N:]) / N])
        return np.array(cols).T

    def symbol(self, rho0: float, n) -> np.ndarray:
        """Closed form of :meth:`mode_matrix` for modes ``n`` (array): shape ``n.shape + (2, 2)``.

        With C = cos(k dx/2) (face ↔ centre averages) and K = 2 sin(k dx/2)/dx (staggered
        differences): the exact Jacobian's assembly with every averaging operator replaced by
        C and every difference by iK, i.e. the continuum matrix in (ρ̂, m̂) with k → K and the
        averaged terms × C.
        K → k and C → 1 as dx → 0, so the discrete growth rates differ from the 2×2
        dispersion relation by O((k dx)²). A moving frame adds i c sin(k dx)/dx to both
        diagonal entries: it shifts the frequencies and leaves the growth rates unchanged.
        """
        c = self.rm.coefficients(rho0)
        n = np.asarray(n, dtype=float)
        k = 2 * np.pi * n.ravel() / self.L
        C = np.cos(0.5 * k * self.dx)
        iK = 2j * np.sin(0.5 * k * self.dx) / self.dx

        def diag(v):
            return np.broadcast_to(np.asarray(v, dtype=complex), k.shape).view(_ModeDiagonal)

        A, D = diag(C), diag(iK)
        blocks = _assemble(
            (A, D, A, D),
            diag,
            eq.flux_partials(c.rho0, c.U, 0.0, c),
            eq.source_partials(c.rho0, c.U, self.sin, c),
            c.U,
            c.rho0,
            self.c,
        )
        M = np.empty(n.shape + (2, 2), dtype=complex)
        for i in (0, 1):
            for j in (0, 1):
                M[..., i, j] = np.asarray(blocks[i][j]).reshape(n.shape)
        return M

    def discrete_dispersion(self, rho0: float, n, **kw) -> np.ndarray:
        """Growth rates of the linearised discrete system on modes ``n``, least stable first
        (shape ``n.shape + (2,)``). ``kw`` given: eigenvalues of :meth:`mode_matrix` (one n)."""
        if kw:
            ev = np.linalg.eigvals(self.mode_matrix(rho0, int(n), **kw))
            return ev[np.argsort(-ev.real)]
        ev = np.linalg.eigvals(self.symbol(rho0, n))
        order = np.argsort(-ev.real, axis=-1)
        return np.take_along_axis(ev, order, axis=-1)

    def eigenmode(self, rho0: float, n: int, amplitude: float) -> np.ndarray:
        """Uniform state plus the least-stable discrete eigenmode n with density amplitude
        ``amplitude`` (real part taken; n = 0 not allowed)."""
        if n < 1 or n >= self.N // 2:
            raise ParameterError(f"mode = {n!r} must be in [1, N/2 − 1] = [1, {self.N // 2 - 1}]")
        w, V = np.linalg.eig(self.symbol(rho0, n))
        v = V[:, int(np.argmax(w.real))]
        v = v / v[0]
        er, ef = self.mode_vectors(n)
        y = self.uniform(rho0)
        y[: self.N] += amplitude * (v[0] * er).real
        y[self.N :] += amplitude * (v[1] * ef).real
        return y


# ---------------------------------------------------------------------------------------


def wave_diagnostics(solver: WaveSolver, rho0: float, y: np.ndarray, n_modes: int):
    """Amplitude max|ρ − ρ0|, mass and |ρ̂_n| (n = 1..n_modes, normalised like a cosine
    amplitude) of one state."""
    rho = y[: solver.N]
    c = np.fft.rfft(rho - rho0) * (2.0 / solver.N)
    return float(np.abs(rho - rho0).max()), solver.mass(y), np.abs(c[1 : n_modes + 1])


def default_cells(
    reduced: ReducedModel, rho0: float, length: float, *, tol: float = 0.05, n_max: int = 16384
) -> int:
    """Cells for a run: the growth rates of the discrete system must match the 2×2 dispersion
    relation (eq. (5.12)'s exact form) to ``tol`` × the largest growth rate.

    Starting from dx ≤ 2 (and ≥ 128 cells), N doubles until every mode with k < k_c (the
    16 longest modes when every k grows or none does) has |Re α_discrete − Re α| ≤ tol ·
    max(max Re α, 1e-3 |Im α|). The error is O((k dx)²); the growth rate being a small
    difference of large terms (Im α ≈ k dq0/dρ0), this asks for ~100 cells per critical
    wavelength.
    """
    coef = reduced.coefficients(rho0)
    n = max(128, 2 ** int(math.ceil(math.log2(max(length / 2.0, 1.0)))))
    while True:
        solver = WaveSolver(reduced, length, n)
        ns = np.arange(1, n // 2)
        ks = 2 * np.pi * ns / length
        sel = ks < coef.k_c if (coef.unstable and math.isfinite(coef.k_c)) else ns <= 16
        sel[:1] = True
        ana = coef.dispersion(ks[sel])[:, 0]
        dis = solver.discrete_dispersion(rho0, ns[sel])[:, 0]
        scale = max(float(ana.real.max()), 1e-3 * float(np.abs(ana.imag).max()), 1e-12)
        if np.abs(dis.real - ana.real).max() <= tol * scale or 2 * n > n_max:
            return n
        n *= 2


# ---------------------------------------------------------------------------------------
# The time stepper and its trackers
# ---------------------------------------------------------------------------------------


@dataclass(frozen=True)
class InitialState:
    """A perturbed uniform state to start a run from.

    Attributes
    ----------
    y : ndarray
        (ρ_i, m_{i+½}) on the grid.
    amplitude : float
        Size of the density perturbation (σ): it sets the integrator's absolute tolerance
        and the reference of the stop conditions.
    description : str
        One line for the output's ``initial_condition``.
    """

    y: np.ndarray = field(repr=False)
    amplitude: float
    description: str


class Step:
    """One accepted step (t_prev, t] of the integrator, as trackers see it."""

    def __init__(self, ode, t_prev: float, y_u: np.ndarray, number: int):
        self._ode, self._y_u = ode, y_u
        self.t_prev, self.t, self.number = float(t_prev), float(ode.t), number
        self._dense: Callable[[float], np.ndarray] | None = None

    @property
    def y(self) -> np.ndarray:
        """State at the end of the step."""
        return self._y_u + self._ode.y

    def state(self, t: float) -> np.ndarray:
        """State at time ``t`` in [t_prev, t] (the integrator's dense output)."""
        dense = self._dense
        if dense is None:
            dense = self._dense = self._ode.dense_output()
        return self._y_u + dense(t)


@dataclass
class RunInfo:
    """How a run ended.

    Attributes
    ----------
    status : str
        "completed" (reached t_end), "left_family" (stopped by :class:`LeaveFamilyStop`) or
        the status a stop condition returned ("saturated", "decayed").
    t, y : float, ndarray
        Time and state of the last accepted step.
    t_end : float
        The requested final time.
    auto_time : bool
        Whether t_end was chosen by :meth:`WaveSimulation.default_t_end`.
    initial : InitialState
        The initial state.
    steps : int
        Integrator steps (including a failed last one).
    wall_time_s : float
        Wall-clock time of the integration.
    left_family : str
        Why the density left the steady family ("" when it did not).
    """

    status: str
    t: float
    y: np.ndarray = field(repr=False)
    t_end: float
    auto_time: bool
    initial: InitialState = field(repr=False)
    steps: int
    wall_time_s: float
    left_family: str = ""


class WaveSimulation:
    """Time stepper of the 1D model on a periodic slope, from a uniform state ρ0.

    All input is checked here, once. The linear theory of the domain's modes (2×2 dispersion
    relation and the discrete operator) is computed on construction; it fixes the frame.

    Parameters
    ----------
    reduced : ReducedModel
        The 1D model at the chosen θ (:func:`~chuteflow.reduced.reduced_model`).
    length : float
        Periodic domain length L in particle diameters.
    rho0, nu0 : float
        The uniform state: one-dimensional density ρ0, or the floor density ν0(0) of the
        steady flow it comes from (exactly one of them).
    n_cells : int, optional
        Grid cells; default :func:`default_cells`.
    frame : {"wave", "lab"} or float
        Reference frame of the computation and of the output: ``"wave"`` moves down the
        slope with the phase velocity of the fastest-growing discrete mode (the waves evolve
        slowly there and the implicit integrator takes ~10× longer steps); the output
        coordinate is then ξ = x − c t. Growth rates do not depend on it.
    rtol : float
        Relative tolerance of the time integrator (atol = rtol · 1e-3 · scale).
    method : {"Radau", "BDF"}
        Implicit integrator (scipy); BDF is slow here (see the module notes).
    max_steps : int
        Give up (ConvergenceError) after this many time steps.

    Examples
    --------
    >>> sim = WaveSimulation(rm, 40.0, nu0=0.12)                     # doctest: +SKIP
    >>> snaps = SnapshotTracker(count=100)                           # doctest: +SKIP
    >>> info = sim.run(sim.perturbed(mode=1), 60.0, trackers=[snaps])  # doctest: +SKIP
    >>> ds = sim.dataset(snaps, info)                                # doctest: +SKIP
    """

    def __init__(
        self,
        reduced: ReducedModel,
        length: float,
        *,
        rho0: float | None = None,
        nu0: float | None = None,
        n_cells: int | None = None,
        frame="wave",
        rtol: float = 1e-6,
        method: str = "Radau",
        max_steps: int = 200000,
    ):
        if (rho0 is None) == (nu0 is None):
            raise ParameterError("give exactly one of rho0 (1D density) and nu0 (floor density)")
        lo, hi = reduced.rho_range
        if nu0 is not None:
            rho0 = reduced.rho_at_nu0(float(nu0))
            if not lo < rho0 < hi:  # rho_at_nu0 returns a knot's ρ̄ exactly
                raise ParameterError(
                    f"nu0 = {nu0:g} is an end of the steady family at theta = "
                    f"{reduced.theta:g} deg (floor densities [{reduced.nu0[0]:.4g}, "
                    f"{reduced.nu0[-1]:.4g}]): a wave about it would leave the range where "
                    "the 1D model is defined at once; choose nu0 inside"
                )
        rho0 = float(rho0)  # type: ignore[arg-type]  # one of rho0, nu0 is set
        if not lo < rho0 < hi:
            raise ParameterError(
                f"rho0 = {rho0:g} is outside ({lo:.4g}, {hi:.4g}), the range of "
                f"the steady family at theta = {reduced.theta:g} deg"
            )
        if not (math.isfinite(length) and length > 0):
            raise ParameterError(f"length = {length!r} must be a positive number of diameters")
        if n_cells is not None and (int(n_cells) != n_cells or n_cells < 8):
            raise ParameterError(f"n_cells = {n_cells!r} must be an integer >= 8")
        if not 1e-12 < rtol < 1e-1:
            raise ParameterError(f"rtol = {rtol!r} must be in (1e-12, 0.1)")
        if method not in ("Radau", "BDF"):
            raise ParameterError(f"method = {method!r}: choose 'Radau' or 'BDF'")
        if frame not in ("wave", "lab"):
            try:
                frame = float(frame)
            except (TypeError, ValueError):
                raise ParameterError(f"frame = {frame!r}: 'wave', 'lab' or a speed") from None
        if int(max_steps) != max_steps or max_steps < 1:
            raise ParameterError(f"max_steps = {max_steps!r} must be a positive integer")
        self.reduced, self.rho0 = reduced, rho0
        self.rtol, self.method, self.max_steps = float(rtol), method, int(max_steps)
        self.coef: LocalCoefficients = reduced.coefficients(rho0)
        n_cells = default_cells(reduced, rho0, length) if n_cells is None else int(n_cells)
        lab = WaveSolver(reduced, length, n_cells)
        # linear theory of the domain's modes (analytic 2×2 and the discrete operator, lab)
        self.modes = np.arange(1, lab.N // 2)
        self.k = 2 * np.pi * self.modes / lab.L
        self.growth_analytic = self.coef.dispersion(self.k)[:, 0]
        self.growth_discrete = lab.discrete_dispersion(rho0, self.modes)[:, 0]
        self.max_growth_rate = float(self.growth_discrete.real.max())
        if frame == "wave":
            best = int(np.argmax(self.growth_discrete.real))
            c = float(-self.growth_discrete[best].imag / self.k[best])
        else:
            c = 0.0 if frame == "lab" else float(frame)
        self.frame_speed = c
        self.solver = WaveSolver(reduced, length, n_cells, frame_speed=c) if c else lab

    # -- initial states and the time span ---------------------------------------------------
    def perturbed(self, mode: int | None = None, amplitude: float = 1e-3, seed: int = 0) -> InitialState:
        """The uniform state plus a perturbation of relative size ``amplitude``.

        ``mode`` given: the least-stable discrete eigenmode ``mode`` (k = 2π mode/L) with
        cosine amplitude ``amplitude`` ρ0; otherwise seeded random noise in every resolved
        density mode (zero mean, max|δρ̄| = ``amplitude`` ρ0) at uniform velocity.
        """
        if not 0.0 < amplitude < 0.5:
            raise ParameterError(f"amplitude = {amplitude!r} must be in (0, 0.5) (relative to rho0)")
        s, rho0, N = self.solver, self.rho0, self.solver.N
        if mode is None:
            rng = np.random.default_rng(seed)
            noise = rng.standard_normal(N)
            noise -= noise.mean()
            noise *= amplitude * rho0 / np.abs(noise).max()
            y0 = s.uniform(rho0)
            y0[:N] += noise
            y0[N:] = y0[:N] * self.coef.U  # uniform velocity
            init = f"random noise (seed {seed}), max |δρ|/ρ0 = {amplitude:g}"
        else:
            y0 = s.eigenmode(rho0, int(mode), amplitude * rho0)
            init = (
                f"discrete eigenmode {mode} (k = {2 * math.pi * mode / s.L:.5g}), amplitude {amplitude:g} ρ0"
            )
        return InitialState(y=y0, amplitude=amplitude * rho0, description=init)

    def default_t_end(self) -> float:
        """40 e-foldings of the fastest discrete mode (10 for a stable state), at most 1e6."""
        sigma = self.max_growth_rate
        rate = abs(sigma) if sigma != 0 else 1e-6
        return min((40.0 if sigma > 0 else 10.0) / max(rate, 1e-6), 1e6)

    # -- the stepper --------------------------------------------------------------------------
    def wave_amplitude(self, y: np.ndarray) -> float:
        """max |ρ̄ − ρ0| of the state ``y``: the size of the wave (:class:`SaturationStop`)."""
        return wave_diagnostics(self.solver, self.rho0, y, 1)[0]

    def resolution(self, y: np.ndarray) -> dict[str, float]:
        """Amplitude of the highest eighth of the density's Fourier modes relative to the
        largest (``x_tail``; ``y_tail`` = 0: the model has no y), as
        :class:`~chuteflow.trackers.ResolutionMonitor` asks."""
        c = np.abs(np.fft.rfft(y[: self.solver.N] - self.rho0))[1:]
        top = c.max() if c.size else 0.0
        m = max(1, len(c) // 8)
        return {"x_tail": float(c[-m:].max() / top) if top > 0 else 0.0, "y_tail": 0.0}

    def run(self, initial: InitialState, time: float | None = None, trackers=()) -> RunInfo:
        """Integrate from ``initial`` to ``time`` (default :meth:`default_t_end`).

        Trackers (:mod:`chuteflow.trackers`: :class:`SnapshotTracker`, :class:`SaturationStop`,
        :class:`ProgressTracker`, :class:`LeaveFamilyStop`, …) watch every accepted step and
        may stop the run.

        Raises
        ------
        ParameterError
            Bad ``time``.
        NoSteadyFlowError
            The density left the range of the steady family and no tracker stops the run
            there.
        ConvergenceError
            The time integrator failed or needed more than ``max_steps`` steps.
        """
        t_end = time
        auto = t_end is None
        if t_end is None:
            t_end = self.default_t_end()
        elif not (math.isfinite(t_end) and t_end > 0):
            raise ParameterError(f"time = {t_end!r} must be a positive number")
        t_end = float(t_end)
        trackers = list(trackers)
        solver, rho0, N = self.solver, self.rho0, self.solver.N
        # integrate the deviation z = y − y_u from the uniform state (an exact equilibrium of
        # the discrete system), so that the error control is relative to the wave, not to ρ0:
        # with tolerances relative to y a wave of amplitude 1e-5 ρ0 is erased by large steps
        y_u = solver.uniform(rho0)
        # atol floor 1e-12 ρ0: the right-hand side carries round-off ~1e-16 Π/dx that no step
        # size can resolve
        rtol = self.rtol
        scale = (
            max(rtol * initial.amplitude, 1e-12 * rho0)
            / rtol
            * np.concatenate([np.ones(N), np.full(N, abs(self.coef.U) + 1.0)])
        )
        ode = {"Radau": Radau, "BDF": BDF}[self.method](
            lambda t, z: solver.rhs(t, y_u + z),
            0.0,
            initial.y - y_u,
            t_end,
            rtol=rtol,
            atol=rtol * scale,
            jac=lambda t, z: solver.jacobian(t, y_u + z),
        )
        for tr in trackers:
            tr.initialize(self, initial, t_end)
        t0 = _time.perf_counter()
        steps, status, left = 0, "completed", ""
        while ode.status == "running":
            t_prev = ode.t
            msg = ode.step()
            steps += 1
            if ode.status == "failed":
                if solver.out_of_range is None:
                    raise ConvergenceError(f"time integration failed at t = {ode.t:.6g}: {msg}")
                left = self._left_message(ode.t)
                stops = [tr.left_validity(self, left) for tr in trackers]  # every tracker is told
                if not any(stops):
                    raise NoSteadyFlowError(left)
                status = "left_family"
                break
            if steps > self.max_steps:
                raise ConvergenceError(
                    f"time integration needed more than {self.max_steps} "
                    f"steps (reached t = {ode.t:.6g} of {t_end:.6g})"
                )
            solver.out_of_range = None
            step = Step(ode, t_prev, y_u, steps)
            stops = [r for r in [tr.handle(self, step) for tr in trackers] if r]
            if stops:
                status = stops[0]
                break
        info = RunInfo(
            status=status,
            t=float(ode.t),
            y=y_u + ode.y,
            t_end=t_end,
            auto_time=auto,
            initial=initial,
            steps=steps,
            wall_time_s=_time.perf_counter() - t0,
            left_family=left,
        )
        for tr in trackers:
            tr.finalize(self, info)
        return info

    def _left_message(self, t: float) -> str:
        rm = self.reduced
        lo, hi = rm.rho_range
        assert self.solver.out_of_range is not None
        _, rb = self.solver.out_of_range
        return (
            f"the density wave left the steady family at t ≈ {t:.4g}: rho_bar reached "
            f"{rb:.4g}, outside [{lo:.4g}, {hi:.4g}] where F and T̄ of the 1D model are "
            f"defined (theta = {rm.theta:g} deg; family ends: {rm.ends[0]} / "
            f"{rm.ends[1]})"
        )

    # -- output ---------------------------------------------------------------------------------
    def dataset(self, snapshots: SnapshotTracker, info: RunInfo):
        """The run as an xarray Dataset (see :func:`simulate` for its content)."""
        import xarray as xr

        solver, rho0, coef, rm = self.solver, self.rho0, self.coef, self.reduced
        N = solver.N
        n_modes = len(self.modes)
        lo, hi = rm.rho_range
        t_used = np.array(snapshots.times)
        Y = np.array(snapshots.states)
        rho = Y[:, :N]
        u_f = Y[:, N:] / (0.5 * (rho + np.roll(rho, -1, axis=1)))
        u_c = 0.5 * (u_f + np.roll(u_f, 1, axis=1))
        mass = rho.sum(axis=1) * solver.dx
        c = np.fft.rfft(rho - rho0, axis=1) * (2.0 / N)
        amp = np.abs(rho - rho0).max(axis=1)
        M0 = mass[0]
        drift = float(np.abs(mass - M0).max() / M0)
        analytic = self.growth_analytic
        ds = xr.Dataset(
            {
                "rho": (("t", "x"), rho, {"long_name": "one-dimensional density ρ̄", "units": "sigma"}),
                "u": (("t", "x"), u_c, {"long_name": "mean velocity ū", "units": "sqrt(g sigma)"}),
                "mass": ("t", mass, {"long_name": "∫ ρ̄ dx", "units": "sigma^2"}),
                "amplitude": ("t", amp, {"long_name": "max |ρ̄ − ρ0|", "units": "sigma"}),
                "mode_amplitude": (
                    ("t", "mode"),
                    np.abs(c[:, 1 : n_modes + 1]),
                    {"long_name": "|ρ̂_n| (cosine amplitude of mode n)", "units": "sigma"},
                ),
                "growth_analytic": (
                    "mode",
                    analytic.real,
                    {"long_name": "Re α(k_n), 2×2 dispersion relation (1D model)"},
                ),
                "frequency_analytic": ("mode", analytic.imag, {"long_name": "Im α(k_n)"}),
            },
            coords={
                "t": ("t", t_used, {"long_name": "time", "units": "sqrt(sigma/g)"}),
                "x": (
                    "x",
                    solver.x,
                    {
                        "long_name": "position down the slope in the frame "
                        "moving at frame_speed, ξ = x − c t",
                        "units": "sigma",
                    },
                ),
                "mode": ("mode", self.modes),
                "k": ("mode", self.k, {"long_name": "wavenumber 2πn/L"}),
            },
        )
        ds["growth_discrete"] = (
            "mode",
            self.growth_discrete.real,
            {"long_name": "Re α of the linearised discrete system"},
        )
        ds.attrs.update(
            {
                "title": "1D model (Mitarai & Nakanishi §5.1.2): nonlinear density waves",
                "theta": rm.theta,
                **rm.model.attrs(),
                "rho0": rho0,
                "nu0": coef.F,
                "U0": coef.U,
                "length": solver.L,
                "n_cells": N,
                "dx": solver.dx,
                "rtol": self.rtol,
                "method": self.method,
                "initial_condition": info.initial.description,
                "frame_speed": self.frame_speed,
                "t_end": float(t_used[-1]),
                "auto_time": str(info.auto_time),
                "status": info.status,
                "left_family": info.left_family,
                "mass_drift": drift,
                "steps": info.steps,
                "rhs_evaluations": solver.n_rhs,
                "jacobian_evaluations": solver.n_jac,
                "wall_time_s": info.wall_time_s,
                "k_c": coef.k_c,
                "L_c": coef.L_c,
                "criterion_margin": coef.criterion_margin,
                "short_wave_unstable": str(coef.short_wave_unstable),
                "max_growth_rate": self.max_growth_rate,
                "rho_range_family": [lo, hi],
            }
        )
        return ds


def simulate(
    reduced: ReducedModel,
    length: float,
    *,
    rho0: float | None = None,
    nu0: float | None = None,
    n_cells: int | None = None,
    time: float | None = None,
    mode: int | None = None,
    amplitude: float = 1e-3,
    seed: int = 0,
    rtol: float = 1e-6,
    snapshots: int = 200,
    saturation_tol: float = 0.02,
    progress: Callable[[float, float], None] | None = None,
    max_steps: int = 200000,
    method: str = "Radau",
    on_exit: str = "raise",
    frame_speed="wave",
    trackers=(),
):
    """Integrate the 1D model in time from a perturbed uniform state; returns an xarray Dataset.

    A convenience wrapper of :class:`WaveSimulation` with a :class:`SnapshotTracker` of
    ``snapshots`` snapshots, a :class:`SaturationStop` when ``time`` is not given, a
    :class:`ProgressTracker` for ``progress`` and a :class:`LeaveFamilyStop` for
    ``on_exit="stop"``. The names are those of :func:`chuteflow.dns.simulate` (``time``,
    ``snapshots``, ``frame_speed``, ``progress``, ``trackers``).

    Parameters
    ----------
    reduced, length, rho0, nu0, n_cells, rtol, max_steps, method
        See :class:`WaveSimulation`.
    frame_speed : {"wave", "lab"} or float
        The frame of the run (``frame`` of :class:`WaveSimulation`).
    time : float, optional
        Final time (units √(σ/g)). Default: run until the wave amplitude saturates (changes
        by less than ``saturation_tol`` relative over the last 10 % of the run) or, for a
        stable state, until the perturbation has decayed by e⁻¹⁰; capped at 40 e-foldings
        of the fastest discrete mode.
    mode, amplitude, seed
        The initial perturbation, see :meth:`WaveSimulation.perturbed`.
    snapshots : int
        Snapshots stored (uniform in time).
    saturation_tol : float
        Relative amplitude change that counts as saturated.
    progress : callable, optional
        ``progress(t, t_end)`` after each time step.
    on_exit : {"raise", "stop"}
        What to do when the density leaves the steady family's range (the model is undefined
        there): raise :class:`NoSteadyFlowError`, or stop and return the run so far with
        ``status = "left_family"`` (the last snapshot is the last accepted state).
    trackers : sequence of Tracker
        More trackers (:mod:`chuteflow.trackers`), after the wrapper's own.

    Returns
    -------
    xarray.Dataset
        ``rho(t, x)`` (cell centres), ``u(t, x)`` (face velocities averaged to centres),
        ``mass(t)``, ``amplitude(t)`` (max|ρ − ρ0|), ``mode_amplitude(t, mode)``; attributes
        with the parameters, the linear theory of the uniform state (k_c, L_c, growth rates
        of the domain's modes: analytic and discrete), ``mass_drift`` (max relative change of
        the mass), ``status`` ("completed" at t_end, "saturated", "decayed" or
        "left_family"), steps and timing.

    Raises
    ------
    ParameterError
        Bad input.
    NoSteadyFlowError
        The density left the range of the steady family on which the model is defined.
    ConvergenceError
        The time integrator failed.
    """
    if on_exit not in ("raise", "stop"):
        raise ParameterError(f"on_exit = {on_exit!r}: choose 'raise' or 'stop'")
    if time is not None and not (math.isfinite(time) and time > 0):
        raise ParameterError(f"time = {time!r} must be a positive number")
    snaps = SnapshotTracker(count=snapshots)
    tracking: list[Tracker] = [snaps]
    if time is None:
        tracking.append(SaturationStop(saturation_tol, count=snapshots))
    if progress is not None:
        tracking.append(ProgressTracker(progress))
    if on_exit == "stop":
        tracking.append(LeaveFamilyStop())
    tracking.extend(trackers)
    sim = WaveSimulation(
        reduced,
        length,
        rho0=rho0,
        nu0=nu0,
        n_cells=n_cells,
        frame=frame_speed,
        rtol=rtol,
        method=method,
        max_steps=max_steps,
    )
    info = sim.run(sim.perturbed(mode, amplitude, seed), time, tracking)
    return sim.dataset(snaps, info)


def growth_rate_fit(ds, mode: int, t_max: float | None = None, factor: float = 10.0) -> tuple[float, float]:
    """Least-squares rate of ln |ρ̂_mode|(t) over the early, linear stage.

    The window runs from t = 0 until the amplitude has changed by ``factor`` from its
    initial value (or ``t_max``). Returns (rate, rms residual of the fit in ln amplitude).
    """
    A = ds["mode_amplitude"].sel(mode=mode).values
    t = ds["t"].values
    lnA = np.log(A)
    keep = np.abs(lnA - lnA[0]) <= math.log(factor)
    if t_max is not None:
        keep &= t <= t_max
    idx = np.nonzero(keep)[0]
    stop = idx[0]
    while stop + 1 < len(t) and keep[stop + 1]:
        stop += 1
    sel = slice(0, stop + 1)
    if stop < 3:
        raise ConvergenceError(
            f"growth_rate_fit: only {stop + 1} snapshots in the linear "
            "window; store more snapshots or shorten the time"
        )
    p = np.polyfit(t[sel], lnA[sel], 1)
    res = lnA[sel] - np.polyval(p, t[sel])
    return float(p[0]), float(np.sqrt(np.mean(res**2)))

"""Fourier (x) × Chebyshev (y) discretisation of the time-dependent equations.

Unknowns: the Fourier coefficients C[f, j, m] (field f ∈ (s = ln ν, u, v, T), Chebyshev node
y_j, mode m = 0 … M, k_m = 2π m / L) of the real fields
f(x, y_j) = C[f, j, 0] + 2 Re Σ_{m ≥ 1} C[f, j, m] e^{i k_m x}.
The residual is evaluated pointwise on a padded grid of ``nxp`` ≥ 3M + 1 points and projected
back onto m ≤ M (3/2 rule; by default the smallest FFT-friendly length, :func:`padded_points`).
Rows (the stability operator's choice, :mod:`chuteflow.stability.operator`):

========  ========================  ======================  ===============================
block     interior nodes            floor (y = 0)           top (y = y_max)
========  ========================  ======================  ===============================
s         mass (2.1) ÷ ν̄ (a)        y-momentum ÷ μ          mass (2.1) ÷ ν̄ (b)
u         x-momentum ÷ μ            eq. (2.9) ÷ μ           û_y + |k| û = 0 per mode
v         y-momentum ÷ μ            v = 0                   v̂_y + |k| v̂ = 0 per mode
T         energy (2.3) ÷ κ          eq. (2.10) ÷ κ          T̂_y + |k| T̂ = 0 per mode
========  ========================  ======================  ===============================

The top conditions are :func:`chuteflow.equations.far_field_conditions` (eq. (4.5)), mode by
mode for u, v, T.

(b) ``top="transport"`` (default): eq. (2.1) at the top node, with the density gradient of
the isothermal atmosphere above, ν_y = −(cos θ/T) ν, where the flow enters (v < 0); ``"isothermal"``:
the decay condition ν_y + (cos θ/T) ν = 0 itself, pointwise with the local T, ÷ ν (the
stability operator's row). Both are the same linear problem up to the O(ν(y_max)) coupling;
at finite amplitude the constraint over-determines ln ν where the flow leaves the domain
(docs/dns.md, *The dilute top*).

(a) The mass rows are projected onto the modes first and then divided by ν̄_j = exp(⟨s⟩(y_j))
(⟨·⟩ the x-average: ŝ_0 on the uniform grid),
plus a uniform source λ in mode 0 (:meth:`Discretisation.mass_source`), so that the total
mass is conserved at any amplitude (docs/dns.md, *Mass*).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import scipy.fft

from ..closures import ChuteModel
from ..equations import TOP_OF, compiled_equations
from ..errors import ParameterError
from ..spectral import ChebyshevGrid
from .residual import DNS_FIELDS, evaluate_residuals
from .xmap import TanMap

#: Unknown of each block (s = ln ν).
UNKNOWNS = ("s", "u", "v", "T")
#: Bulk equation of each block, and its floor row.
BULK_OF = {"nu": "mass", "u": "xmom", "v": "ymom", "T": "energy"}
FLOOR_OF = {"nu": "ymom", "u": "floor_x", "v": "floor_v", "T": "floor_energy"}
#: BDF coefficients (a0, a1, a2): ∂_t X ≈ (a0 X^{n+1} + a1 X^n + a2 X^{n−1}) / Δt.
BDF1 = (1.0, -1.0, 0.0)
BDF2 = (1.5, -2.0, 0.5)
#: Rows of s at the top node: eq. (2.1) with the vertical gradient of the isothermal
#: atmosphere where the flow enters (``"transport"``, the default), or the decay condition
#: ν_y + (cos θ/T) ν = 0 itself (``"isothermal"``, the stability operator's row).
TOPS = ("transport", "isothermal")


def padded_points(modes: int) -> int:
    """The default padded x grid of ``modes`` Fourier modes: the smallest length ≥ 3M + 1 (the
    3/2 rule) whose FFT is fast (factors 2, 3, 5). 3M + 1 itself is often prime (61 at
    nx = 41): there an inverse FFT of the twelve x-jets took 1.0 ms against 0.12 ms at 64
    (docs/dns.md, *Where a nonlinear step's time goes*)."""
    if not modes:
        return 1
    return max(scipy.fft.next_fast_len(3 * modes + 1, real=True), 4)


@dataclass(frozen=True, eq=False)
class Discretisation:
    """Grid and operators of one simulation: length ``L``, modes ``M``, ``N`` Chebyshev intervals.

    Attributes
    ----------
    theta : float
        Inclination (degrees).
    model : ChuteModel
        Closures and parameters.
    length : float
        Period L along the slope.
    y_max : float
        Top of the domain.
    n : int
        Chebyshev intervals N (N + 1 nodes).
    modes : int
        Highest Fourier mode M.
    nxp : int
        Points of the padded x grid (≥ 3M + 1; below that, :func:`padded_points`).
    frame : float
        Speed c of the frame ξ = x − c t the unknowns move with (velocities stay those in
        the floor's frame): ∂_t at fixed x is ∂_t − c ∂_ξ. With c near the wave speed the
        waves are nearly steady in ξ and BDF2's damping of fast phases (∝ (ωΔt)⁴) is small.
    x_map : TanMap or None
        A mapped x (:mod:`chuteflow.dns.xmap`): the Fourier modes are in s, the points of the
        padded grid at x = g(s_i), x-derivatives by the chain rule, the mass rows and the
        x-averages weighted by g', and the top conditions' |k| exactly as (1/g') |∂_s| (the
        tan map is a Möbius map of the circle, under which the Hilbert transform is
        invariant). None (default): the uniform grid. The residual, the mass and the
        preconditioners' coefficients (:func:`~chuteflow.dns.columns.jet_coefficients`) are
        mapped; :class:`~chuteflow.dns.simulation.DnsSimulation` goes to a map with
        ``x_map=True`` (:mod:`chuteflow.dns.remap`; docs/dns.md, *A grid that follows the
        front*).
    """

    theta: float
    model: ChuteModel
    length: float
    y_max: float
    n: int
    modes: int
    nxp: int = 0
    frame: float = 0.0
    top: str = "transport"
    x_map: TanMap | None = None
    grid: ChebyshevGrid = field(init=False, repr=False)

    def __post_init__(self):
        if self.top not in TOPS:
            raise ValueError(f"top = {self.top!r}: choose one of {TOPS}")
        if self.nxp < 3 * self.modes + 1:
            object.__setattr__(self, "nxp", padded_points(self.modes))
        object.__setattr__(self, "grid", ChebyshevGrid(self.n, 0.0, self.y_max))
        if self.x_map is not None and self.x_map.length != self.length:
            raise ParameterError(
                f"x_map: its period {self.x_map.length:g} must be the discretisation's length {self.length:g}"
            )

    # -- sizes and packing --------------------------------------------------------------
    @property
    def shape(self) -> tuple[int, int, int]:
        """Shape (4, N + 1, M + 1) of the coefficient array."""
        return (4, self.n + 1, self.modes + 1)

    @property
    def size(self) -> int:
        """Number of real unknowns."""
        return 4 * (self.n + 1) * (2 * self.modes + 1)

    @cached_property
    def k(self) -> np.ndarray:
        """Wavenumbers k_m = 2π m / L, m = 0 … M."""
        return 2.0 * math.pi * np.arange(self.modes + 1) / self.length

    @cached_property
    def s(self) -> np.ndarray:
        """Points of the padded grid in the computational coordinate (uniform)."""
        return np.arange(self.nxp) * self.length / self.nxp

    @cached_property
    def x(self) -> np.ndarray:
        """Points of the padded x grid (x = g(s) with a map)."""
        return self.s if self.x_map is None else self.x_map.x(self.s)

    @cached_property
    def x_weights(self) -> np.ndarray:
        """g'(s_i) on the padded grid, the weights of an x-average over the s points (ones on
        the uniform grid)."""
        return np.ones(self.nxp) if self.x_map is None else self.x_map.dx_ds(self.s)

    @cached_property
    def x_weight_modes(self) -> np.ndarray:
        """The modes m ≤ M of g' (1 in mode 0 only on the uniform grid)."""
        return self.to_modes(self.x_weights)

    def x_mean(self, f: np.ndarray) -> np.ndarray:
        """The x-average (1/L)∫ f dx of values on the padded grid (last axis)."""
        if self.x_map is None:
            return f.mean(axis=-1)
        return (f * self.x_weights).mean(axis=-1)

    @cached_property
    def sin_cos(self) -> tuple[float, float]:
        """(sin θ, cos θ)."""
        th = math.radians(self.theta)
        return math.sin(th), math.cos(th)

    def pack(self, C: np.ndarray) -> np.ndarray:
        """Coefficients (4, N+1, M+1) → real vector (real parts, then imaginary parts of m ≥ 1)."""
        return np.concatenate([C.real.ravel(), C[..., 1:].imag.ravel()])

    def unpack(self, z: np.ndarray) -> np.ndarray:
        """Inverse of :meth:`pack`."""
        n_re = 4 * (self.n + 1) * (self.modes + 1)
        C = z[:n_re].reshape(self.shape).astype(complex)
        C[..., 1:] += 1j * z[n_re:].reshape(4, self.n + 1, self.modes)
        return C

    # -- transforms ---------------------------------------------------------------------
    def to_physical(self, C: np.ndarray) -> np.ndarray:
        """Values on the padded grid (…, nxp) of coefficients (…, M + 1)."""
        full = np.zeros(C.shape[:-1] + (self.nxp // 2 + 1,), dtype=complex)
        full[..., : self.modes + 1] = C
        return scipy.fft.irfft(full, n=self.nxp, axis=-1, norm="forward")

    def to_modes(self, f: np.ndarray) -> np.ndarray:
        """Coefficients m ≤ M of values on the padded grid (projection)."""
        return scipy.fft.rfft(f, axis=-1, norm="forward")[..., : self.modes + 1]

    def coefficients_of(self, fields: dict[str, np.ndarray]) -> np.ndarray:
        """Coefficients of physical fields {"s", "u", "v", "T"} given on the padded grid."""
        return np.stack([self.to_modes(np.asarray(fields[f], dtype=float)) for f in UNKNOWNS])

    # -- jets ---------------------------------------------------------------------------
    def primitive_jets(self, C: np.ndarray) -> dict[str, np.ndarray]:
        """Values and x, y derivatives up to second order of s, u, v, T on the padded grid
        (keys ``"s"``, ``"s_x"``, ``"s_y"``, ``"s_xx"``, ``"s_xy"``, ``"s_yy"``, ``"u"``, …).
        One inverse FFT of the twelve x-jets and one product per y-derivative (the calls, not
        the arithmetic, are what a residual of a small grid costs)."""
        ik = 1j * self.k
        D, D2 = self.grid.D, self.grid.D2
        v = self.to_physical(np.stack((C, C * ik, C * ik**2)))  # (x-order, field, y, x)
        dv = D @ v[:2]  # ∂_y of the values and of their x-derivatives
        d2 = D2 @ v[0]
        if self.x_map is not None:
            # s-derivatives → x-derivatives: ∂_x = a ∂_s, ∂_xx = a² ∂_ss − (g''/g'³) ∂_s
            a, b = self.map_metric
            v = np.stack((v[0], a * v[1], a * a * v[2] + b * v[1]))
            dv = np.stack((dv[0], a * dv[1]))
        out = {}
        for i, f in enumerate(UNKNOWNS):
            out[f] = v[0, i]
            out[f + "_x"] = v[1, i]
            out[f + "_xx"] = v[2, i]
            out[f + "_y"] = dv[0, i]
            out[f + "_yy"] = d2[i]
            out[f + "_xy"] = dv[1, i]
        return out

    @staticmethod
    def state_jets(prim: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """The jets of :data:`chuteflow.dns.residual.JETS` (without ∂_t) from
        :meth:`primitive_jets`: ν = e^s and its derivatives by the chain rule."""
        out = dict(prim)
        s, sx, sy = out.pop("s"), out.pop("s_x"), out.pop("s_y")
        sxx, sxy, syy = out.pop("s_xx"), out.pop("s_xy"), out.pop("s_yy")
        nu = np.exp(s)
        out.update(
            nu=nu,
            nu_x=nu * sx,
            nu_y=nu * sy,
            nu_xx=nu * (sxx + sx * sx),
            nu_xy=nu * (sxy + sx * sy),
            nu_yy=nu * (syy + sy * sy),
        )
        return out

    def jets(self, C: np.ndarray) -> dict[str, np.ndarray]:
        """Every jet of :data:`chuteflow.dns.residual.JETS` except ∂_t, on the padded grid."""
        return self.state_jets(self.primitive_jets(C))

    # -- residual -----------------------------------------------------------------------
    def residual(self, C: np.ndarray, history: tuple, dt: float, bdf=BDF2) -> np.ndarray:
        """Scaled residual (4, N+1, M+1) of the implicit step to coefficients ``C``.

        ``history`` holds the physical fields (ν, u, v, T) on the padded grid at the previous
        one or two time levels (``(X^n, X^{n−1})``; X^{n−1} unused for BDF1).
        """
        st = self.jets(C)
        R = self.pointwise_rows(st, history, dt, bdf)
        nu = st["nu"]
        if self.top == "isothermal":
            out = self.to_modes(R)
            out[0, 1:-1] = self._mass_rows(C, R[0], nu, st["T"][-1], history, dt, bdf)
        else:
            out = self.to_modes(R)
            out[0, 1:] = self._mass_rows(C, R[0], nu, st["T"][-1], history, dt, bdf, top=True)
        top = self._top_terms
        for i, f in enumerate(UNKNOWNS[1:], start=1):
            acc = np.zeros(self.modes + 1, dtype=complex)
            for c, kpow, coef in top[f]:
                d = C[i, -1] if c == 0 else self._Dtop[c] @ C[i]
                acc += coef * self.abs_dx(d, kpow)
            out[i, -1] = acc
        return out

    def abs_dx(self, c: np.ndarray, power: int = 1) -> np.ndarray:
        """Coefficients of |∂_x|^power f for f of coefficients ``c`` (…, M + 1): |k_m|^power
        per mode; with a map (power 0 or 1) (1/g') |∂_s| f, projected — exact, because the
        tan map is a Möbius map of the circle (a dilation in the Cayley coordinate tan(πs/L)),
        under which the Hilbert transform H is invariant up to a constant, and
        |∂_x| = H ∂_x."""
        if self.x_map is None or power == 0:
            return self.k**power * c
        if power != 1:
            raise NotImplementedError(f"|∂_x|^{power} on a mapped grid")
        return self.to_modes(self.to_physical(self.k * c) * self.map_metric[0])

    def pointwise_rows(
        self, st: dict, history: tuple, dt: float, bdf=BDF2, inflow: np.ndarray | None = None
    ) -> np.ndarray:
        """The rows (4, N+1, points) of the residual at each point, before the projection.

        ``st`` holds the jets of :meth:`jets` (completed here by the upwind top density
        gradient and the ∂_t jets of the BDF formula), ``history`` the fields of the previous
        time levels on the same points. Bulk rows are scaled as in the module table; the
        mass rows are left unscaled (:meth:`residual` divides their modes by ν̄); the top
        rows of u, v, T are per-mode conditions and are not among these rows (their entries
        are the bulk equations there). ``inflow`` (where v(y_max) ≤ 0) fixes the upwind choice of
        :meth:`_upwind_top` (default: from ``st``), so that it can be differentiated.
        """
        if self.top == "transport":
            self._upwind_top(st, inflow)
        a0, a1, a2 = bdf
        now = (st["nu"], st["u"], st["v"], st["T"])
        for i, f in enumerate(DNS_FIELDS):
            val = a0 * now[i] + a1 * history[0][i]
            if a2:
                val = val + a2 * history[1][i]
            st[f + "_t"] = val / dt - self.frame * st[f + "_x"]
        res, part = evaluate_residuals(st, self.model, self.theta)
        mu, kap, nu = part["mu"][(0, 0)], part["kappa"][(0, 0)], st["nu"]
        R = np.empty((4,) + nu.shape)
        R[0] = res["mass"]
        R[1] = res["xmom"] / mu
        R[2] = res["ymom"] / mu
        R[3] = res["energy"] / kap
        R[0, 0] = res["ymom"][0] / mu[0]
        R[1, 0] = res["floor_x"][0] / mu[0]
        R[2, 0] = res["floor_v"][0]
        R[3, 0] = res["floor_energy"][0] / kap[0]
        if self.top == "isothermal":
            R[0, -1] = self._top_nu(st)
        return R

    def _upwind_top(self, st: dict, inflow: np.ndarray | None = None) -> None:
        """The vertical density gradient that eq. (2.1) sees at the top node (``top="transport"``).

        Eq. (2.1) is a transport equation for ln ν (no diffusion of mass), so the top needs a
        density only where the flow enters. Where it leaves (v > 0) the row uses the
        collocated ν_y (the interior's density is carried out); where it enters (v < 0) the
        gradient of the isothermal atmosphere above y_max, ν_y = −(cos θ/T) ν with the local T
        (the decay condition of eq. (4.5) as the state of the inflow). Linearised about the
        steady flow (v = 0) both give the linear problem's mass equation at the top node.
        Using the atmosphere's gradient everywhere was tried and dropped: at outflow it
        contradicts the interior, and the weakly nonlinear growth then changed with N
        (docs/dns.md, *The dilute top*).
        """
        nu, v, T = st["nu"][-1], st["v"][-1], st["T"][-1]
        enters = ~(v > 0) if inflow is None else inflow
        st["nu_y"][-1] = np.where(enters, -self.sin_cos[1] / T * nu, st["nu_y"][-1])

    def _mass_rows(
        self, C: np.ndarray, mass: np.ndarray, nu, T_top, history: tuple, dt: float, bdf, top: bool = False
    ):
        """Interior rows of eq. (2.1), mode by mode, projected before they are scaled.

        ``mass`` is the derived residual −(∂_t ν + ∇·(ν u)) at the padded points. Its modes
        m ≤ M are divided by ν̄_j = exp(⟨s⟩_j) only after the projection, so that the
        mode-0 row states ⟨∂_t ν⟩_j = −⟨∇·(νu)⟩_j for the x-mean itself (projecting the
        pointwise mass/ν, the s-equation, does not, and mass drifted ∝ amplitude²). The floor
        and top nodes carry boundary rows instead of eq. (2.1), the x-mean of the pointwise
        divergence integrates to the top flux only up to the collocation error, and the mass
        diagnostic includes the isothermal tail above y_max: :meth:`mass_source` returns what
        these leave, as a uniform relative source λ of the interior mode-0 rows, so that the
        total mass ∫∫ν dx dy (with the tail) changes by the Newton residual only.
        """
        nubar = self.mass_scale(C)
        # with a map the rows are g' times eq. (2.1): their mode 0 is the x-average
        modes = self.to_modes(mass if self.x_map is None else mass * self.x_weights)
        rows = modes / nubar[:, None]
        lam = self.mass_source(nubar, modes[:, 0].real, nu, T_top, history, dt, bdf)
        if self.x_map is None:
            rows[1:-1, 0] -= lam
        else:
            # the source uniform in x, as on the uniform grid: g' λ ν̄ in every mode
            rows[1:-1] -= lam * self.x_weight_modes
        return rows[1:] if top else rows[1:-1]

    def mass_scale(self, C: np.ndarray) -> np.ndarray:
        """ν̄_j = exp(⟨s⟩_j), the x-average of ln ν at each node (ŝ_0 on the uniform grid; on
        a mapped one the s-average is not the x-average), by which the mass rows are divided."""
        s0 = C[0, :, 0].real if self.x_map is None else self.x_mean(self.to_physical(C[0]))
        return np.exp(s0)

    @cached_property
    def map_metric(self) -> tuple[np.ndarray, np.ndarray]:
        """(a, b) = (1/g', −g''/g'³) on the padded grid: ∂_x = a ∂_s, ∂_xx = a² ∂_ss + b ∂_s
        (a = 1, b = 0 on the uniform grid)."""
        if self.x_map is None:
            return np.ones(self.nxp), np.zeros(self.nxp)
        gp = self.x_weights
        return 1.0 / gp, -np.asarray(self.x_map.d2x_ds2(self.s)) / gp**3

    def mass_source(self, nubar, mass0, nu, T_top, history: tuple, dt: float, bdf) -> float:
        """The uniform relative mass source λ of the interior mode-0 mass rows.

        With B_j = ⟨BDF(ν)⟩_j / Δt the discrete time derivative of the x-mean ν at node j
        (in the frame of the run), D_j = −⟨mass residual⟩_j − B_j its spatial part, τ the
        isothermal tail ν T / cos θ at y_max (:meth:`depth_integrals`) and w the
        Clenshaw–Curtis weights: λ = (w_0 B_0 + w_N B_N + ∂_t⟨τ⟩ − Σ_int w_j D_j) / Σ_int w_j ν̄_j.
        Then the interior rows B_j + D_j + λ ν̄_j = 0 give Σ_j w_j B_j + ∂_t⟨τ⟩ = 0. In the
        continuum limit λ → 0 (it is the boundary nodes' mass residual and the quadrature error
        of the divergence; see docs/dns.md for its size).
        """
        w = self.grid.weights
        a0, a1, a2 = bdf
        cos = self.sin_cos[1]
        B = a0 * nu + a1 * history[0][0]
        tau = a0 * nu[-1] * T_top + a1 * history[0][0][-1] * history[0][3][-1]
        if a2:
            B = B + a2 * history[1][0]
            tau = tau + a2 * history[1][0][-1] * history[1][3][-1]
        Bm = self.x_mean(B) / dt
        tail_t = float(self.x_mean(tau)) / (dt * cos)
        D = -mass0 - Bm
        defect = w[0] * Bm[0] + w[-1] * Bm[-1] + tail_t - w[1:-1] @ D[1:-1]
        return float(defect / (w[1:-1] @ nubar[1:-1]))

    @cached_property
    def _Dtop(self) -> dict[int, np.ndarray]:
        return {1: self.grid.D[-1], 2: self.grid.D2[-1]}

    @cached_property
    def _top_terms(self) -> dict[str, list]:
        """Terms (c, power of |k|, coefficient) of the top conditions on u, v, T (eq. 4.5)."""
        comp = compiled_equations()
        # the coefficients of these conditions are constants; any admissible state will do
        base = {b: np.full(1, 1e-3) for b in ("nu", "nu_y", "nu_yy", "u", "u_y", "u_yy", "T", "T_y", "T_yy")}
        part = self.model.evaluate(base["nu"], base["T"])
        out = {}
        for f in ("u", "v", "T"):
            ce = comp[TOP_OF[f]]
            _, coefs = ce.evaluate(base, part, *self.sin_cos)
            terms = []
            for t, cf in zip(ce.terms, coefs):
                if t.field != f or t.a or t.b or t.d:
                    raise NotImplementedError(f"top condition of {f}: unexpected term {t}")
                terms.append((t.c, t.k, float(np.ravel(cf)[0])))
            out[f] = terms
        return out

    def _top_nu(self, st: dict) -> np.ndarray:
        """ν's top condition (eq. (4.5), density decay) at the local state, divided by ν."""
        ce = compiled_equations()["top_nu"]
        base = {
            "nu": st["nu"][-1],
            "nu_y": st["nu_y"][-1],
            "nu_yy": st["nu_yy"][-1],
            "u": st["u"][-1],
            "u_y": st["u_y"][-1],
            "u_yy": st["u_yy"][-1],
            "T": st["T"][-1],
            "T_y": st["T_y"][-1],
            "T_yy": st["T_yy"][-1],
        }
        part = self.model.evaluate(base["nu"], base["T"])
        _, coefs = ce.evaluate(base, part, *self.sin_cos)
        acc = np.zeros_like(base["nu"])
        jets = {0: base["nu"], 1: base["nu_y"], 2: base["nu_yy"]}
        for t, cf in zip(ce.terms, coefs):
            if t.field != "nu" or t.a or t.b or t.d or t.k:
                raise NotImplementedError(f"top condition of ν: unexpected term {t}")
            acc = acc + cf * jets[t.c]
        return acc / base["nu"]

    # -- preconditioner -----------------------------------------------------------------
    def linear_blocks(self, C: np.ndarray) -> dict:
        """The linearisation about the x-averaged state of ``C`` (mode 0), per power of ik.

        Built from the compiled coefficients of :func:`chuteflow.equations.compiled_equations`
        (those of the stability operator), in this discretisation's unknowns (ŝ = ν̂/ν̄) and
        row scaling. Returns ``{"pieces": {b: matrix}, "K": matrix, "Bt": matrix}`` with the
        Jacobian of mode m ``Σ_b (ik_m)^b pieces[b] + |k_m| K + (a0/Δt) Bt``.
        """
        g = self.grid
        m = self.n + 1
        # the x-independent state of mode 0; ν jets from s jets as in :meth:`jets`
        sb, ub, Tb = (C[i, :, 0].real for i in (0, 1, 3))
        nu = np.exp(sb)
        sy, syy = g.D @ sb, g.D2 @ sb
        base = {
            "nu": nu,
            "nu_y": nu * sy,
            "nu_yy": nu * (syy + sy * sy),
            "u": ub,
            "u_y": g.D @ ub,
            "u_yy": g.D2 @ ub,
            "T": Tb,
            "T_y": g.D @ Tb,
            "T_yy": g.D2 @ Tb,
        }
        mean = {"T": Tb}
        part = self.model.evaluate(nu, mean["T"])
        mu, kap = part["mu"][(0, 0)], part["kappa"][(0, 0)]
        eqs = compiled_equations()
        eye = np.eye(m)
        dmat = (eye, g.D, g.D2)
        # ν̂ = ν̄ ŝ with ν̂_y = ν̄ (ŝ_y + s̄_y ŝ), ν̂_yy = ν̄ (ŝ_yy + 2 s̄_y ŝ_y + (s̄_yy + s̄_y²) ŝ)
        dnu = (
            nu[:, None] * eye,
            nu[:, None] * (g.D + np.diag(sy)),
            nu[:, None] * (g.D2 + 2 * sy[:, None] * g.D + np.diag(syy + sy * sy)),
        )
        M4 = 4 * m
        col = {f: slice(i * m, (i + 1) * m) for i, f in enumerate(DNS_FIELDS)}
        pieces: dict[int, np.ndarray] = {0: np.zeros((M4, M4))}
        K = np.zeros((M4, M4))
        Bt = np.zeros((M4, M4))
        cache: dict[str, list] = {}

        def coefs(name):
            if name not in cache:
                _, cs = eqs[name].evaluate(base, part, *self.sin_cos)
                cache[name] = [np.broadcast_to(np.asarray(c, dtype=float), (m,)) for c in cs]
            return cache[name]

        def add(name, nodes, scale, rows, keep_t):
            for t, cf in zip(eqs[name].terms, coefs(name)):
                if t.field not in col or t.d:
                    continue
                op = dnu if t.field == "nu" else dmat
                blk = (cf[nodes] * scale)[:, None] * op[t.c][nodes]
                if t.a:
                    if keep_t:
                        Bt[rows, col[t.field]] += blk
                    continue
                if t.k:
                    K[rows, col[t.field]] += blk
                    continue
                pieces.setdefault(t.b, np.zeros((M4, M4)))[rows, col[t.field]] += blk

        bulk_scale = {"mass": 1.0 / nu, "xmom": 1.0 / mu, "ymom": 1.0 / mu, "energy": 1.0 / kap}
        floor_scale = {
            "ymom": 1.0 / mu[0],
            "floor_x": 1.0 / mu[0],
            "floor_v": 1.0,
            "floor_energy": 1.0 / kap[0],
        }
        inner = slice(1, m - 1)
        for i, f in enumerate(DNS_FIELDS):
            r0 = i * m
            name = BULK_OF[f]
            add(name, inner, bulk_scale[name][inner], slice(r0 + 1, r0 + m - 1), True)
            name = FLOOR_OF[f]
            add(name, slice(0, 1), floor_scale[name], slice(r0, r0 + 1), False)
            top = slice(m - 1, m)
            if f == "nu" and self.top == "transport":
                # eq. (2.1) at the top node (v̄ = 0 in the linear phase: no ŝ_y term)
                add("mass", top, bulk_scale["mass"][top], slice(r0 + m - 1, r0 + m), True)
                continue
            add(TOP_OF[f], top, 1.0 / nu[-1] if f == "nu" else 1.0, slice(r0 + m - 1, r0 + m), False)
        if self.top == "isothermal":
            # the density top condition holds with the local T (a linear condition of the
            # linear problem with T0 frozen): its T derivative, by central differences of
            # the compiled condition, completes the Jacobian's top row of ŝ
            h = 1e-6 * float(base["T"][-1])
            hi = {**base, "T": base["T"] + h}
            lo = {**base, "T": base["T"] - h}
            pieces[0][m - 1, 3 * m + m - 1] += float(self._top_nu(hi) - self._top_nu(lo)) / (2 * h)
        return {"pieces": pieces, "K": K, "Bt": Bt}

    def factorise(self, blocks: dict, dt: float, a0: float) -> np.ndarray:
        """Inverses (M + 1, 4(N+1), 4(N+1)) of the Jacobian of each mode m = 0 … M
        (:meth:`linear_blocks`), computed in one batched LAPACK call; applied by one batched
        product in :meth:`precondition` (much cheaper than M + 1 triangular solves)."""
        k = self.k
        J = (
            blocks["K"][None] * np.abs(k)[:, None, None]
            + blocks["Bt"][None] * (a0 / dt - self.frame * 1j * k)[:, None, None]
        )
        for b, P in blocks["pieces"].items():
            J = J + ((1j * k) ** b)[:, None, None] * P[None]
        return np.linalg.inv(J)

    def precondition(self, inverses: np.ndarray, R: np.ndarray) -> np.ndarray:
        """Apply the block-diagonal inverse: mode by mode, (J_m)⁻¹ R_m."""
        m = self.n + 1
        r = np.moveaxis(R.reshape(4 * m, self.modes + 1), -1, 0)[..., None]
        sol = np.matmul(inverses, r)[..., 0]
        out = np.moveaxis(sol, 0, -1).reshape(R.shape)
        out[:, :, 0] = out[:, :, 0].real
        return out

    def total_mass(self, nu: np.ndarray, T_top: np.ndarray) -> float:
        """Mass per unit length ⟨∫ν dy⟩ + ⟨ν(y_max) T(y_max)⟩/cos θ of ν, T on the padded grid
        (the x-mean of :meth:`depth_integrals`' ρ̄)."""
        return float(self.grid.weights @ self.x_mean(nu) + self.x_mean(nu[-1] * T_top) / self.sin_cos[1])

    # -- diagnostics --------------------------------------------------------------------
    def depth_integrals(self, C: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """ρ̄(x) = ∫ν dy and Q(x) = ∫νu dy on the padded grid (at :attr:`x`), with the
        isothermal tail above y_max (ν(y_max) T(y_max)/cos θ, and u(y_max) times it)."""
        s = self.to_physical(C[0])
        u = self.to_physical(C[1])
        T = self.to_physical(C[3])
        nu = np.exp(s)
        w = self.grid.weights
        tail = nu[-1] * T[-1] / self.sin_cos[1]
        return w @ nu + tail, w @ (nu * u) + tail * u[-1]

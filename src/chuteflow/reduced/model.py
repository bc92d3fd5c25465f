"""The reduced one-dimensional model of §5.1.2 (eqs (5.10), (5.11)) and its linear theory.

Integrating the equations over the depth and closing them with the steady family at fixed θ
gives, for the one-dimensional density ρ̄(x, t) and mean velocity ū(x, t),

    ∂t ρ̄ + ∂x(ρ̄ ū) = 0,
    ρ̄ (∂t ū + ū ∂x ū) = a(ρ̄) [U(ρ̄) − ū] − ∂x(ρ̄ T̄(ρ̄)) + ∂x(μ̄(ρ̄) ∂x ū),        (eq. 5.10)

with a(ρ̄) = η*(F(ρ̄), T̄(ρ̄)), U(ρ̄) = ρ̄ sin θ / a(ρ̄) (eq. 5.11) and
μ̄ = (4/3) f2(0) H(T̄) √T̄, H = T̄ / cos θ. F(ρ̄) is the floor density ν0(0) and T̄(ρ̄) the
density-weighted mean temperature of the steady flow whose ρ̄0 is ρ̄.

:class:`LocalCoefficients` holds these functions and their first derivatives at one uniform
state ρ0 and gives the analytic linear theory: the exact 2×2 dispersion relation, the
instability condition (eq. (5.12), with the correction of docs/errata.md, item 4: the viscous
term is μ̄ k²/ρ0), the k → 0 criterion (eq. (5.13)) and the long-wave expansion
(eq. (5.14)). :func:`local_coefficients` computes them exactly at one steady flow from the
family tangent; :class:`ReducedModel` holds F, T̄, a as smooth functions of ρ̄ over the whole
family (piecewise Hermite cubics through solved flows, with exact slopes from the tangent)
with their interpolation error measured against direct solves.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import CubicHermiteSpline

from .._memory import brentq
from ..closures import ChuteModel
from ..conventions import long_wave_phase_velocity
from ..errors import ConvergenceError, NoSteadyFlowError, ParameterError
from ..steady import SteadyFlow, solve_steady, steady_tangent
from . import equations as eq

__all__ = ["LocalCoefficients", "local_coefficients", "ReducedModel", "reduced_model", "mu_bar_prefactor"]


def _f2_0(model: ChuteModel) -> float:
    return float(model.f(0.0)["f2"][0])


def mu_bar_prefactor(theta: float, model: ChuteModel) -> float:
    """(4/3) f2(0) / cos θ, so that μ̄ = prefactor · T̄^{3/2} (§5.1.2, approximation iii).

    The value of the viscosity closure :data:`chuteflow.reduced.equations.VISCOSITY` at T̄ = 1.
    """
    return float(eq.viscosity(1.0, 0.0, theta, _f2_0(model))[0])


@dataclass(frozen=True)
class LocalCoefficients:
    """The 1D model's functions and their ρ̄-derivatives at one uniform state ρ̄ = ρ0.

    Primes are d/dρ̄ along the steady family at fixed θ. All quantities are dimensionless
    (σ, ρ_p σ³, √(σ/g)).

    Attributes
    ----------
    theta : float
        Inclination θ in degrees.
    rho0 : float
        One-dimensional density ρ0 = ρ̄0 = ∫ ν0 dy.
    F, dF : float
        Floor density F(ρ0) = ν0(0) and F'(ρ0).
    Tbar, dTbar : float
        Mean temperature T̄(ρ0) and T̄'(ρ0).
    a, da : float
        Floor drag coefficient a = η*(F, T̄) (eq. (5.11)) and a'.
    mu_bar, dmu_bar : float
        Effective viscosity μ̄ = (4/3) f2(0) T̄^{3/2}/cos θ and μ̄'.
    """

    theta: float
    rho0: float
    F: float
    dF: float
    Tbar: float
    dTbar: float
    a: float
    da: float
    mu_bar: float
    dmu_bar: float

    # -- the uniform state, derived from the statement (:mod:`.equations`) ----------------
    @property
    def sin_theta(self) -> float:
        return math.sin(math.radians(self.theta))

    @functools.cached_property
    def _uniform(self) -> eq.UniformState:
        return eq.uniform_state(self.rho0, self.sin_theta, self)

    @property
    def U(self) -> float:
        """U(ρ0) = ρ0 sin θ / a (eq. 5.11): the uniform flow velocity, S(ρ0, U) = 0."""
        return float(self._uniform.U)

    @property
    def dU(self) -> float:
        """U'(ρ0) = sin θ / a − ρ0 sin θ a'/a²."""
        return float(self._uniform.dU)

    @property
    def P(self) -> float:
        """Depth-integrated dilute pressure ρ0 T̄(ρ0)."""
        return float(self._uniform.P)

    @property
    def dP(self) -> float:
        """(ρ0 T̄)' = T̄ + ρ0 T̄'. Negative means the pressure term amplifies density bumps."""
        return float(self._uniform.dP)

    @property
    def q0(self) -> float:
        """Flux of the uniform state q0 = ρ0 U(ρ0)."""
        return float(self._uniform.q0)

    @property
    def dq0(self) -> float:
        """dq0/dρ0 = U + ρ0 U'."""
        return float(self._uniform.dq0)

    # -- long waves (eqs 5.13, 5.14) ---------------------------------------------
    @property
    def criterion_margin(self) -> float:
        """(ρ0 U')² − (ρ0 T̄)' (eq. (5.13)): positive means long-wave unstable."""
        return (self.rho0 * self.dU) ** 2 - self.dP

    @property
    def unstable(self) -> bool:
        """Long-wave instability, criterion (ρ0 U')² > (ρ0 T̄)'."""
        return self.criterion_margin > 0.0

    @property
    def alpha1(self) -> complex:
        """α1 of α = α1 k + α2 k² + O(k³) (eq. 5.14): −i dq0/dρ0."""
        return -1j * self.dq0

    @property
    def alpha2(self) -> float:
        """α2 = (ρ0/a) [(ρ0 U')² − (ρ0 T̄)'] (eq. 5.14); real."""
        return self.rho0 / self.a * self.criterion_margin

    @property
    def phase_velocity(self) -> float:
        """Long-wave phase velocity c = −Im α / k → dq0/dρ0 (> 0: the wave travels down
        the slope; the one convention of :mod:`chuteflow.conventions`)."""
        return long_wave_phase_velocity(self.alpha1)

    @property
    def short_wave_unstable(self) -> bool:
        """True when (ρ0 T̄)' < 0: every wavenumber grows, up to the rate ρ0|(ρ0T̄)'|/μ̄.

        The effective pressure then sharpens density bumps instead of spreading them and
        nothing in the model (no ∂x² ρ̄ term) stops the shortest waves: there is no k_c.
        """
        return self.dP < 0.0

    # -- exact linear theory of the 1D model -------------------------------------------
    def matrix(self, k) -> np.ndarray:
        """Linearised 1D model about (ρ0, U(ρ0)) for exp(αt + ikx): α (ρ̂, û) = M(k) (ρ̂, û).

        Derived from the statement of the model (:func:`.equations.linear_matrix`). Returns an
        array of shape ``k.shape + (2, 2)``.
        """
        return eq.linear_matrix(k, self.rho0, self.U, self.sin_theta, self)

    def dispersion(self, k) -> np.ndarray:
        """Both growth rates α(k) of the linearised model, least stable first.

        Closed form of the eigenvalues of :meth:`matrix`: α = −ikU + λ with
        λ² + bλ + c = 0, b = (a + μ̄k²)/ρ0, c = ik a U' + k² (ρ0T̄)'
        (:func:`.equations.dispersion_coefficients`). Shape ``k.shape + (2,)``.
        """
        k = np.asarray(k, dtype=float)
        b, c = eq.dispersion_coefficients(k, self.rho0, self.U, self.sin_theta, self)
        disc = np.sqrt(b * b - 4.0 * c + 0j)
        # the root −b/2 + disc/2 suffers cancellation for small k: use c = λ1 λ2
        lam2 = -0.5 * (b + disc)
        lam1 = np.where(np.abs(lam2) > 0, c / np.where(lam2 == 0, 1.0, lam2), -0.5 * (b - disc))
        out = np.stack([lam1, lam2], axis=-1) - 1j * k[..., None] * self.U
        swap = out[..., 1].real > out[..., 0].real
        out[swap] = out[swap][:, ::-1]
        return out

    def growth_rate(self, k) -> np.ndarray:
        """Re α(k) of the least stable branch."""
        return self.dispersion(k)[..., 0].real

    def condition(self, k, *, errata: bool = True) -> np.ndarray:
        """Instability condition (eq. (5.12)) at wavenumbers ``k``.

        ``(a U')² k² > ((a + μ̄ k²)/ρ0)² (ρ0 T̄)' k²`` (docs/errata.md, item 4: the paper prints
        (a/ρ0 + μ̄k²)²; only its O(k⁴) part differs). ``errata=False`` evaluates the printed
        form, for comparison.
        """
        k = np.asarray(k, dtype=float)
        if errata:
            damp = (self.a + self.mu_bar * k**2) / self.rho0
        else:
            damp = self.a / self.rho0 + self.mu_bar * k**2
        return (self.a * self.dU) ** 2 * k**2 > damp**2 * self.dP * k**2

    @property
    def k_c(self) -> float:
        """Critical wavenumber: waves with k < k_c grow (eq. (5.12), errata-corrected).

        0 when the flow is long-wave stable; ``inf`` when (ρ0T̄)' ≤ 0 and every k grows.
        """
        if not self.unstable:
            return 0.0
        if self.dP <= 0.0:
            return math.inf
        ratio = self.rho0 * abs(self.dU) / math.sqrt(self.dP)
        return math.sqrt(self.a * (ratio - 1.0) / self.mu_bar)

    @property
    def L_c(self) -> float:
        """Critical length 2π/k_c: the shortest periodic domain on which a wave can grow."""
        kc = self.k_c
        if kc == 0.0:
            return math.inf
        return 2.0 * math.pi / kc

    def most_unstable(self) -> tuple[float, float]:
        """(k_max, Re α(k_max)) of the fastest-growing wave; (nan, ≤0) when stable.

        For short-wave unstable states the rate increases towards its k → ∞ limit
        ρ0 |(ρ0T̄)'| / μ̄, returned with k_max = inf.
        """
        if not self.unstable:
            return math.nan, 0.0
        if self.short_wave_unstable:
            return math.inf, self.rho0 * abs(self.dP) / self.mu_bar
        from scipy.optimize import minimize_scalar

        kc = self.k_c
        res = minimize_scalar(
            lambda x: -float(self.growth_rate(x * kc)),
            bounds=(1e-6, 1.0),
            method="bounded",
            options={"xatol": 1e-10},
        )
        return float(res.x * kc), float(-res.fun)

    def to_dict(self) -> dict:
        """JSON-ready dict of the coefficients and the linear theory."""
        kmax, smax = self.most_unstable()
        d = {
            k: float(getattr(self, k))
            for k in (
                "theta",
                "rho0",
                "F",
                "dF",
                "Tbar",
                "dTbar",
                "a",
                "da",
                "U",
                "dU",
                "P",
                "dP",
                "mu_bar",
                "q0",
                "dq0",
                "criterion_margin",
                "alpha2",
                "phase_velocity",
                "k_c",
                "L_c",
            )
        }
        d.update(
            unstable=bool(self.unstable),
            short_wave_unstable=bool(self.short_wave_unstable),
            k_max=kmax,
            growth_max=smax,
        )
        return d


def local_coefficients(flow: SteadyFlow, tangent: dict | None = None) -> LocalCoefficients:
    """The 1D-model coefficients at the uniform state ρ0 = ρ̄0 of one steady flow, exactly.

    F' = 1/(dρ̄0/dβ) and T̄' = (dT̄0/dβ)/(dρ̄0/dβ) come from the exact family tangent
    (:func:`chuteflow.steady.steady_tangent`, β = ν0(0)); a' from the chain rule through
    η*(ν, T) (eq. (2.13)). No finite differences between solved flows.
    """
    tangent = tangent if tangent is not None else steady_tangent(flow)
    model = flow.model
    drho = float(tangent["drho_bar"])
    if not drho > 0.0:
        raise NoSteadyFlowError(
            f"rho_bar does not increase with nu0 at theta = {flow.theta:g}, nu0 = {flow.nu0:g} "
            f"(d rho_bar/d nu0 = {drho:.3g}): F(rho_bar) is not single-valued here, so the "
            "1D model (§5.1.2) is undefined"
        )
    beta, T = flow.nu0, flow.T_mean
    dT = float(tangent["dT_mean"]) / drho
    eta = model.evaluate(beta, T)["eta_star"]
    a = float(eta[(0, 0)])
    dF = 1.0 / drho
    da = float(eta[(1, 0)]) * dF + float(eta[(0, 1)]) * dT
    mu, dmu = eq.viscosity(T, dT, flow.theta, _f2_0(model))
    return LocalCoefficients(
        theta=flow.theta,
        rho0=flow.rho_bar,
        F=beta,
        dF=dF,
        Tbar=T,
        dTbar=dT,
        a=a,
        da=da,
        mu_bar=float(mu),
        dmu_bar=float(dmu),
    )


# ---------------------------------------------------------------------------------------
# The family as smooth functions of ρ̄
# ---------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Knot:
    flow: SteadyFlow
    coef: LocalCoefficients


@dataclass(frozen=True, eq=False)
class ReducedModel:
    """F(ρ̄), T̄(ρ̄), a(ρ̄), U(ρ̄), μ̄(ρ̄) of the 1D model over a steady family at fixed θ.

    ln F, ln T̄ and ln a are piecewise cubic Hermite interpolants in ρ̄ through solved steady
    flows (the knots), with exact slopes from the family tangent; so the functions and their
    first derivatives are continuous and accurate to O(Δρ̄⁴) and O(Δρ̄³).

    Attributes
    ----------
    theta : float
        Inclination θ (degrees).
    model : ChuteModel
        Closure parameters.
    rho, nu0 : ndarray
        Knots: ρ̄0 of the solved flows and their floor densities ν0(0) = F(ρ̄0).
    coefficients_at_knots : tuple of LocalCoefficients
        Exact coefficients at the knots.
    flux, h, nu_mean, monotonic : ndarray
        The full model's Q0 (eq. (3.15)), thickness, mean density and monotonicity of the
        steady flows at the knots (q0 = ρ̄U(ρ̄) of the 1D model is not Q0: §5.1.2, footnote).
    accuracy : dict
        Largest relative error of F, T̄, a (``F``, ``Tbar``, ``a``) and of their ρ̄-slopes
        (``dF``, ``dTbar``, ``da``) at the midpoints ν0 = (ν0_i + ν0_{i+1})/2 between knots,
        against direct steady solves there; ``midpoints`` is how many were checked.
    ends : tuple of str
        Why the family stops at its low and high ends (the message of the last failure, or
        the requested bound).
    """

    theta: float
    model: ChuteModel
    rho: np.ndarray = field(repr=False)
    nu0: np.ndarray = field(repr=False)
    coefficients_at_knots: tuple = field(repr=False)
    flux: np.ndarray | None = field(default=None, repr=False)
    h: np.ndarray | None = field(default=None, repr=False)
    nu_mean: np.ndarray | None = field(default=None, repr=False)
    monotonic: np.ndarray | None = field(default=None, repr=False)
    accuracy: dict = field(default_factory=dict)
    ends: tuple = ("", "")
    _splines: dict = field(default_factory=dict, repr=False, compare=False)

    @property
    def rho_range(self) -> tuple[float, float]:
        return float(self.rho[0]), float(self.rho[-1])

    @property
    def mu_prefactor(self) -> float:
        return mu_bar_prefactor(self.theta, self.model)

    def _check(self, rho) -> np.ndarray:
        rho = np.asarray(rho, dtype=float)
        lo, hi = self.rho_range
        if rho.size and (
            not np.isfinite(rho).all() or rho.min() < lo * (1 - 1e-12) or rho.max() > hi * (1 + 1e-12)
        ):
            bad = rho[~np.isfinite(rho) | (rho < lo) | (rho > hi)]
            raise NoSteadyFlowError(
                f"rho_bar = {float(bad.flat[0]):.4g} is outside [{lo:.4g}, {hi:.4g}], the range "
                f"of the steady family at theta = {self.theta:g} deg (roughness = "
                f"{self.model.roughness:g}) on which F and T̄ of the 1D model are defined "
                f"(family ends: {self.ends[0]} / {self.ends[1]})"
            )
        return rho

    def _eval(self, name, rho, nu):
        rho = self._check(rho)
        s = self._splines[name]
        g = np.exp(s(rho))
        if nu == 0:
            return g
        if nu == 1:
            return g * s(rho, 1)
        if nu == 2:
            d1, d2 = s(rho, 1), s(rho, 2)
            return g * (d2 + d1 * d1)
        raise ValueError("nu: derivative order 0, 1 or 2")

    def F(self, rho, nu: int = 0):
        """Floor density F(ρ̄) = ν0(0) (or its ``nu``-th derivative)."""
        return self._eval("F", rho, nu)

    def Tbar(self, rho, nu: int = 0):
        """Mean temperature T̄(ρ̄) (or its ``nu``-th derivative)."""
        return self._eval("Tbar", rho, nu)

    def a(self, rho, nu: int = 0):
        """Floor drag a(ρ̄) = η*(F(ρ̄), T̄(ρ̄)) (eq. (5.11)), or a derivative."""
        return self._eval("a", rho, nu)

    @functools.cached_property
    def f2_0(self) -> float:
        """f2(0) of the closure (Table 1), the constant of the viscosity closure μ̄."""
        return _f2_0(self.model)

    @property
    def sin_theta(self) -> float:
        return math.sin(math.radians(self.theta))

    def closure(self, rho) -> eq.ClosureValues:
        """T̄, a, μ̄ and their ρ̄-slopes at ``rho`` (values for :mod:`chuteflow.reduced.equations`)."""
        T, dT = self.Tbar(rho), self.Tbar(rho, 1)
        mu, dmu = eq.viscosity(T, dT, self.theta, self.f2_0)
        return eq.ClosureValues(Tbar=T, dTbar=dT, a=self.a(rho), da=self.a(rho, 1), mu_bar=mu, dmu_bar=dmu)

    def _uniform(self, rho, nu, name):
        if nu not in (0, 1):
            raise ValueError("nu: derivative order 0 or 1")
        rho = np.asarray(rho, dtype=float)
        st = eq.uniform_state(rho, self.sin_theta, self.closure(rho))
        return getattr(st, ("d" if nu else "") + name)

    def U(self, rho, nu: int = 0):
        """U(ρ̄) = ρ̄ sin θ / a(ρ̄) (eq. 5.11), or its first derivative."""
        return self._uniform(rho, nu, "U")

    def P(self, rho, nu: int = 0):
        """Depth-integrated pressure ρ̄ T̄(ρ̄), or its first derivative."""
        return self._uniform(rho, nu, "P")

    def mu_bar(self, rho, nu: int = 0):
        """μ̄(ρ̄) = (4/3) f2(0) H(T̄) √T̄, H = T̄/cos θ, or its first derivative."""
        if nu not in (0, 1):
            raise ValueError("nu: derivative order 0 or 1")
        c = self.closure(rho)
        return c.dmu_bar if nu else c.mu_bar

    def coefficients(self, rho0: float) -> LocalCoefficients:
        """:class:`LocalCoefficients` at ρ0 from the interpolants."""
        r = float(self._check(rho0))
        c = self.closure(r)
        return LocalCoefficients(
            theta=self.theta,
            rho0=r,
            F=float(self.F(r)),
            dF=float(self.F(r, 1)),
            Tbar=float(c.Tbar),
            dTbar=float(c.dTbar),
            a=float(c.a),
            da=float(c.da),
            mu_bar=float(c.mu_bar),
            dmu_bar=float(c.dmu_bar),
        )

    def rho_at_nu0(self, nu0: float) -> float:
        """ρ̄0 of the steady flow with floor density ``nu0`` (inverse of F).

        Exact at the knots (solved flows); between knots the root of F(ρ̄) = ν0 on the
        bracketing interval.
        """
        lo, hi = self.nu0[0], self.nu0[-1]
        if not lo <= nu0 <= hi:
            raise ParameterError(
                f"nu0 = {nu0:g} is outside [{lo:.4g}, {hi:.4g}], the floor "
                f"densities of the steady family at theta = {self.theta:g} deg"
            )
        hit = np.flatnonzero(self.nu0 == nu0)
        if hit.size:  # a knot, e.g. an end of the family: F(ρ̄) − ν0 is round-off there
            return float(self.rho[hit[0]])
        i = int(np.clip(np.searchsorted(self.nu0, nu0), 1, len(self.nu0) - 1))
        ra, rb = float(self.rho[i - 1]), float(self.rho[i])
        fa, fb = float(self.F(ra)) - nu0, float(self.F(rb)) - nu0
        if fa * fb > 0:  # within round-off of a knot (exp ∘ log of the interpolant)
            return ra if abs(fa) <= abs(fb) else rb
        return float(brentq(lambda r: float(self.F(r)) - nu0, ra, rb, xtol=1e-15, rtol=1e-14))

    def table(self, n: int = 200):
        """The functions on ``n`` points of the ρ̄ range and the criterion there, as xarray."""
        import xarray as xr

        r = np.linspace(*self.rho_range, n)
        cs = [self.coefficients(x) for x in r]
        data = {
            "F": (self.F(r), "floor density ν0(0) = F(ρ̄)"),
            "Tbar": (self.Tbar(r), "mean temperature T̄(ρ̄)"),
            "a": (self.a(r), "floor drag a(ρ̄) = η*(F, T̄)"),
            "U": (self.U(r), "velocity U(ρ̄) = ρ̄ sinθ / a"),
            "q": (r * self.U(r), "flux q0 = ρ̄ U(ρ̄)"),
            "dU": (self.U(r, 1), "U'(ρ̄)"),
            "dP": (self.P(r, 1), "(ρ̄ T̄)'"),
            "mu_bar": (self.mu_bar(r), "viscosity μ̄(ρ̄)"),
            "criterion_margin": (
                np.array([c.criterion_margin for c in cs]),
                "(ρ̄ U')² − (ρ̄ T̄)' (eq. (5.13); > 0 unstable)",
            ),
            "alpha2": (np.array([c.alpha2 for c in cs]), "α2 (eq. 5.14)"),
            "k_c": (np.array([c.k_c for c in cs]), "critical wavenumber k_c"),
        }
        ds = xr.Dataset(
            {k: ("rho", v, {"long_name": n_}) for k, (v, n_) in data.items()},
            coords={"rho": ("rho", r, {"long_name": "one-dimensional density ρ̄", "units": "sigma"})},
        )
        ds.attrs.update(
            theta=self.theta,
            **self.model.attrs(),
            **{f"accuracy_{k}": float(v) for k, v in self.accuracy.items()},
        )
        return ds

    def to_dict(self) -> dict:
        return {
            "theta": self.theta,
            "roughness": self.model.roughness,
            "rho_range": list(self.rho_range),
            "nu0_range": [float(self.nu0[0]), float(self.nu0[-1])],
            "knots": int(len(self.rho)),
            "accuracy": dict(self.accuracy),
            "ends": list(self.ends),
        }


def _solve(theta, nu0, model, guess, nu_top, cold_retry=True):
    try:
        return solve_steady(theta, nu0, model, guess=guess, nu_top=nu_top, strict=True)
    except (NoSteadyFlowError, ConvergenceError) as exc:
        if guess is None or not cold_retry:
            raise
        try:  # a continuation guess can mislead Newton near the ends of the family
            return solve_steady(theta, nu0, model, nu_top=nu_top, strict=True)
        except (NoSteadyFlowError, ConvergenceError):
            raise exc from None


def _knot(theta, nu0, model, guess, nu_top, cold_retry=True) -> _Knot:
    flow = _solve(theta, nu0, model, guess, nu_top, cold_retry)
    return _Knot(flow, local_coefficients(flow))


def _walk(theta, model, start: _Knot, direction, bound, step, min_step, nu_top):
    """Continuation in ln ν0 from ``start`` towards ``bound``; halve the step on failure.

    Where the shortest step fails too, the steady solver decides the flow there on its own
    (shooting scan and Newton, no guess) before the walk ends: a continuation guess can
    stall Newton inside the family (θ = 16.237°, φ = 0.0469, Φ = 0.322, e_p = 0.86: from
    ν0(0) = 0.0219 both neighbours failed, while each solves alone), and the family ends
    only where there is no flow.
    """
    knots: list[_Knot] = []
    cur = start
    reason = f"requested bound nu0 = {bound:g}"
    if direction * (math.log(cur.flow.nu0) - math.log(bound)) >= -1e-12:
        return knots, reason  # the start is the bound: no duplicate knot
    while True:
        ln_next = math.log(cur.flow.nu0) + direction * step
        if direction * (ln_next - math.log(bound)) >= 0:
            ln_next, last = math.log(bound), True
        else:
            last = False
        try:
            # no cold retry: near an end of the family continuation is the better guess;
            # the bound itself exactly (not exp(log(bound))), so that it is a knot
            nu_next = bound if last else math.exp(ln_next)
            k = _knot(theta, nu_next, model, cur.flow, nu_top, cold_retry=False)
        except (NoSteadyFlowError, ConvergenceError):
            if step / 2 >= min_step:
                step /= 2
                continue
            try:
                k = _knot(theta, nu_next, model, None, nu_top)
            except (NoSteadyFlowError, ConvergenceError) as alone:
                # the solver's own verdict there, its first clause (the rest lists what it tried)
                why = str(alone).split(" — ")[0]
                reason = f"no steady flow found beyond nu0 = {cur.flow.nu0:.4g} (at nu0 = {nu_next:.4g}: "
                reason += f"{why})"
                break
        knots.append(k)
        cur = k
        if last:
            break
    return knots, reason


#: Floor densities ν0(0) from which :func:`reduced_model` starts the steady family, in order.
SEEDS = (0.05, 0.1, 0.15, 0.03, 0.2, 0.3)
#: Densities spaced evenly in ln ν0 over [nu0_min, nu0_max] tried after the seeds (ratio ~1.2
#: between neighbours over the default bounds).
SCAN_SEEDS = 24


def _seed_order(seeds, nu0_min: float, nu0_max: float):
    """The seeds within [nu0_min, nu0_max], then the scan's densities not within 5 % of
    one of them."""
    first = [float(s) for s in seeds if nu0_min <= float(s) <= nu0_max]
    yield from first
    for s in np.geomspace(nu0_min, nu0_max, SCAN_SEEDS):
        if all(abs(math.log(s / f)) > 0.05 for f in first):
            yield float(s)


@functools.lru_cache(maxsize=32)
def reduced_model(
    theta: float,
    model: ChuteModel | None = None,
    *,
    nu0_min: float = 5e-3,
    nu0_max: float | None = None,
    step: float = 0.15,
    tol: float = 1e-4,
    max_knots: int = 200,
    nu_top: float = 1e-9,
    seeds: tuple = SEEDS,
) -> ReducedModel:
    """Build the 1D model's F, T̄, a over the steady family at fixed ``theta``.

    Parameters
    ----------
    theta : float
        Inclination θ (degrees).
    model : ChuteModel, optional
        Closure parameters (paper defaults).
    nu0_min, nu0_max : float
        Bounds on the floor density of the family; it also stops where no steady flow is
        found (angle-dependent ends: collapse or diverging decay length). Default
        ``nu0_max`` = 0.75 ν_m.
    step : float
        Initial continuation step in ln ν0.
    tol : float
        Target relative interpolation error of F, T̄, a at the midpoints between knots;
        intervals that miss it are split (the midpoint flow becomes a knot).
    max_knots : int
        Upper bound on the number of knots.
    nu_top : float
        ν0(y_max) of the steady solutions (paper: 1e-9).
    seeds : tuple of float
        Floor densities tried, in order, to start the continuation (those outside
        [``nu0_min``, ``nu0_max``] are skipped). Where none has a flow, :data:`SCAN_SEEDS`
        densities spaced evenly in ln ν0 over the bounds are tried as well, so that a family
        that exists anywhere on a ratio grid of ~1.2 is found (e.g. θ = 16.237°, φ = 0.0469,
        Φ = 0.322, e_p = 0.86: flows only for ν0(0) ≲ 0.03).

    Raises
    ------
    ParameterError
        Bad bounds or tolerance.
    NoSteadyFlowError
        No steady flow at any seed, or too few to build the functions.
    ConvergenceError
        The interpolation error does not reach ``tol`` within ``max_knots``.
    """
    model = model or ChuteModel()
    theta = float(theta)
    if not 0.0 < theta < 90.0:
        raise ParameterError(f"theta = {theta!r} is outside (0, 90) degrees")
    nu0_max = 0.75 * model.nu_max if nu0_max is None else float(nu0_max)
    if not 0.0 < nu0_min < nu0_max < model.nu_max:
        raise ParameterError(
            f"nu0_min = {nu0_min!r}, nu0_max = {nu0_max!r}: need "
            f"0 < nu0_min < nu0_max < nu_max = {model.nu_max:g}"
        )
    if not 0.0 < tol < 1e-1:
        raise ParameterError(f"tol = {tol!r} is outside (0, 0.1): relative interpolation error")
    start, tried, first = None, [], ""
    for s in _seed_order(seeds, nu0_min, nu0_max):
        try:
            start = _knot(theta, s, model, None, nu_top)
            break
        except (NoSteadyFlowError, ConvergenceError) as exc:
            tried.append(s)
            first = first or f"at nu0 = {s:.4g}: {exc}"
    if start is None:
        raise NoSteadyFlowError(
            f"no steady flow to build the 1D model on at theta = {theta:g} deg ({model.describe()}): "
            f"none at {len(tried)} floor densities nu0 in [{min(tried):.3g}, {max(tried):.3g}]; "
            f"{first}"
        )
    down, why_lo = _walk(theta, model, start, -1, nu0_min, step, step / 4, nu_top)
    up, why_hi = _walk(theta, model, start, +1, nu0_max, step, step / 4, nu_top)
    knots = down[::-1] + [start] + up
    if len(knots) < 3:
        raise NoSteadyFlowError(
            f"the steady family at theta = {theta:g} deg is too short to build the 1D model "
            f"on ({len(knots)} flow(s); ends: {why_lo} / {why_hi})"
        )
    # adaptive refinement: compare the interpolants at each midpoint with a direct solve
    checked: dict[tuple[float, float], dict] = {}
    while True:
        rm = _assemble(theta, model, knots, {}, (why_lo, why_hi))
        worst: dict[str, float] = {}
        insert: list = []
        for i in range(len(knots) - 1):
            k0, k1 = knots[i], knots[i + 1]
            key = (k0.flow.nu0, k1.flow.nu0)
            if key not in checked:
                mid = 0.5 * (key[0] + key[1])
                try:
                    km = _knot(theta, mid, model, k0.flow, nu_top)
                except (NoSteadyFlowError, ConvergenceError) as exc:
                    # an unverifiable interval ends the family on the side it lies
                    cut = f"no steady flow found at nu0 = {mid:.4g} ({exc})"
                    if i + 1 >= len(knots) - 1 - i:
                        knots, why_hi = knots[: i + 1], cut
                    else:
                        knots, why_lo = knots[i + 1 :], cut
                    break
                checked[key] = {"knot": km, "err": _errors(rm, km.coef)}
            err = checked[key]["err"]
            for name, v in err.items():
                worst[name] = max(worst.get(name, 0.0), v)
            if max(err["F"], err["Tbar"], err["a"]) > tol:
                insert.append((i, checked[key]["knot"]))
        else:
            if not insert:
                break
            if len(knots) + len(insert) > max_knots:
                raise ConvergenceError(
                    f"1D model at theta = {theta:g}: interpolation error "
                    f"{max(worst.values()):.2e} still above tol = {tol:g} with {len(knots)} "
                    f"knots (max_knots = {max_knots})"
                )
            for i, km in reversed(insert):
                knots.insert(i + 1, km)
            continue
        if len(knots) < 3:
            raise NoSteadyFlowError(
                f"the steady family at theta = {theta:g} deg is too short to build the 1D "
                f"model on ({len(knots)} flow(s); ends: {why_lo} / {why_hi})"
            )
    worst["midpoints"] = len(knots) - 1
    return _assemble(theta, model, knots, worst, (why_lo, why_hi))


def _errors(rm: ReducedModel, exact: LocalCoefficients) -> dict:
    r = exact.rho0
    rel = lambda x, y: abs(float(x) - y) / max(abs(y), 1e-300)  # noqa: E731
    return {
        "F": rel(rm.F(r), exact.F),
        "Tbar": rel(rm.Tbar(r), exact.Tbar),
        "a": rel(rm.a(r), exact.a),
        "dF": rel(rm.F(r, 1), exact.dF),
        "dTbar": rel(rm.Tbar(r, 1), exact.dTbar),
        "da": rel(rm.a(r, 1), exact.da),
    }


def _assemble(theta, model, knots, accuracy, ends) -> ReducedModel:
    rho = np.array([k.coef.rho0 for k in knots])
    if not (np.diff(rho) > 0).all():
        raise NoSteadyFlowError(
            f"rho_bar is not monotonic in nu0 along the family at theta = {theta:g} deg: "
            "F(rho_bar) of the 1D model is not single-valued"
        )
    cs = [k.coef for k in knots]
    splines = {}
    for name, val, der in (("F", "F", "dF"), ("Tbar", "Tbar", "dTbar"), ("a", "a", "da")):
        v = np.array([getattr(c, val) for c in cs])
        d = np.array([getattr(c, der) for c in cs])
        splines[name] = CubicHermiteSpline(rho, np.log(v), d / v, extrapolate=False)
    return ReducedModel(
        theta=theta,
        model=model,
        rho=rho,
        nu0=np.array([k.flow.nu0 for k in knots]),
        coefficients_at_knots=tuple(cs),
        flux=np.array([k.flow.Q for k in knots]),
        h=np.array([k.flow.h for k in knots]),
        nu_mean=np.array([k.flow.nu_mean for k in knots]),
        monotonic=np.array([bool(k.flow.monotonic) for k in knots]),
        accuracy=dict(accuracy),
        ends=ends,
        _splines=splines,
    )

"""Transverse perturbations (k_x = 0): long-wave coefficient α2z and the transverse analysis.

Perturbations ∝ exp(αt + i k_z z) across the slope (the question of the paper's §5.3).
At k = 0 the mass-conservation mode has α = 0 and eigenvector V0 = ∂X0/∂β (Appendix B,
eq. (B 18)), whatever the direction of k. Along a ray k = s (k̂x, k̂z) the discrete operator is

    A(s) = A0 + s P1 + s² P2,   P1 = i(k̂x A_{1,0} + k̂z A_{0,1}) + K,
                                P2 = −(k̂x² A_{2,0} + k̂x k̂z A_{1,1} + k̂z² A_{0,2}),

(:attr:`StabilityOperator.pieces`, K the |k| terms of the top rows), and the bordered
perturbation theory of :mod:`chuteflow.longwave.theory` gives α = α1 s + α2 s² + O(s³).
Across the slope (k̂ = (0, 1)) the base flow has no spanwise velocity, so α1z = 0 (up to
the top truncation) and α(0, k_z) = α2z k_z² + O(k_z⁴), α2z real (at k_x = 0 the problem
is real).

Physical reading (lubrication limit of the z-momentum balance, derived here; the analogue
of the paper's eq. (B 11) for the lateral flux). At O(k_z) the spanwise velocity obeys
(μ0 ŵ')' = i k_z p̂ with μ0 ŵ' = η*(0) ŵ at the floor (eq. (2.9), z component) and no stress
at the top, p̂ = ∂p0/∂β the lateral pressure perturbation of the neighbouring steady
column; the depth-integrated mass balance α ∫ν̂ = −i k_z ∫ ν0 ŵ dy then gives

    α2z = −[ ρ̄ Ŝ(0)/η*(0) + ∫ W0(y) Ŝ(y)/μ0(y) dy ] / (dρ̄/dβ),
    Ŝ(y) = ∂/∂β ∫_y^∞ p0 dy',   W0(y) = ∫_y^∞ ν0 dy',

:func:`lubrication_alpha2z`. Ŝ(0) = dP/dβ with P = ∫ p0 dy = Σ_zz integrated over the
depth, the lateral pressure of a column (= cos θ ∫ y ν0 dy by the steady y-momentum
balance, ~ ρ̄ T̄ for a dilute column). When the columns' lateral pressures Ŝ(y) fall as
the mass rises (dP/dρ̄ < 0: denser columns are colder and push less), α2z > 0: mass flows
towards the denser columns, the transverse long-wave instability (lateral clustering).

:func:`transverse` adds to α2z the dispersion relation α(k_z) of the tracked branch
(:func:`chuteflow.stability.transverse_dispersion`). The scans of the largest growth rate
along each axis for sweeps (:func:`~chuteflow.stability.axis_peaks.longitudinal_peak`,
:func:`~chuteflow.stability.axis_peaks.transverse_peak`, :class:`GrowthPeak`) are dispersion
scans, not long-wave theory: they live in :mod:`chuteflow.stability.axis_peaks` and are
re-exported here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import minimize_scalar

from ..closures import ChuteModel
from ..errors import ConvergenceError, ParameterError
from ..stability.axis_peaks import (  # the axis scans, re-exported: they lived here
    PEAK_RATIO,
    GrowthPeak,
    _refine_peak,  # noqa: F401 (re-exported for tests/stability/test_growth_peak.py)
    cutoff_of_branch,
    longitudinal_peak,
    transverse_peak,
)
from ..stability.modes import OperatorCache, stability_operator
from ..stability.operator import StabilityOperator, base_on_grid, stability_grid
from ..stability.policy import DEFAULT_POLICY, RejectionPolicy
from ..stability.scan import peak_index
from ..stability.transverse import (
    TransverseDispersion,
    growth_plane,
    transverse_dispersion,
    transverse_mode,
)
from ..stability.transverse_tracking import TransverseTracker
from ..steady import SteadyFlow, steady_tangent
from .theory import bordered_coefficients, fixed_height_tangent

__all__ = [
    "GrowthPeak",
    "PEAK_RATIO",
    "TransverseLongWave",
    "TransverseResult",
    "directional_coefficients",
    "lateral_pressure",
    "longitudinal_peak",
    "lubrication_alpha2z",
    "transverse",
    "transverse_longwave",
    "transverse_peak",
    "growth_plane",
]


def directional_coefficients(
    op: StabilityOperator, tangent: dict, direction=(0.0, 1.0)
) -> tuple[complex, complex]:
    """(α1, α2) of α(s k̂) = α1 s + α2 s² + … on one discretised 3D operator.

    Bordered perturbation theory at k = 0 (as :func:`chuteflow.longwave.theory.taylor_coefficients`)
    along the unit direction k̂ = (k̂x, k̂z); ``op`` must be three-dimensional when k̂z ≠ 0.
    """
    cx, cz = (float(direction[0]), float(direction[1]))
    norm = math.hypot(cx, cz)
    cx, cz = cx / norm, cz / norm
    M = op.size
    z = np.zeros((M, M))
    P = op.pieces
    A0 = P[(0, 0)]
    P1 = 1j * (cx * P.get((1, 0), z) + cz * P.get((0, 1), z)) + op.K
    P2 = -(cx**2 * P.get((2, 0), z) + cx * cz * P.get((1, 1), z) + cz**2 * P.get((0, 2), z))
    return bordered_coefficients(op, tangent, A0, P1, P2)


@dataclass(frozen=True)
class TransverseLongWave:
    """α(0, k_z) = α1z k_z + α2z k_z² + O(k_z³) at k = 0 (α1z = 0 up to the top truncation).

    Attributes
    ----------
    alpha1_z, alpha2_z : complex
        The coefficients (bordered perturbation theory, finer resolution ``n``).
    n : int
        Chebyshev intervals of the finer resolution.
    convergence_alpha2 : float
        Relative change of α2z between n and 4n/5.
    rtol : float
        The accepted relative change (:attr:`converged`: ``convergence_alpha2 <= rtol``).
    """

    alpha1_z: complex
    alpha2_z: complex
    n: int
    convergence_alpha2: float
    rtol: float = 1e-3

    @property
    def converged(self) -> bool:
        """α2z changed by at most :attr:`rtol` between the two finest resolutions."""
        return bool(self.convergence_alpha2 <= self.rtol)

    @property
    def note(self) -> str:
        """Empty when converged; else by how much α2z still changed."""
        if self.converged:
            return ""
        return (
            f"alpha2_z changed by {self.convergence_alpha2:.1e} between the two finest resolutions "
            f"(n = {self.n}; rtol = {self.rtol:g})"
        )

    def to_dict(self) -> dict:
        """JSON-ready dict (complex coefficients as real and imaginary parts)."""
        return {
            "alpha1_z_re": self.alpha1_z.real,
            "alpha1_z_im": self.alpha1_z.imag,
            "alpha2_z_re": self.alpha2_z.real,
            "alpha2_z_im": self.alpha2_z.imag,
            "n": self.n,
            "convergence_alpha2": self.convergence_alpha2,
            "rtol": self.rtol,
            "converged": self.converged,
            "note": self.note,
        }


def transverse_longwave(
    flow: SteadyFlow,
    n: int = 100,
    *,
    rtol: float = 1e-3,
    n_max: int = 320,
    cache: OperatorCache | None = None,
    strict: bool = False,
) -> TransverseLongWave:
    """α2z by bordered perturbation theory, n raised by 25 % until it changes < ``rtol``;
    the three-dimensional operators come from ``cache`` (default: the module's).

    Where α2z has not converged to ``rtol`` by ``n_max``, the estimate at ``n_max`` is
    returned flagged (``converged`` False, :attr:`TransverseLongWave.note`), or with
    ``strict=True`` :class:`ConvergenceError` is raised.
    """
    tangent = steady_tangent(flow)
    ladder = RejectionPolicy(n_start=n, n_max=n_max)
    n2 = max(24, (4 * n) // 5)
    _, b2 = directional_coefficients(stability_operator(flow, n2, True, cache=cache), tangent)
    while True:
        a1, a2 = directional_coefficients(stability_operator(flow, n, True, cache=cache), tangent)
        c2 = abs(a2 - b2) / max(abs(a2), 1e-300)
        if c2 <= rtol or n >= n_max:
            break
        b2, n2, n = a2, n, ladder.next_n(n)
    if strict and not c2 <= rtol:
        raise ConvergenceError(
            f"transverse long-wave coefficient at theta = {flow.theta:g}, nu0 = {flow.nu0:g} "
            f"changed by {c2:.1e} between n = {n2} and n = {n} (rtol = {rtol:g})"
        )
    return TransverseLongWave(a1, a2, n, float(c2), float(rtol))


def lateral_pressure(flow: SteadyFlow) -> dict:
    """Depth-integrated lateral pressure of the steady column and its change along the family.

    Returns
    -------
    dict
        ``P`` = ∫ p0 dy (Σ_zz = p0 at the base state), ``P_moment`` = cos θ ∫ y ν0 dy (equal
        to P by the steady y-momentum balance, up to the weight above y_max), ``rho_T`` =
        ∫ ν0 T0 dy, and their derivatives along the family with respect to the mass ρ̄
        (``dP_drho``, ``drho_T_drho``; at fixed θ, from :func:`steady_tangent`).
    """
    tg = steady_tangent(flow)
    g, L = flow.grid, flow.y_max
    w = g.weights
    nu, T = flow.nu, flow.T
    part = flow.model.evaluate(nu, T)
    p = part["p"]
    # the tangent at fixed ξ = y/y_max: ∂/∂β ∫_0^L f dy = ∫ ∂f/∂β|_ξ dy + (dL/dβ) f̄ ξ-weighted
    dnu = nu * tg["log_nu"]
    dT = tg["T"]
    dp = p[(1, 0)] * dnu + p[(0, 1)] * dT
    dL = tg["y_max"]

    # ∫_0^{L} f(ξL) dy = L ∫_0^1 f dξ  ⇒  d/dβ = (dL/dβ)/L ∫ f dy + ∫ ∂f/∂β|_ξ dy
    def d_int(f, df):
        return dL / L * (w @ f) + w @ df

    th = math.radians(flow.theta)
    P = float(w @ p[(0, 0)])
    rhoT = float(w @ (nu * T))
    drho = d_int(nu, dnu)
    dP = d_int(p[(0, 0)], dp)
    drhoT = d_int(nu * T, dnu * T + nu * dT)
    y = g.y
    Pm = math.cos(th) * float(w @ (y * nu))
    dPm = math.cos(th) * d_int(y * nu, y * dnu + (g.y / L) * dL * nu)
    return {
        "P": P,
        "P_moment": Pm,
        "rho_T": rhoT,
        "dP_drho": float(dP / drho),
        "dP_moment_drho": float(dPm / drho),
        "drho_T_drho": float(drhoT / drho),
        "drho_bar": float(drho),
    }


def lubrication_alpha2z(flow: SteadyFlow, n: int = 160) -> float:
    """α2z from the lubrication balance of the lateral flux (module docstring).

    Uses V0 = ∂X0/∂β at fixed height on an N = ``n`` grid: p̂ = p_ν ν̂ + p_T T̂,
    Ŝ(y) = ∫_y^∞ p̂, W0(y) = ∫_y^∞ ν0, η*(0) and μ0 from the flow's model.
    """
    # the grid and base state of the three-dimensional operator at N = n (plain Chebyshev),
    # without assembling it: only V0 and the base state are used
    g = stability_grid(flow, n, mapped=False)
    V0 = fixed_height_tangent(flow, steady_tangent(flow), g.y)
    base = base_on_grid(flow, g.y)
    nu, T = base["nu"], base["T"]
    part = flow.model.evaluate(nu, T)
    p, mu, eta = part["p"], part["mu"][(0, 0)], part["eta_star"][(0, 0)]
    dp = p[(1, 0)] * V0["nu"] + p[(0, 1)] * V0["T"]
    # cumulative integrals from the top: ∫_y^L f = ∫_0^L f − ∫_0^y f
    cum = _cumulative(g)
    S = (g.weights @ dp) - cum @ dp
    W = (g.weights @ nu) - cum @ nu
    eta0 = float(np.broadcast_to(eta, nu.shape)[0])
    drho = g.weights @ V0["nu"]
    num = W[0] * S[0] / eta0 + g.weights @ (W * S / mu)
    return float(-num / drho)


def _cumulative(g) -> np.ndarray:
    """Matrix Q with (Q f)_j = ∫_0^{y_j} f dy, spectrally (inverse of D with f(0) = 0)."""
    m = g.n + 1
    D = g.D.copy()
    D[0, :] = 0.0
    D[0, 0] = 1.0
    rhs = np.eye(m)
    rhs[0, :] = 0.0
    return np.linalg.solve(D, rhs)


@dataclass(frozen=True)
class TransverseResult:
    """Transverse (k_x = 0) stability of one steady flow.

    Attributes
    ----------
    theta, nu0 : float
        The steady flow (degrees, floor density ν0(0)).
    alpha2_z : float
        α(0, k_z) = α2z k_z² + O(k_z⁴) (perturbation theory at k = 0); > 0: long-wave
        transverse instability.
    alpha1_z : float
        |α1z|, zero up to the top truncation (a check).
    convergence_alpha2 : float
        Relative change of α2z between the two finest resolutions.
    alpha2_z_eigen : float
        Re α(0, k_check)/k_check² from the eigenvalue at the small ``k_check``.
    k_check : float
        The wavenumber of that check.
    alpha2_z_lubrication : float
        α2z from the lubrication formula (:func:`lubrication_alpha2z`).
    dP_drho, drho_T_drho : float
        Change of the depth-integrated lateral pressure ∫p0 dy, and of ρ̄T̄ = ∫ν0 T0 dy,
        with the mass along the steady family at fixed θ.
    kz_max : float or None
        Wavenumber of the largest growth rate on the computed grid (refined); None when
        every k_z decays.
    growth_max : float
        max Re α over the grid (the least negative when all decay; NaN when the tracked
        branch is inside the continuum from the first step, as where α2z < 0).
    kz_at_growth_max : float
        Where that maximum lies (also when negative).
    alpha_im_at_max : float
        Im α of that mode.
    stationary : bool
        Im α = 0 at the maximum (to 1e-9 relative).
    kz_cutoff : float or None
        The first k_z > 0 where the growth rate changes sign, when from + to − (upper edge of
        the long-wave unstable band, the k_c rule of :mod:`chuteflow.stability.scan`), None
        if none on the grid or the first change goes from − to +.
    dispersion : TransverseDispersion
        The computed α(k_z) with convergence estimates.
    model : ChuteModel
        Parameters and closures of the flow.
    method : str
        ``"track"`` (the α(0) = 0 branch followed in k_z) or ``"dense"`` (every eigenvalue
        at every k_z).
    """

    theta: float
    nu0: float
    alpha2_z: float
    alpha1_z: float
    convergence_alpha2: float
    alpha2_z_eigen: float
    k_check: float
    alpha2_z_lubrication: float
    dP_drho: float
    drho_T_drho: float
    kz_max: float | None
    growth_max: float
    kz_at_growth_max: float
    alpha_im_at_max: float
    stationary: bool
    kz_cutoff: float | None
    dispersion: TransverseDispersion = field(repr=False)
    model: ChuteModel | None = None
    method: str = "track"
    alpha2_z_note: str = ""

    @property
    def converged(self) -> bool:
        """α2z converged (:attr:`TransverseLongWave.converged`) and every computed k_z passed
        the drift and tail tests."""
        return not self.note

    @property
    def note(self) -> str:
        """Empty when converged; else what missed its tolerance."""
        d = self.dispersion
        bad = int((~d.physical[np.isfinite(d.alpha_re)]).sum())
        parts = [self.alpha2_z_note] if self.alpha2_z_note else []
        if bad:
            parts.append(f"{bad} of the computed k_z miss the drift or tail test")
        return "; ".join(parts)

    @property
    def unstable(self) -> bool:
        """Some k_z grows (on the grid, or α2z > 0)."""
        return bool((math.isfinite(self.growth_max) and self.growth_max > 0) or self.alpha2_z > 0)

    def to_dict(self) -> dict:
        """JSON-ready dict: alpha2_z, kz_max (None if all decay), growth_max, stationary,
        unstable, and the convergence estimates and model parameters."""
        d = self.dispersion
        return {
            "theta": self.theta,
            "nu0": self.nu0,
            "alpha2_z": self.alpha2_z,
            "alpha1_z": self.alpha1_z,
            "convergence_alpha2": self.convergence_alpha2,
            "alpha2_z_eigen": self.alpha2_z_eigen,
            "k_check": self.k_check,
            "alpha2_z_lubrication": self.alpha2_z_lubrication,
            "dP_drho": self.dP_drho,
            "drho_T_drho": self.drho_T_drho,
            "kz_max": self.kz_max,
            "growth_max": self.growth_max,
            "kz_at_growth_max": self.kz_at_growth_max,
            "alpha_im_at_max": self.alpha_im_at_max,
            "stationary": self.stationary,
            "unstable": self.unstable,
            "kz_cutoff": self.kz_cutoff,
            "kz_points": int(len(d.kz)),
            "kz_computed": int(np.isfinite(d.alpha_re).sum()),
            "branch_lost_at": d.branch_lost_at,
            "method": self.method,
            # NaN (JSON null) where no k_z was computed (the branch lost at the first step)
            "drift_max": float(np.nanmax(d.drift)) if not np.isnan(d.drift).all() else math.nan,
            "tail_max": float(np.nanmax(d.tail)) if not np.isnan(d.tail).all() else math.nan,
            "all_physical": bool(d.physical[np.isfinite(d.alpha_re)].all()),
            "converged": self.converged,
            "note": self.note,
            **(self.model.to_dict() if self.model is not None else {}),
        }


def transverse(
    flow: SteadyFlow,
    *,
    kz_max: float = 3.0,
    num: int = 50,
    n: int = 100,
    k_check: float = 1e-4,
    policy: RejectionPolicy = DEFAULT_POLICY,
    method: str = "track",
) -> TransverseResult:
    """Transverse analysis of one flow: α2z, the dispersion α(k_z) on (0, kz_max], k_z*.

    The grid is geometric from 1e-5 (the long-wave instability lives at k_z ~ 1e-3 for P1)
    to ``kz_max``. ``method="track"`` (fast, ~0.3 s): the α(0) = 0 branch is followed from
    k = 0 with the predictor α2z k_z² (:class:`~chuteflow.stability.TransverseTracker`) until
    it enters the continuum of the dilute top; ``"dense"``: the dense scan of every
    eigenvalue at every k_z (the reference, which also sees other modes, e.g.
    finite-wavelength rolls; ~1 s per k_z). The maximum of Re α is refined by a bounded
    scalar search in log k_z between the best grid point's neighbours (to 2 % in k_z), and
    the first sign change of Re α (the cut-off of the unstable band) by Brent's method (to
    0.1 %), both on the tracked branch (``"track"``) or on dense solves (``"dense"``).
    """
    if method not in ("track", "dense"):
        raise ParameterError(f"method = {method!r}: choose 'track' (fast) or 'dense' (reference scan)")
    lw = transverse_longwave(flow, n)
    ks = np.geomspace(1e-5, kz_max, num)
    tr = None
    if method == "track":
        tr = TransverseTracker(flow, alpha2z=float(lw.alpha2_z.real), policy=policy)
        disp = transverse_dispersion(flow, ks, policy=policy, tracker=tr)
        k_check = min(k_check, float(ks[-1]))
        tr.advance(k_check) if tr.lost_at is None or k_check < tr.lost_at else None
        a_chk = tr.at(k_check)
        a2e = a_chk.real / k_check**2 if a_chk is not None else math.nan

        def growth_at(k):
            a = tr.at(k)
            return (a.real, a.imag) if a is not None else (-math.inf, 0.0)
    else:
        disp = transverse_dispersion(flow, ks, policy=policy, method="dense")
        a2e = transverse_mode(flow, k_check, policy=policy).alpha.real / k_check**2

        def growth_at(k):
            m = transverse_mode(flow, k, policy=policy)
            return m.alpha.real, m.alpha.imag

    lp = lateral_pressure(flow)
    lub = lubrication_alpha2z(flow)
    g = np.where(np.isfinite(disp.alpha_re), disp.alpha_re, -np.inf)
    j = peak_index(g) or 0  # the branch scan's rule (chuteflow.stability.scan)
    kz_best, growth, aim = float(ks[j]), float(g[j]), float(disp.alpha_im[j])
    if 0 < j < len(ks) - 1 and np.isfinite(g[j - 1]):
        # where the tracker lost the branch after k_z[j], up to as far beyond its last point
        # as TransverseTracker.point_at solves (max_ratio): where exactly it was lost depends
        # on round-off, the maximum beyond k_z[j] does not
        hi = (
            ks[j + 1]
            if np.isfinite(g[j + 1]) or tr is None
            else min(ks[j + 1], tr.history[-1].kz * tr.max_ratio)
        )
        seen = {}

        def minus_growth(x):
            seen[x] = growth_at(float(np.exp(x)))
            return -seen[x][0]

        opt = minimize_scalar(
            minus_growth,
            bounds=(math.log(ks[j - 1]), math.log(hi)),
            method="bounded",
            options={"xatol": 0.02, "maxiter": 12},
        )
        got = seen.get(opt.x)
        if got is not None and got[0] > growth:
            kz_best, (growth, aim) = float(np.exp(opt.x)), (float(got[0]), float(got[1]))
    if not math.isfinite(growth):
        # no resolved point at all: the branch (α ≈ α2z k_z² < 0) is inside the continuum of
        # the dilute top from the first step; it decays, at a rate the continuum hides
        growth, aim, kz_best = math.nan, 0.0, math.nan
    stationary = abs(aim) <= 1e-9 * max(abs(growth), 1e-300) or abs(aim) < 1e-14
    cut = cutoff_of_branch(ks, g, tr, growth_at)
    return TransverseResult(
        flow.theta,
        flow.nu0,
        float(lw.alpha2_z.real),
        float(abs(lw.alpha1_z)),
        lw.convergence_alpha2,
        float(a2e),
        float(k_check),
        lub,
        lp["dP_drho"],
        lp["drho_T_drho"],
        kz_best if growth > 0 else None,  # NaN > 0 is False
        growth,
        kz_best,
        aim,
        bool(stationary),
        cut,
        disp,
        flow.model,
        method=method,
        alpha2_z_note=lw.note,
    )

"""Spatial branches k(ω): the wave a steady forcing at real frequency ω makes grow in x.

A mode ∝ exp(αt + ikx) forced at the inlet at angular frequency ω > 0 has α = −iω (it goes
as exp(i(kx − ωt))); the wavenumber k(ω) is then complex, the root of

    α(k) = −iω                                                     (eq. (4.4) at complex k)

on the tracked α(0) = 0 branch continued to complex k (:mod:`chuteflow.stability.complex_k`).
The wave's amplitude grows as exp(−Im k · x): the spatial growth rate is −Im k.

Method. The real wavenumber k0 with −Im α(k0) = ω is found by Newton along the real axis
(from k = ω/c, c the long-wave speed); Gaster's relation gives the first estimate,

    k ≈ k0 + (−iω − α(k0))/α'(k0),   i.e.  −Im k ≈ Re α(k0)/c_g(k0),  c_g = −Im α'(k0),

which Newton's method on α(k) + iω = 0 in the complex k plane then corrects (α'(k) exactly,
from the bordered Jacobian). The point is judged by the temporal modes' tests: the drift
|α(k; N) − α(k; N')| at the found k (N' = 0.8 N) and the Chebyshev tail of the eigenvector.
The group velocity reported is c_g = Re(i α'(k)) = Re dω/dk at the complex k (at real k,
−Im α'(k)).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..closures import ChuteModel
from ..conventions import RATE_UNITS, VELOCITY_UNITS, WAVENUMBER_UNITS
from ..errors import ChuteflowError, ConvergenceError, ParameterError
from ..stability import branch_scan
from ..steady import SteadyFlow
from ._core import DEFAULT_SPATIAL_POLICY, Branch, SpatialPolicy, check_flow, newton_k

__all__ = [
    "SpatialPoint",
    "spatial_point",
    "spatial_dispersion",
    "spatial_peak",
    "check_omega",
    "real_k_of_frequency",
]


def check_omega(omega) -> float:
    """ω as a float, or a one-line :class:`~chuteflow.errors.ParameterError`."""
    try:
        w = float(omega)
    except (TypeError, ValueError):
        raise ParameterError(f"omega = {omega!r}: expected a number") from None
    if not (math.isfinite(w) and w > 0):
        raise ParameterError(
            f"omega = {omega!r} is outside (0, inf): the angular frequency of the inlet forcing "
            "exp(-i omega t) is positive (a negative one is the complex conjugate wave)"
        )
    return w


@dataclass(frozen=True, eq=False)
class SpatialPoint:
    """One point k(ω) of the spatial branch (module docstring).

    Attributes
    ----------
    omega : float
        Angular frequency ω > 0 (√(g/σ)).
    k : complex
        The wavenumber k(ω) with α(k) = −iω (1/σ); Re k > 0.
    spatial_growth : float
        −Im k: the wave grows as exp(−Im k · x) down the slope.
    group_velocity : float
        Re(i α'(k)) (√(gσ)).
    k_real : float
        The real k0 with −Im α(k0) = ω (the temporal mode of the same frequency).
    gaster_growth : float
        Re α(k0)/c_g(k0): Gaster's estimate of the spatial growth rate.
    alpha_residual : float
        |α(k) + iω| at the answer.
    drift, tail : float
        The temporal modes' two tests at the found k (|α(k; N) − α(k; N')|, Chebyshev tail).
    n, n_check : int
        Resolutions N and N'.
    converged : bool
        Both tests pass and Newton settled; False: the best estimate, with :attr:`note`.
    note : str
        Why it is flagged; empty if nothing.
    """

    omega: float
    k: complex
    group_velocity: float
    k_real: float
    gaster_growth: float
    alpha_residual: float
    drift: float
    tail: float
    n: int
    n_check: int
    converged: bool
    note: str = ""
    theta: float = math.nan
    nu0: float = math.nan
    model: ChuteModel | None = field(default=None, repr=False)
    dalpha: complex = complex(math.nan, math.nan)

    @property
    def spatial_growth(self) -> float:
        return float(-self.k.imag)

    def to_dict(self) -> dict:
        """JSON-ready scalars (the keys of ``chuteflow spatial --json``)."""
        return {
            "theta": self.theta,
            "nu0": self.nu0,
            **(self.model.to_dict() if self.model is not None else {}),
            "omega": self.omega,
            "k_re": float(self.k.real),
            "k_im": float(self.k.imag),
            "spatial_growth": self.spatial_growth,
            "group_velocity": float(self.group_velocity),
            "k_real": float(self.k_real),
            "gaster_growth": float(self.gaster_growth),
            "drift": float(self.drift),
            "tail": float(self.tail),
            "n": int(self.n),
            "n_check": int(self.n_check),
            "converged": bool(self.converged),
            "note": self.note,
        }


def real_k_of_frequency(branch: Branch, omega: float, k0: float, maxiter: int = 40):
    """(k0, eigenpair): the real k with −Im α(k) = ω on ``branch``, by Newton along the real axis
    (dω/dk = c_g = −Im α'(k)); None where it leaves k > 0 or does not settle."""
    k = float(k0)
    e = branch.at(k)
    for _ in range(maxiter):
        cg = -e.dalpha.imag
        if not (math.isfinite(cg) and cg != 0):
            return None
        dk = (omega - (-e.alpha.imag)) / cg
        k_new = k + dk
        if k_new <= 0:
            k_new = 0.5 * k
        k = k_new
        e = branch.at(k, start=e)
        # 1e-10: the round-off of Im α (~1e-13 at P4, where ω ~ 2e-3, k ~ 1e-3) makes steps of
        # ~5e-11 k forever; k0 only starts the complex Newton, which has its own tolerance
        if abs(dk) <= 1e-10 * k:
            return k, e
    return None


def _solve(branch: Branch, omega: float, k_guess: complex, policy: SpatialPolicy, flow) -> SpatialPoint:
    notes = []
    found = real_k_of_frequency(branch, omega, max(k_guess.real, 1e-12))
    if found is None:
        kr, e0 = k_guess.real, branch.at(k_guess.real)
        notes.append("no real k with -Im alpha(k) = omega on the branch (Gaster's start from the guess)")
    else:
        kr, e0 = found
    cg0 = -e0.dalpha.imag
    gaster = e0.alpha.real / cg0 if cg0 else math.nan
    k_start = kr + (-1j * omega - e0.alpha) / e0.dalpha
    try:
        e = newton_k(branch, k_start, -1j * omega, policy, start=e0)
    except ChuteflowError as exc:
        raise ConvergenceError(f"spatial branch at omega = {omega:g}: {exc}") from None
    drift, tl, n2 = branch.convergence(e)
    ok = policy.rejection.accepts(drift, tl)
    if not ok:
        notes.append(f"misses the temporal modes' tests at N = {branch.n} (drift {drift:.1e}, tail {tl:.1e})")
    return SpatialPoint(
        omega=omega,
        k=complex(e.k),
        group_velocity=float((1j * e.dalpha).real),
        k_real=float(kr),
        gaster_growth=float(gaster),
        alpha_residual=float(abs(e.alpha + 1j * omega)),
        drift=drift,
        tail=tl,
        n=branch.n,
        n_check=n2,
        converged=bool(ok and found is not None),
        note="; ".join(notes),
        theta=flow.theta,
        nu0=flow.nu0,
        model=flow.model,
        dalpha=complex(e.dalpha),
    )


def _seed_k(flow: SteadyFlow, omega: float, policy: SpatialPolicy, cache) -> tuple[Branch, float]:
    """A branch seeded at the real k of frequency ω by the long-wave speed, refined once."""
    from ..stability import least_stable

    k_probe = 1e-4
    m = least_stable(flow, k_probe, policy=policy.rejection, cache=cache)
    c = -m.alpha.imag / k_probe
    if not (math.isfinite(c) and c > 0):
        raise ConvergenceError(
            f"the branch at k = {k_probe:g} does not travel down the slope (phase velocity {c:.3g})"
        )
    k0 = min(omega / c, 6.0)
    return Branch(flow, k0, policy, cache), k0


def spatial_point(
    flow: SteadyFlow,
    omega: float,
    *,
    k_guess: complex | None = None,
    policy: SpatialPolicy | None = None,
    cache=None,
    strict: bool = False,
) -> SpatialPoint:
    """The spatial branch k(ω) at angular frequency ``omega`` (module docstring).

    Parameters
    ----------
    flow : SteadyFlow
        Base state.
    omega : float
        Angular frequency ω > 0 of the forcing, in √(g/σ).
    k_guess : complex, optional
        Where to start (default ω/c with c the phase velocity at k = 1e-4, refined along the
        real axis).
    policy : SpatialPolicy, optional
        Newton's tolerances and the temporal rejection policy.
    strict : bool
        True: raise :class:`~chuteflow.errors.ConvergenceError` instead of returning a flagged
        point.

    Returns
    -------
    SpatialPoint
        Flagged (``converged=False``, ``note``) when the tests fail or Newton does not settle
        (then its estimate is Gaster's).
    """
    flow = check_flow(flow)
    omega = check_omega(omega)
    policy = DEFAULT_SPATIAL_POLICY if policy is None else policy
    if k_guess is None:
        branch, k0 = _seed_k(flow, omega, policy, cache)
    else:
        k0 = complex(k_guess).real
        if not (k0 > 0):
            raise ParameterError(f"k_guess = {k_guess!r}: Re k must be > 0 (the branch cut is Re k = 0)")
        branch = Branch(flow, k0, policy, cache)
    try:
        pt = _solve(branch, omega, complex(k0), policy, flow)
    except ConvergenceError as exc:
        if strict:
            raise
        e0 = branch.at(k0)
        cg0 = -e0.dalpha.imag
        g = e0.alpha.real / cg0 if cg0 else math.nan
        pt = SpatialPoint(
            omega=omega,
            k=complex(k0, -g),
            group_velocity=float(cg0),
            k_real=float(k0),
            gaster_growth=float(g),
            alpha_residual=float(abs(e0.alpha + 1j * omega)),
            drift=math.nan,
            tail=math.nan,
            n=branch.n,
            n_check=0,
            converged=False,
            note=f"{exc}; Gaster's estimate from the real k of the guess is returned",
            theta=flow.theta,
            nu0=flow.nu0,
            model=flow.model,
        )
    if strict and not pt.converged:
        raise ConvergenceError(f"spatial branch at omega = {omega:g}: {pt.note}")
    return pt


def spatial_dispersion(
    flow: SteadyFlow,
    omegas=None,
    *,
    num: int = 24,
    policy: SpatialPolicy | None = None,
    cache=None,
):
    """The spatial dispersion curve k(ω) as an :class:`xarray.Dataset` over ``omega``.

    Default frequencies: ``num`` points on (0, 1.25 ω_c], ω_c = −Im α(k_c) the cut-off
    frequency, the frequency of the neutral temporal mode at the paper's k_c, where the
    spatial growth vanishes (k real there). Continuation in ω from point to point. Variables
    ``k_re``, ``k_im``, ``spatial_growth`` (−Im k), ``group_velocity``, ``gaster_growth``,
    ``drift``, ``tail``, ``converged``; attributes ``omega_c`` (cut-off), ``omega_max`` and
    ``spatial_growth_max`` (the most amplified frequency, refined where Re α'(k(ω)) = 0,
    i.e. d(−Im k)/dω = Re(1/α') = 0), ``converged`` (every point), and the flow's parameters.
    A flow without the long-wave band (k_c None) is scanned up to the frequency of k = 0.05.
    """
    import xarray as xr

    flow = check_flow(flow)
    policy = DEFAULT_SPATIAL_POLICY if policy is None else policy
    scan = branch_scan(flow, policy=policy.rejection, cache=cache)
    kc = scan.k_c
    omega_c = math.nan
    if omegas is None:
        k_end = kc if kc is not None else float(scan.k[-1])
        br0 = Branch(flow, k_end, policy, cache)
        w_end = float(-br0.last.alpha.imag)
        if kc is not None:
            omega_c = w_end
        if not (w_end > 0):
            raise ConvergenceError(f"the branch's frequency at k = {k_end:g} is not positive ({w_end:.3g})")
        omegas = np.linspace(1.25 * w_end / num, 1.25 * w_end, num)
    else:
        omegas = np.array([check_omega(w) for w in np.atleast_1d(omegas)], dtype=float)
        if kc is not None:
            omega_c = float(-Branch(flow, kc, policy, cache).last.alpha.imag)
    omegas = np.sort(omegas)
    branch, k0 = _seed_k(flow, float(omegas[0]), policy, cache)
    pts: list[SpatialPoint] = []
    guess = complex(k0)
    for w in omegas:
        try:
            pt = _solve(branch, float(w), guess, policy, flow)
        except ConvergenceError as exc:
            pt = spatial_point(flow, float(w), policy=policy, cache=cache)
            pt = SpatialPoint(**{**pt.__dict__, "converged": False, "note": f"{exc}; {pt.note}".strip("; ")})
        pts.append(pt)
        guess = complex(pt.k_real)
    growth = np.array([p.spatial_growth for p in pts])
    w_max, g_max = _most_amplified(branch, omegas, pts, policy, flow)
    conv = np.array([p.converged for p in pts])
    ds = xr.Dataset(
        {
            "k_re": ("omega", np.array([p.k.real for p in pts]), {"units": WAVENUMBER_UNITS}),
            "k_im": ("omega", np.array([p.k.imag for p in pts]), {"units": WAVENUMBER_UNITS}),
            "spatial_growth": (
                "omega",
                growth,
                {"units": WAVENUMBER_UNITS, "long_name": "spatial growth rate -Im k"},
            ),
            "group_velocity": ("omega", np.array([p.group_velocity for p in pts]), {"units": VELOCITY_UNITS}),
            "gaster_growth": (
                "omega",
                np.array([p.gaster_growth for p in pts]),
                {"units": WAVENUMBER_UNITS, "long_name": "Gaster's estimate Re alpha / c_g"},
            ),
            "drift": ("omega", np.array([p.drift for p in pts]), {"units": RATE_UNITS}),
            "tail": ("omega", np.array([p.tail for p in pts])),
            "converged": ("omega", conv),
        },
        coords={"omega": ("omega", omegas, {"units": RATE_UNITS, "long_name": "angular frequency"})},
    )
    ds.attrs.update(
        theta=flow.theta,
        nu0=flow.nu0,
        omega_c=omega_c,
        omega_max=w_max,
        spatial_growth_max=g_max,
        converged=str(bool(conv.all())),
        convention="modes ~ exp(alpha t + i k x), alpha = -i omega; growth exp(-Im k x)",
    )
    ds.attrs.update(flow.model.attrs())
    ds.attrs["model"] = flow.model.describe()
    return ds


def _most_amplified(branch: Branch, omegas, pts, policy, flow) -> tuple[float, float]:
    """(ω_max, −Im k(ω_max)): the maximum of the sampled spatial growth refined by the secant
    on Re α'(k(ω)) = 0 between its neighbours; NaN where no sample grows."""
    g = np.array([p.spatial_growth for p in pts])
    if not np.any(g > 0):
        return math.nan, math.nan
    i = int(np.nanargmax(g))
    if i == 0 or i == len(g) - 1:
        return float(omegas[i]), float(g[i])
    lo, hi = pts[i - 1], pts[i + 1]
    f_lo, f_hi = lo.dalpha.real, hi.dalpha.real
    if not (f_lo * f_hi < 0):
        return float(omegas[i]), float(g[i])
    a, b, fa, fb = lo.omega, hi.omega, f_lo, f_hi
    best = pts[i]
    for _ in range(30):
        w = b - fb * (b - a) / (fb - fa)
        if not (min(a, b) < w < max(a, b)):
            w = 0.5 * (a + b)
        try:
            best = _solve(branch, w, complex(best.k_real), policy, flow)
        except ConvergenceError:
            return float(omegas[i]), float(g[i])
        fw = best.dalpha.real
        if fa * fw < 0:
            b, fb = w, fw
        else:
            a, fa = w, fw
        if abs(b - a) <= 1e-8 * w or abs(fw) <= 1e-12:
            break
    return float(best.omega), float(best.spatial_growth)


def spatial_peak(branch: Branch, k_peak: float, policy: SpatialPolicy | None = None):
    """The most amplified frequency found directly: the complex k* on the spatial branch where
    d(−Im k)/dω = 0, i.e. (along α(k(ω)) = −iω, dk/dω = −i/α') Re(1/α'(k*)) = 0, so

        Re α(k*) = 0   and   Re α'(k*) = 0,

    two real equations in (Re k, Im k), solved by Newton's method with the exact 2 × 2
    Jacobian (α analytic: ∂/∂Re k = α', ∂/∂Im k = iα', and the same for α' with α'').
    Started from the refined temporal peak ``k_peak`` (real, Re α' = 0 there), whose first
    step is Gaster's −Im k = Re α/c_g. Returns the eigenpair at k* (ω_max = −Im α(k*),
    spatial growth −Im k*); raises :class:`~chuteflow.errors.ConvergenceError` where Newton
    does not settle or leaves Re k > 0. It replaces sampling ω (the dispersion curve,
    :func:`spatial_dispersion`) where only the maximum is wanted (the sweep metric)."""
    policy = DEFAULT_SPATIAL_POLICY if policy is None else policy
    e = branch.at(complex(k_peak))
    for _ in range(policy.maxiter):
        F = np.array([e.alpha.real, e.dalpha.real])
        J = np.array(
            [[e.dalpha.real, -e.dalpha.imag], [e.d2alpha.real, -e.d2alpha.imag]],
            dtype=float,
        )
        try:
            da, db = np.linalg.solve(J, -F)
        except np.linalg.LinAlgError:
            break
        if not (np.isfinite(da) and np.isfinite(db)):
            break
        k = e.k + complex(da, db)
        e = branch.at(k, start=e)
        # the step at the round-off of α' (~1e-10 |α'|, as for the saddle points: saddle_rtol)
        if abs(complex(da, db)) <= policy.saddle_rtol * max(abs(k), 1e-12):
            return e
    raise ConvergenceError(
        f"the most amplified frequency (Re alpha = Re alpha' = 0) did not settle from the temporal "
        f"peak k = {k_peak:.6g} (last k = {e.k:.6g})"
    )

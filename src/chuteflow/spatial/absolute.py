"""Absolute or convective: the Briggs–Bers saddle points of α(k) and the edges of the wave packet.

An impulse at x = 0 grows, along the ray x = V t, at the rate σ(V) = Re[α(k*) + i k* V] with
k* the saddle point of α(k) + ikV in the complex k plane (the frame moving at V sees
exp((α + ikV) t + ikx')):

    α'(k*) = −iV                                                    (steepest descent)

provided the saddle is a pinch of two spatial branches k⁺, k⁻ coming from opposite
half-planes (Briggs' collapse criterion). The flow is **absolutely** unstable when the lab
frame's σ(0) = Re α(k*₀) > 0 (a disturbance grows in place), **convectively** unstable when
σ(0) < 0 while σ(V) > 0 for some V (the packet grows but is swept away), and **stable** when
the temporal growth Re α(k) is negative for every real k. The packet's edges V₋ < V₊ are the
zeros of σ(V).

Limitation. The far-field decay rate κ = √(k²) has its branch cut on Re k = 0
(:mod:`chuteflow.stability.complex_k`). Where the saddle family continued from the temporal
peak reaches that cut (or k → 0, where α = 0 and the edge is the kinematic-wave speed
dQ0/dρ̄0) before σ(V) changes sign on a side, the edge found is that limit; at the paper's
points P1, P4, P5 the family never reaches V = 0 on this sheet, both edges are positive (P1:
4.1525 and 9.0043) and the verdict is ``"convective"``, resting on V₋ > 0. Where neither edge
is decided the verdict is ``"undetermined"`` and flagged, with the growing range found so far
in :attr:`rays`.

The lab frame (``lab_frame=True``). The impulse response at x = 0 is ∫ exp(α(k) t) dk over
real k, with α(k) computed with κ = |k|. Its half k > 0 is J = ∫_0^∞ exp(α₊(k) t) dk, with α₊
the eigenvalue of the pencil with κ = k (``sheet="continued"``), a polynomial in k and so
analytic across Re k = 0; the half k < 0 is the complex conjugate of J (the equations are
real). J's end point k = 0, where α₊(0) = 0 (mass conservation), contributes algebraically in
t; a saddle k* of α₊ contributes exp(α₊(k*) t) exactly where the steepest-descent deformation
of the half-line [0, ∞) (end point fixed) must pass through it. So the family is continued
from where it left the principal sheet down to V = 0 on the continued sheet
(:func:`_continue_to_lab`), and its saddle is checked by Briggs' collapse criterion adapted to
the half-line (:func:`_lab_pinch`): the two roots of α₊(k) = α₊(k*) + s are followed from k*
as s grows until Re α₊ exceeds every value on the contour; the path from one root's end through
k* to the other's must cross [0, ∞) an odd number of times (the contour, which the roots never
touch, is then trapped between them as s returns to 0; an even count lets it slide off, around
the end point if need be). The check runs along two target paths tilted by ±5 % in Im α (a
path straight up passes exactly through another critical value where α₊ is nearly real along
the saddle's ascent path) and stands only where both agree. Where it pinches, ``k_saddle``
and ``absolute_growth`` are that saddle's and the verdict follows its sign; otherwise they
stay NaN and the note says why (``lab_pinch``).

Method. At V_peak = c_g(k_peak), the group velocity at the temporal peak k_peak, the saddle is
k_peak itself (Re α'(k_peak) = 0) and σ(V_peak) = Re α(k_peak), the largest temporal growth.
The saddle is continued in V from there (Newton on α'(k) + iV = 0 with α'' exact, from the
predictor k* − i ΔV/α''(k*)) down through V = 0 until σ < 0 and up until σ < 0; V₋, V₊ are
refined by Newton on σ(V) with dσ/dV = −Im k* (the envelope theorem). The family continued
from the real axis is the one that pinches at V_peak (the two branches k(ω) on either side of
the real axis meet there). That pinch is checked (Briggs' collapse criterion) by following the
two roots of α(k) + ikV_peak = α_V(k*) + s from k* ± √(2s/α''(k*)) as s grows to
(1 + pinch_margin) × the largest temporal growth, above which no real k solves it: a pinch
when they end in opposite half-planes. Where the family reaches V = 0, the lab-frame
saddle's Re α(k*₀) is the absolute growth rate.

Resolution. The continuation, the edges' brackets and Briggs' check at V_peak run at the
coarse N = ``SpatialPolicy.coarse`` × N (0.6: N = 48 for N = 80), where an evaluation of α(k)
costs about a fifth; each edge is then refined at N (the coarse saddle nearest to it carried
over, Newton on σ(V) = 0 with dσ/dV = −Im k*), and so are the kinematic-wave speed, the saddle
of the temporal tests and the lab-frame steps. The edges at the paper's points agree with the
all-N continuation to 7e-9 (P1's branch-point V₋), 4e-8 (P4's V₊) and 1e-10 elsewhere.

The branch point. At the paper's points the family ends, on one side, at k* → 0 with σ → 0:
the branch point k = 0 of κ = √(k²), where α(0) = 0 (mass conservation). The ray there is
the kinematic-wave speed c0 = dQ0/dρ̄0 (Appendix B; −Im α'(0) = −Im α1 of
:mod:`chuteflow.longwave`), the edge of the packet on that side (long waves, whose growth
α2 k² vanishes as k → 0, travel at c0).
"""

from __future__ import annotations

import cmath
import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from ..closures import ChuteModel
from ..conventions import RATE_UNITS, VELOCITY_UNITS, WAVENUMBER_UNITS
from ..errors import ChuteflowError, ConvergenceError
from ..stability import branch_scan
from ..stability.scan import BranchScan
from ..steady import SteadyFlow
from ._core import DEFAULT_SPATIAL_POLICY, Branch, SpatialPolicy, check_flow, newton_k, newton_saddle

__all__ = ["AbsoluteResult", "absolute_instability", "VERDICTS"]

#: The verdicts of :func:`absolute_instability`.
VERDICTS = ("absolute", "convective", "stable", "undetermined")


@dataclass(frozen=True, eq=False)
class AbsoluteResult:
    """The Briggs–Bers analysis of one flow (module docstring).

    Attributes
    ----------
    k_saddle : complex
        The lab-frame saddle point k*₀ (α'(k*₀) = 0), 1/σ.
    alpha_saddle : complex
        α(k*₀); :attr:`absolute_growth` = Re α(k*₀).
    verdict : str
        ``"absolute"``, ``"convective"``, ``"stable"`` (Re α < 0 at every real k), or
        ``"undetermined"`` (flagged: the saddle family left the principal sheet through the
        branch cut Re k = 0 before deciding; the note says where).
    v_minus, v_plus : float
        The edges of the growing packet (σ(V) = 0), √(gσ); NaN for a stable flow.
    v_peak, growth_peak, k_peak : float
        The ray of fastest growth (the group velocity at the temporal peak), its growth rate
        (the largest temporal Re α) and the peak's k.
    pinch : bool or None
        The saddle of the ray :attr:`pinch_v` passes Briggs' collapse check (None: not
        decided or not checked).
    pinch_v : float
        The ray checked: V_peak, where the family's saddle is the real temporal peak.
    lab_pinch : bool or None
        Where the family leaves the principal sheet before V = 0: whether its saddle continued
        to V = 0 on the continued sheet pinches the contour (module docstring, "The lab frame");
        :attr:`k_saddle` and :attr:`alpha_saddle` are that saddle's when True, NaN otherwise
        (None: the family reached V = 0 on the principal sheet, or the step was not taken or
        not decided; the note says which).
    kinematic_speed : float
        c0, where the family ends at the branch point k = 0 (NaN if it does not).
    rays : tuple of ndarray
        (V, σ(V), Re k*, Im k*) along the continuation (at the coarse N of
        :attr:`SpatialPolicy.coarse`, 0.6 N by default; the edges are refined at N).
    n : int
        Resolution N of the operator.
    drift, tail : float
        The temporal tests at the lab-frame saddle.
    converged : bool
        Every step settled, the saddle passes the drift/tail tests and pinches.
    note : str
        Why it is flagged.
    """

    k_saddle: complex
    alpha_saddle: complex
    verdict: str
    v_minus: float
    v_plus: float
    v_peak: float
    growth_peak: float
    k_peak: float
    pinch: bool | None
    pinch_v: float
    kinematic_speed: float
    rays: tuple = field(repr=False)
    n: int
    drift: float
    tail: float
    converged: bool
    lab_pinch: bool | None = None
    note: str = ""
    theta: float = math.nan
    nu0: float = math.nan
    model: ChuteModel | None = field(default=None, repr=False)

    @property
    def absolute_growth(self) -> float:
        return float(self.alpha_saddle.real)

    def to_dict(self) -> dict:
        """JSON-ready scalars (the keys of ``chuteflow absolute --json``)."""
        return {
            "theta": self.theta,
            "nu0": self.nu0,
            **(self.model.to_dict() if self.model is not None else {}),
            "k_saddle_re": float(self.k_saddle.real),
            "k_saddle_im": float(self.k_saddle.imag),
            "absolute_growth": self.absolute_growth,
            "absolute_frequency": float(-self.alpha_saddle.imag),
            "verdict": self.verdict,
            "v_minus": self.v_minus,
            "v_plus": self.v_plus,
            "v_peak": self.v_peak,
            "growth_peak": self.growth_peak,
            "k_peak": self.k_peak,
            "pinch": self.pinch,
            "pinch_v": self.pinch_v,
            "kinematic_speed": self.kinematic_speed,
            "lab_pinch": self.lab_pinch,
            "n": int(self.n),
            "drift": self.drift,
            "tail": self.tail,
            "converged": bool(self.converged),
            "note": self.note,
        }

    def to_xarray(self):
        """σ(V) and the saddle k*(V) along the rays, as an :class:`xarray.Dataset` over V."""
        import xarray as xr

        V, s, kr, ki = self.rays
        ds = xr.Dataset(
            {
                "growth": ("V", s, {"units": RATE_UNITS, "long_name": "growth rate along the ray x = V t"}),
                "k_saddle_re": ("V", kr, {"units": WAVENUMBER_UNITS}),
                "k_saddle_im": ("V", ki, {"units": WAVENUMBER_UNITS}),
            },
            coords={"V": ("V", V, {"units": VELOCITY_UNITS, "long_name": "ray speed"})},
        )
        d = self.to_dict()
        ds.attrs.update({k: (str(v) if isinstance(v, bool) or v is None else v) for k, v in d.items()})
        if self.model is not None:
            ds.attrs.update(self.model.attrs())
        return ds


def _ray_growth(e, V: float) -> float:
    return float((e.alpha + 1j * e.k * V).real)


def _continue(
    branch: Branch, e0, V0: float, direction: float, dV0: float, policy, k_small: float, unrefined: list
):
    """Continue the saddle from (e0, V0) in V along ``direction`` until σ(V) changes sign
    (downwards also until V = 0 is passed, to land on the lab frame); an edge whose
    refinement fails is the secant estimate, with the reason appended to ``unrefined``. Returns
    (samples [(V, e)], edge V where σ = 0 or NaN, end), ``end`` one of ``"done"``,
    ``"branch point"`` (|k*| < ``k_small``: the family ends at k = 0, where α(0) = 0), ``"cut"``
    (it reaches Re k = 0 at finite |k|, where the continuation is not analytic)."""
    out = [(V0, e0)]
    V, e, dV = V0, e0, dV0
    edge = math.nan
    passed_zero = direction > 0 or V0 <= 0
    for _ in range(400):
        V_new = V + direction * dV
        if not passed_zero and V_new * V < 0:
            V_new = 0.0  # land on the lab frame exactly
        pred = e.k - 1j * (V_new - V) / e.d2alpha
        try:
            if pred.real <= 0:
                raise ConvergenceError("the predictor crosses the branch cut")
            e_new = newton_saddle(branch, pred, V_new, policy, start=e)
            _check_same_family(e, pred, e_new)
        except ChuteflowError:
            dV *= 0.5
            if dV < 1e-4 * dV0:
                near_zero = abs(e.k) < k_small and abs(_ray_growth(e, V)) < 1e-2 * abs(_ray_growth(e0, V0))
                return out, edge, ("branch point" if near_zero else "cut")
            continue
        s_old, s_new = _ray_growth(e, V), _ray_growth(e_new, V_new)
        out.append((V_new, e_new))
        if V_new == 0.0:
            passed_zero = True
        if s_old > 0 >= s_new and math.isnan(edge):
            try:
                edge = _edge(branch, V, e, V_new, e_new, policy)
            except ChuteflowError as exc:
                # the secant between the bracketing saddles, flagged by the caller's note
                edge = V + (V_new - V) * s_old / (s_old - s_new)
                unrefined.append(f"{exc}; the secant estimate {edge:.6g} is reported")
        V, e = V_new, e_new
        if abs(e.k) < k_small and abs(s_new) < 1e-2 * abs(_ray_growth(e0, V0)):
            return out, edge, "branch point"
        if passed_zero and (not math.isnan(edge) or _ray_growth(e0, V0) <= 0):
            break
        dV = min(dV * 1.5, 4 * dV0)
    return out, edge, "done"


#: A continuation step in V is accepted only where Newton's saddle lies within this fraction
#: of the predictor's step from the predictor (a first-order predictor errs by O(ΔV²)): a
#: corrector that travels further has found another saddle family (at P5, steps of 0.04 and
#: 0.08 V_peak jumped from k* = 1.6e-3 to the family at k* ≈ 0.028 − 0.012i and reported its
#: σ < 0 as the edge) or the step is too long to trust; either way the step is halved.
CORRECTOR_RATIO = 0.5

#: The sheet of κ(k) on which the lab-frame saddle is sought beyond the cut (module docstring).
LAB_SHEET = "continued"

#: A root path of the lab-frame pinch check that crosses the real axis within this fraction
#: of |k*| of k = 0 passes through the contour's end point k = 0 (module docstring, "The lab
#: frame"); it counts as a crossing of the half-line [0, ∞).
ENDPOINT_RTOL = 1e-6

#: Newton's relative step on k at which a root of the lab-frame pinch check is settled.
PINCH_K_RTOL = 1e-8

#: The tilt η of the target paths α(k*) + s (1 ± iη) of the lab-frame collapse check.
PINCH_TILT = 0.05


def _check_same_family(e, pred: complex, e_new) -> None:
    """Raise :class:`ConvergenceError` where the corrector moved further from the predictor
    than ``CORRECTOR_RATIO`` × the predictor's step (:data:`CORRECTOR_RATIO`)."""
    step = abs(pred - e.k)
    moved = abs(e_new.k - pred)
    if moved > CORRECTOR_RATIO * step + 1e-9 * abs(e.k):
        raise ConvergenceError(
            f"the saddle moved {moved:.2g} from the predictor, more than {CORRECTOR_RATIO:g} × its step "
            f"{step:.2g}: another saddle family or too long a step"
        )


def _edge(branch, Va, ea, Vb, eb, policy) -> float:
    """σ(V) = 0 between Va (σ > 0) and Vb (σ ≤ 0): Newton with dσ/dV = −Im k*, kept in the
    bracket by bisection."""
    lo, hi = Va, Vb
    V, e = Vb, eb
    for _ in range(60):
        s = _ray_growth(e, V)
        ds = -e.k.imag
        V_new = V - s / ds if ds != 0 else 0.5 * (lo + hi)
        if not (min(lo, hi) < V_new < max(lo, hi)):
            V_new = 0.5 * (lo + hi)
        e_new = None
        for _half in range(30):
            pred = e.k - 1j * (V_new - V) / e.d2alpha
            try:
                e_new = newton_saddle(branch, pred, V_new, policy, start=e)
                _check_same_family(e, pred, e_new)
                break
            except ChuteflowError:
                e_new = None
                V_new = 0.5 * (V + V_new)  # a shorter step from the last settled saddle
        if e_new is None:
            raise ConvergenceError(f"the edge between V = {Va:.6g} and {Vb:.6g} was not refined")
        if abs(V_new - V) <= 1e-10 * max(abs(V_new), 1.0):
            return float(V_new)
        if _ray_growth(e_new, V_new) > 0:
            lo = V_new
        else:
            hi = V_new
        V, e = V_new, e_new
    return float(V)


def _refine_edge(branch: Branch, cb: Branch, edge: float, side: list, policy, unrefined: list) -> float:
    """The edge ``edge`` found at the coarse N of ``cb`` refined at ``branch``'s N: the coarse
    saddle nearest to it carried over (:meth:`Branch.transfer`), then Newton on σ(V) = 0 with
    dσ/dV = −Im k* (the envelope theorem), each step a saddle at the new V. NaN stays NaN; a
    refinement that fails keeps the coarse edge, noted in ``unrefined``."""
    if math.isnan(edge):
        return edge
    V, e_c = min(side, key=lambda t: abs(t[0] - edge))
    try:
        e = branch.transfer(e_c, cb)
        for _ in range(20):
            pred = e.k - 1j * (edge - V) / e.d2alpha
            e_new = newton_saddle(branch, pred, edge, policy, start=e)
            _check_same_family(e, pred, e_new)
            V, e = edge, e_new
            ds = -e.k.imag
            step = -_ray_growth(e, V) / ds if ds != 0 else math.nan
            if not math.isfinite(step):
                break
            edge = V + step
            if abs(step) <= 1e-10 * max(abs(V), 1.0):
                return float(edge)
    except ChuteflowError as exc:
        unrefined.append(f"the edge {edge:.6g} was not refined at N = {branch.n} ({exc})")
        return edge
    unrefined.append(f"the edge {edge:.6g} was not refined at N = {branch.n}")
    return edge


def _march(pairs: list, s: float, s_end: float, advance, *, floor: float, regrow: bool, on_step=None) -> list:
    """Follow the two roots of a collapse check (:func:`_pinch`, :func:`_crossings`) from the
    target's parameter ``s`` to ``s_end``: ``advance(pairs, s, s_new)`` gives the roots at
    ``s_new`` (a ChuteflowError where the step was too long). Steps of ×3 in s; after a failed
    step (or the two roots falling onto one) the factor shrinks to its square root, down to
    ``floor`` (then the failure is raised), and with ``regrow`` it grows back ×1.5 (at most
    3) after each step taken, when ``on_step(s_new, roots)`` is called. Returns the roots at
    ``s_end``."""
    factor = 3.0
    while s < s_end:
        s_new = min(s_end, factor * s)
        try:
            nxt = advance(pairs, s, s_new)
            if abs(nxt[0].k - nxt[1].k) <= 1e-6 * abs(nxt[0].k):
                raise ConvergenceError("the two roots fell onto one")
        except ChuteflowError:
            if factor <= floor:
                raise
            factor = max(floor, factor**0.5)
            continue
        pairs, s = nxt, s_new
        if on_step is not None:
            on_step(s, pairs)
        if regrow:
            factor = min(3.0, factor * 1.5)
    return pairs


def _pinch(branch: Branch, e, V: float, growth_peak: float, policy: SpatialPolicy) -> tuple[bool | None, str]:
    """Briggs' collapse check at the saddle ``e`` of the frame V (module docstring): the two
    roots of α(k) + ikV = α_V* + s, from k* ± √(2s/α''), followed as s grows until Re of the
    target exceeds (1 + pinch_margin) × the largest temporal growth (above which no real k
    solves it), end in opposite half-planes."""
    a_v = e.alpha + 1j * e.k * V
    # only the roots' half-planes matter: Newton on k stops at PINCH_K_RTOL
    policy = dataclasses.replace(policy, k_rtol=max(policy.k_rtol, PINCH_K_RTOL))
    s_end = (1.0 + policy.pinch_margin) * max(growth_peak, 0.0) - a_v.real
    if s_end <= 0:
        s_end = abs(a_v.real) + max(growth_peak, 0.0) + 1e-6
    s = 1e-3 * s_end
    root = cmath.sqrt(2.0 * s / e.d2alpha)

    def advance(pairs: list, s: float, s_new: float) -> list:
        nxt = []
        for p in pairs:
            d = p.dalpha + 1j * V
            dk = (s_new - s) / d
            dk -= 0.5 * p.d2alpha * dk * dk / d  # second order: α' Δk + α'' Δk²/2 = Δs
            nxt.append(newton_k(branch, p.k + dk, a_v + s_new, policy, start=p, V=V))
        return nxt

    try:
        pairs = [newton_k(branch, k0, a_v + s, policy, start=e, V=V) for k0 in (e.k + root, e.k - root)]
        # a step too long for the predictor: shorter ones, down to the old fixed 1.5
        pairs = _march(pairs, s, s_end, advance, floor=1.5, regrow=False)
    except ChuteflowError as exc:
        return None, f"the pinch was not decided ({exc})"
    im = [p.k.imag for p in pairs]
    if im[0] * im[1] < 0:
        return True, ""
    return False, (
        f"the saddle of the ray V = {V:.4g} does not pinch: at growth {a_v.real + s_end:.3g} both spatial "
        f"branches lie in one half-plane (Im k = {im[0]:.3g}, {im[1]:.3g})"
    )


def _continue_to_lab(branch: Branch, V0: float, e0, dV0: float, policy: SpatialPolicy):
    """Continue the saddle family from (``e0``, ``V0``), where it left the principal sheet
    (the cut Re k = 0, or the branch point k = 0), down to the lab frame V = 0 on the continued
    sheet κ = k (module docstring, "The lab frame"). Returns (samples [(V, e)], the saddle at
    V = 0 or None, why not)."""
    out = [(V0, e0)]
    V, e, dV = V0, e0, dV0
    for _ in range(400):
        if V <= 0.0:
            return out, e, ""
        V_new = max(V - dV, 0.0)
        pred = e.k - 1j * (V_new - V) / e.d2alpha
        try:
            step = abs(pred - e.k)
            e_new = newton_saddle(
                branch, pred, V_new, policy, start=e, sheet=LAB_SHEET, max_step=step + 1e-9 * abs(e.k)
            )
            _check_same_family(e, pred, e_new)
        except ChuteflowError as exc:
            dV *= 0.5
            if dV < 1e-4 * dV0:
                return out, None, f"the saddle family stops at V = {V:.4g} on the continued sheet ({exc})"
            continue
        out.append((V_new, e_new))
        V, e = V_new, e_new
        dV = min(dV * 1.5, 4 * dV0)
    return out, None, f"the saddle family did not reach V = 0 on the continued sheet (last V = {V:.4g})"


def _half_line_crossings(path: list) -> list:
    """The points where the polyline ``path`` [(s, k)] crosses the real axis, as
    (index of the segment, Re k at the crossing by linear interpolation)."""
    out = []
    for i in range(len(path) - 1):
        a, b = path[i][1], path[i + 1][1]
        if a.imag == b.imag or (a.imag > 0) == (b.imag > 0) and a.imag != 0 and b.imag != 0:
            continue
        t = -a.imag / (b.imag - a.imag)
        out.append((i, a.real + t * (b.real - a.real)))
    return out


def _lab_pinch(branch: Branch, e, growth_peak: float, policy: SpatialPolicy) -> tuple[bool | None, str]:
    """Whether the lab-frame saddle ``e`` on the continued sheet pinches the half-line
    contour [0, ∞) of the impulse response's k > 0 half (module docstring, "The lab frame").

    The two roots of α(k) = α(k*) + s w, from k* ± √(2sw/α''), are followed as s grows until
    Re α(k*) + s exceeds (1 + pinch_margin) × the largest temporal growth (no point of the
    contour reaches that level); the path from one root's end through k* to the other's
    crosses [0, ∞) an odd number of times exactly when the contour cannot be pulled off the
    saddle. w = 1 ± i :data:`PINCH_TILT`: the straight path w = 1 (Briggs' lowering of Im ω at
    fixed Re ω) is degenerate where α is real along the saddle's steepest-ascent path (at P5
    the roots run along the imaginary axis into another saddle); the two tilted paths pass
    such a critical value on either side, and the answer stands only where both agree (None
    otherwise)."""
    pol = dataclasses.replace(policy, k_rtol=max(policy.k_rtol, PINCH_K_RTOL))
    try:
        found = [_crossings(branch, e, growth_peak, pol, complex(1.0, t)) for t in (PINCH_TILT, -PINCH_TILT)]
    except ChuteflowError as exc:
        return None, f"the lab-frame pinch was not decided ({exc})"
    odd = [c % 2 == 1 for c, _, _, _ in found]
    count, at_end, ends, level = found[0]
    if odd[0] != odd[1]:
        return None, (
            f"the lab-frame pinch of the saddle k* = {e.k:.10g}, alpha* = {e.alpha:.10g} on the continued "
            f"sheet was not decided: the two tilted paths of the collapse check cross the half-line "
            f"[0, inf) {found[0][0]} and {found[1][0]} times"
            + (
                " (Re alpha* < 0 = alpha(0): it cannot make the flow absolute either way)"
                if e.alpha.real < 0
                else ""
            )
        )
    if odd[0]:
        return True, (
            f"the lab-frame saddle k* = {e.k:.6g} pinches through the contour's end point k = 0 "
            "(its steepest-descent path from k = 0 runs into the saddle)"
            if at_end
            else ""
        )
    return False, (
        f"the lab-frame saddle k* = {e.k:.6g} (growth {e.alpha.real:.4g}) on the continued sheet does "
        f"not pinch the contour: its spatial branches (ends {ends} at growth {level:.3g}) cross "
        f"the half-line [0, inf) {count} times"
    )


def _crossings(branch: Branch, e, growth_peak: float, policy: SpatialPolicy, w: complex):
    """The collapse check of :func:`_lab_pinch` along the target path α(k*) + s w: (number of
    crossings of [0, ∞), how many of them at k = 0, the roots' ends, the final growth)."""
    sh = LAB_SHEET
    a0 = e.alpha
    s_end = (1.0 + policy.pinch_margin) * max(growth_peak, 0.0) - a0.real
    if s_end <= 0:
        s_end = abs(a0.real) + max(growth_peak, 0.0) + 1e-6
    s = 1e-3 * s_end
    root = cmath.sqrt(2.0 * s * w / e.d2alpha)
    pairs = [newton_k(branch, k0, a0 + s * w, policy, start=e, sheet=sh) for k0 in (e.k + root, e.k - root)]
    paths: list[list] = [[(s, p)] for p in pairs]

    def advance(pairs: list, s: float, s_new: float) -> list:
        nxt = []
        for p in pairs:
            pred = p.k + (s_new - s) * w / p.dalpha
            q = newton_k(branch, pred, a0 + s_new * w, policy, start=p, sheet=sh, max_step=abs(pred - p.k))
            _check_same_family(p, pred, q)
            nxt.append(q)
        return nxt

    def record(s_new: float, nxt: list) -> None:
        for path, q in zip(paths, nxt):
            path.append((s_new, q))

    pairs = _march(pairs, s, s_end, advance, floor=1.01, regrow=True, on_step=record)
    count, at_end = 0, 0
    tol_end = ENDPOINT_RTOL * abs(e.k)
    for path in paths:
        # the saddle k* itself starts each path (α = α(k*) at s = 0)
        full = [(0.0, e)] + path
        for i, x in _half_line_crossings([(sv, q.k) for sv, q in full]):
            (sa, pa), (sb, pb) = full[i], full[i + 1]
            if abs(x) < 2 * abs(pb.k - pa.k):
                x = _locate_crossing(branch, a0, w, sa, pa, sb, pb, policy, tol_end)
            at_end += abs(x) <= tol_end
            count += x > -tol_end
    ends = ", ".join(f"{p.k:.4g}" for p in pairs)
    return count, at_end, ends, a0.real + s_end


def _locate_crossing(
    branch, a0: complex, w: complex, sa: float, pa, sb: float, pb, policy, tol_end: float
) -> float:
    """Re k where the root path of α(k) = a0 + s w crosses the real axis between the roots ``pa``
    at s = ``sa`` and ``pb`` at ``sb`` (Im k of opposite signs): the path is bisected in s (in
    √s from the saddle, ``sa`` = 0, where the root leaves k* like √s) until the linear
    interpolation's crossing x lies further from k = 0 than twice the bracket (its side is
    then certain); a bracket shorter than ``tol_end`` ends it (the path passes through
    k = 0: the returned x is within ``tol_end`` of 0)."""
    k_sad = pa.k if sa == 0.0 else None
    for _ in range(80):
        dk = abs(pb.k - pa.k)
        x = pa.k.real + (pb.k.real - pa.k.real) * (-pa.k.imag) / (pb.k.imag - pa.k.imag)
        if abs(x) >= 2 * dk or dk <= 0.5 * tol_end:
            return float(x)
        if sa == 0.0 and k_sad is not None:
            sm = 0.25 * sb
            k0, start = k_sad + 0.5 * (pb.k - k_sad), pb
        else:
            sm = 0.5 * (sa + sb)
            k0, start = pa.k + (sm - sa) * w / pa.dalpha, pa
        pm = newton_k(branch, k0, a0 + sm * w, policy, start=start, sheet=LAB_SHEET)
        if abs(pm.k - pa.k) > dk and abs(pm.k - pb.k) > dk:
            raise ConvergenceError(f"the root path left its bracket near k = {x:.3g} (s = {sm:.3g})")
        if (pm.k.imag > 0) == (pa.k.imag > 0):
            sa, pa = sm, pm
        else:
            sb, pb = sm, pm
    raise ConvergenceError(f"a crossing of the real axis near k = {x:.3g} was not located")


def _checked(res: AbsoluteResult, strict: bool) -> AbsoluteResult:
    """``res``, or with ``strict=True`` a :class:`ConvergenceError` where it is flagged."""
    if strict and not res.converged:
        raise ConvergenceError(
            f"absolute instability at theta = {res.theta:g}, nu0 = {res.nu0:g}: {res.note}"
        )
    return res


def _stable(flow: SteadyFlow, scan: BranchScan, peak, strict: bool) -> AbsoluteResult:
    """The verdict ``"stable"`` of a flow whose temporal growth is ≤ 0 at every k of its scan:
    no packet grows, nothing to continue."""
    nan = math.nan
    i = int(np.nanargmin(np.abs(scan.k - peak.k)))
    res = AbsoluteResult(
        k_saddle=complex(nan, nan),
        alpha_saddle=complex(nan, nan),
        verdict="stable",
        v_minus=nan,
        v_plus=nan,
        v_peak=nan,
        growth_peak=float(peak.growth),
        k_peak=float(peak.k),
        pinch=None,
        pinch_v=nan,
        kinematic_speed=nan,
        lab_pinch=None,
        rays=(np.empty(0), np.empty(0), np.empty(0), np.empty(0)),
        n=int(scan.n[i]),
        drift=float(scan.drift[i]),
        tail=float(scan.tail[i]),
        converged=bool(scan.converged),
        note="" if scan.converged else f"the temporal branch scan is not converged ({scan.note})",
        theta=flow.theta,
        nu0=flow.nu0,
        model=flow.model,
    )
    return _checked(res, strict)


def absolute_instability(
    flow: SteadyFlow,
    *,
    policy: SpatialPolicy | None = None,
    cache=None,
    strict: bool = False,
    check_pinch: bool = True,
    scan: BranchScan | None = None,
    lab_frame: bool = False,
) -> AbsoluteResult:
    """Absolute or convective instability of ``flow`` by the Briggs–Bers saddle points of its
    α(0) = 0 branch continued to complex k (module docstring).

    ``scan``: the temporal :func:`~chuteflow.stability.branch_scan` of ``flow`` when the
    caller has it (the sweep metric ``spatial``); computed here otherwise. Where its largest
    growth rate is ≤ 0 the flow is temporally stable: the verdict is ``"stable"`` at once,
    nothing is continued (the edges and the saddle are NaN).

    Returns an :class:`AbsoluteResult`; flagged (``converged=False``, ``note``) when a
    continuation step does not settle, an edge is not decided, the saddle misses the temporal
    tests or does not pinch (``strict=True``: :class:`~chuteflow.errors.ConvergenceError`
    instead).

    ``lab_frame=True``: where the saddle family leaves the principal sheet before V = 0 (the
    cut Re k = 0, or the branch point k = 0), continue it to V = 0 on the continued sheet and
    check its pinch (module docstring, "The lab frame"; :attr:`AbsoluteResult.lab_pinch`).
    Off by default: it costs 2–5 times the rest of the analysis at the paper's points (its steps
    run at the full N), where none of these saddles pinches decidedly.
    """
    flow = check_flow(flow)
    policy = DEFAULT_SPATIAL_POLICY if policy is None else policy
    if scan is None:
        scan = branch_scan(flow, policy=policy.rejection, cache=cache)
    peak = scan.peak()
    if not (math.isfinite(peak.k) and peak.k > 0):
        raise ConvergenceError("absolute instability: the temporal branch scan reached no point")
    if not (peak.growth > 0):
        return _stable(flow, scan, peak, strict)
    branch = Branch(flow, float(peak.k), policy, cache)
    e_peak = branch.last
    # the continuation and Briggs' check at the coarse N; the edges refined at N below
    cb = branch.coarsened(policy.coarse) if policy.coarse < 1 else branch
    e_peak_c = cb.last
    notes = []
    if not scan.converged:
        notes.append("the temporal branch scan is not converged")
    V_peak = float((1j * e_peak.dalpha).real)
    growth_peak = float(e_peak.alpha.real)
    # the saddle at V_peak: on the real axis up to the refinement of the peak
    e_sad = newton_saddle(branch, e_peak.k, V_peak, policy, start=e_peak)
    e_sad_c = e_sad if cb is branch else newton_saddle(cb, e_peak_c.k, V_peak, policy, start=e_peak_c)
    dV0 = policy.ray_step * max(abs(V_peak), 1e-3)
    # |k*| below which the family is at the branch point k = 0 (with σ < 1 % of the peak's)
    k_small = 0.05 * float(peak.k)
    unrefined: list[str] = []
    down, edge_down, end_down = _continue(cb, e_sad_c, V_peak, -1.0, dV0, policy, k_small, unrefined)
    up, edge_up, end_up = _continue(cb, e_sad_c, V_peak, +1.0, dV0, policy, k_small, unrefined)
    if cb is not branch:
        edge_down = _refine_edge(branch, cb, edge_down, down, policy, unrefined)
        edge_up = _refine_edge(branch, cb, edge_up, up, policy, unrefined)
    notes.extend(unrefined)
    samples = sorted(down + up[1:], key=lambda t: t[0])
    c0 = math.nan
    edges = {}
    for name, edge, end, side in (("down", edge_down, end_down, down), ("up", edge_up, end_up, up)):
        V_last, e_last = side[-1]
        if not math.isnan(edge):
            edges[name] = edge
        elif end == "branch point":
            # k* → 0 with σ → 0: the family ends at the branch point k = 0 of √(k²), where
            # α(0) = 0 (mass conservation); the ray there is the kinematic-wave speed c0
            # α'(k) = −i c0 + 2 α2 k + …: the linear term removed with α''
            k_bp = 2e-5 * float(peak.k)
            e_bp = branch.at(complex(k_bp, 0.0), start=branch.transfer(e_last, cb))
            c0 = float(-(e_bp.dalpha - e_bp.d2alpha * k_bp).imag)
            edges[name] = c0
            notes.append(
                f"one edge is the branch point k = 0 (alpha(0) = 0): V = c0 = {c0:.6g}, the "
                f"kinematic-wave speed (growth {_ray_growth(e_last, V_last):.2g} "
                f"at |k*| = {abs(e_last.k):.2g})"
            )
        elif growth_peak > 0:
            notes.append(
                f"the saddle family reaches the branch cut Re k = 0 at V = {V_last:.4g} "
                f"(k* = {e_last.k:.3g}, growth {_ray_growth(e_last, V_last):.3g}) "
                f"before the growth changes sign: that edge "
                "is not determined"
            )
    lab = [e for V, e in down if V == 0.0]
    e0 = lab[0] if lab else None
    if e0 is not None and cb is not branch:
        e0 = newton_saddle(branch, e0.k, 0.0, policy, start=branch.transfer(e0, cb))
    lab_pinch: bool | None = None
    lab_sheet = "principal"
    if e0 is None and lab_frame and growth_peak > 0:
        V_last, e_last = down[-1]
        # at N itself: the saddles across the cut are resolved less well than the family's
        # (at P4 the coarse N moves k* by 30 %)
        e_last = branch.transfer(e_last, cb)
        _, e_lab, why = _continue_to_lab(branch, V_last, e_last, dV0, policy)
        if e_lab is not None:
            lab_pinch, why = _lab_pinch(branch, e_lab, growth_peak, policy)
            if lab_pinch:
                e0, lab_sheet = e_lab, LAB_SHEET
        if why:
            notes.append(why)
    conflict = False
    if growth_peak <= 0:
        verdict, v_minus, v_plus = "stable", math.nan, math.nan
    else:
        v_minus = min(edges.values()) if len(edges) == 2 else math.nan
        v_plus = max(edges.values()) if len(edges) == 2 else math.nan
        if e0 is not None:
            verdict = "absolute" if e0.alpha.real > 0 else "convective"
            if len(edges) == 2 and (verdict == "absolute") != (v_minus < 0 < v_plus):
                conflict = True
                notes.append(
                    f"the lab-frame saddle (growth {e0.alpha.real:.4g}) and the edges "
                    f"(V- = {v_minus:.6g}, V+ = {v_plus:.6g}) disagree"
                )
        elif len(edges) == 2:
            verdict = "absolute" if v_minus < 0 < v_plus else "convective"
        else:
            verdict = "undetermined"
    if e0 is not None:
        k0, a0 = complex(e0.k), complex(e0.alpha)
    else:
        k0, a0 = complex(math.nan, math.nan), complex(math.nan, math.nan)
        if growth_peak > 0 and not lab_frame:
            notes.append("no saddle of the family at V = 0 (the lab frame lies outside the continuation)")
    # Briggs' check on the family at the ray of fastest growth V_peak, where its saddle is the
    # real temporal peak; the continuation in V carries that pinch along the family
    pinch: bool | None = None
    pinch_V = math.nan
    if check_pinch and growth_peak > 0:
        pinch_V = V_peak
        pinch, why = _pinch(cb, e_sad_c, V_peak, growth_peak, policy)
        if why:
            notes.append(why)
    e_conv = e0 if e0 is not None else e_sad
    drift, tl, _ = branch.convergence(e_conv, sheet=lab_sheet if e0 is not None else "principal")
    if not policy.rejection.accepts(drift, tl):
        notes.append(f"the saddle misses the temporal tests (drift {drift:.1e}, tail {tl:.1e})")
    ok = (
        policy.rejection.accepts(drift, tl)
        and (pinch is True or not check_pinch or growth_peak <= 0)
        and scan.converged
        and verdict != "undetermined"
        and not unrefined
        and not conflict
    )
    V = np.array([v for v, _ in samples])
    res = AbsoluteResult(
        k_saddle=k0,
        alpha_saddle=a0,
        verdict=verdict,
        v_minus=float(v_minus),
        v_plus=float(v_plus),
        v_peak=V_peak,
        growth_peak=growth_peak,
        k_peak=float(peak.k),
        pinch=pinch,
        pinch_v=float(pinch_V),
        kinematic_speed=c0,
        lab_pinch=lab_pinch,
        rays=(
            V,
            np.array([_ray_growth(e, v) for v, e in samples]),
            np.array([e.k.real for _, e in samples]),
            np.array([e.k.imag for _, e in samples]),
        ),
        n=branch.n,
        drift=drift,
        tail=tl,
        converged=bool(ok),
        note="; ".join(notes),
        theta=flow.theta,
        nu0=flow.nu0,
        model=flow.model,
    )
    return _checked(res, strict)

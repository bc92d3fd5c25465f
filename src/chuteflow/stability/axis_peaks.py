"""The largest growth rate of the α(0) = 0 branch along each axis of the (k_x, k_z) plane.

For the sweep metric ``transverse`` (:mod:`chuteflow.sweep.transverse`): along the slope
(k_z = 0) :func:`longitudinal_peak` follows the branch by
:class:`~chuteflow.stability.BranchTracker` through a geometric scan in k_x; across it
(k_x = 0) :func:`transverse_peak` follows it by
:class:`~chuteflow.stability.transverse_tracking.TransverseTracker` in k_z. Each scan stops
past the cut-off k_c of the long-wave band (the first sign change of Re α, from + to −: the
rule of :mod:`chuteflow.stability.scan`), refines the maximum by a bounded search in ln k
and judges only the mode there. These are dispersion scans, not long-wave theory: α2z
(:func:`chuteflow.longwave.transverse_longwave`) is only the transverse predictor's input.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import minimize_scalar

from .._memory import brentq  # scipy's, without keeping the trackers alive (a cycle)
from ..errors import ConvergenceError
from ..steady import SteadyFlow
from .modes import Mode, OperatorCache, nearest_eigenpair, stability_operator
from .policy import DEFAULT_POLICY, RejectionPolicy
from .scan import critical_index, peak_index, sign_changes
from .tracking import BranchTracker
from .transverse import judge_resolved
from .transverse_tracking import TransverseTracker

__all__ = [
    "GrowthPeak",
    "LONGITUDINAL_RUNGS",
    "NUDGE",
    "PEAK_RATIO",
    "PEAK_XATOL",
    "SCAN_HALVINGS",
    "cutoff_of_branch",
    "longitudinal_peak",
    "transverse_peak",
]


@dataclass(frozen=True)
class GrowthPeak:
    """The largest growth rate of the α(0) = 0 branch along one axis of the (k_x, k_z) plane.

    Attributes
    ----------
    direction : str
        ``"longitudinal"`` (k_z = 0, along the slope) or ``"transverse"`` (k_x = 0).
    growth : float
        Largest Re α found (the least negative where the branch decays everywhere; NaN when
        no point of the branch was resolved).
    k : float
        Wavenumber of that maximum along the axis.
    alpha_im : float
        Im α there.
    cutoff : float or None
        First sign change of Re α, when from + to − (the upper edge of the long-wave unstable
        band, the k_c rule of :mod:`chuteflow.stability.scan`), None if the branch was not
        followed that far or the first change goes from − to +.
    mode : Mode or None
        The mode at the maximum, judged by the policy (drift |α(N) − α(N')|, tail; N raised
        along the ladder while it is not physical).
    solves : int
        Shift-invert solves (LU factorisations) spent.
    """

    direction: str
    growth: float
    k: float
    alpha_im: float
    cutoff: float | None
    mode: Mode | None = field(repr=False, default=None)
    solves: int = 0

    @property
    def physical(self) -> bool:
        """The mode at the maximum passes the drift and tail tests."""
        return bool(self.mode is not None and self.mode.physical)


#: Ratio of successive wavenumbers of the coarse scan of :func:`longitudinal_peak` and
#: :func:`transverse_peak` (the maximum is then refined by parabolic interpolation in ln k).
PEAK_RATIO = 1.6
#: Tolerance in ln k of the refined maximum (2 % in k, as :func:`chuteflow.longwave.transverse`).
PEAK_XATOL = 0.02


def _refine_peak(f, xs, ys, *, xatol: float = PEAK_XATOL, maxiter: int = 12):
    """The maximum of y(x) in the bracket xs[0] < xs[1] < xs[2] (ys[1] the largest of the
    three) by Brent's bounded search (parabolic steps safeguarded by golden sections: the
    growth rate near its maximum is skewed in ln k, towards the cut-off, and plain
    successive parabolas stall on the far side).

    ``f(x)`` returns (y, payload) or None (no trustworthy value, taken as −∞). Returns
    (x, y, payload, evaluations) of the best point evaluated, payload None if none beat
    ys[1]."""
    seen: dict = {}

    def minus(x):
        got = f(x)
        seen[x] = got
        return -got[0] if got is not None else math.inf

    minimize_scalar(
        minus, bounds=(xs[0], xs[2]), method="bounded", options={"xatol": xatol, "maxiter": maxiter}
    )
    best = max(((x, g) for x, g in seen.items() if g is not None), key=lambda t: t[1][0], default=None)
    if best is None or best[1][0] <= ys[1]:
        return xs[1], ys[1], None, len(seen)
    return best[0], best[1][0], best[1][1], len(seen)


def _quad_log(ks, values, k):
    """Quadratic interpolation in ln k through three points (complex values allowed)."""
    x = np.log(np.asarray(ks, dtype=float))
    v = np.asarray(values)
    c_re = np.polyfit(x, v.real, len(x) - 1)
    c_im = np.polyfit(x, v.imag, len(x) - 1)
    return complex(np.polyval(c_re, math.log(k)), np.polyval(c_im, math.log(k)))


#: Factor by which :func:`longitudinal_peak` moves a scan point where the continuation
#: fails (θ = 15.43°, ν0(0) = 0.0443, φ = 0.05: lost at k = 1.6e-4 at N = 48–75, followed
#: through 1.58e-4).
NUDGE = 1.04
#: Step halvings of the continuation allowed per scan point (the tracker's default 16 costs
#: tens of seconds where the branch is lost at k ~ 1e-5, and the scan's points are close).
SCAN_HALVINGS = 8
#: Resolutions of the ladder tried by :func:`longitudinal_peak` before it gives up: where
#: the branch is lost before its maximum at N = 48, 60 and 75 it is lost at every N of the
#: old 20-point scan up to 160 too. (Thick dilute flows, e.g. θ = 17.5°, ν0(0) = 0.02 at
#: φ = 0.05, where the branch was lost near k = 1e-5 at every N, were the tracker's first
#: step from k = 0 accepted off α1 k, TrackingPolicy.first_step_min; a rule that gave up after two rungs
#: lost before the first scan point was dropped with it: dense thin flows, θ = 16°,
#: ν0(0) = 0.25, need N = 75, eigenvector tails 1.8e-4 and 1.8e-5 at N = 48 and 60.)
LONGITUDINAL_RUNGS = 3


def longitudinal_peak(
    flow: SteadyFlow,
    *,
    k_min: float = 1e-4,
    k_max: float = 0.05,
    ratio: float = PEAK_RATIO,
    n: int = 48,
    policy: RejectionPolicy | None = None,
    cache: OperatorCache | None = None,
) -> GrowthPeak:
    """Largest growth rate of the α(0) = 0 branch along the slope (k_z = 0), for sweeps.

    The branch is continued from k = 0 (:class:`~chuteflow.stability.BranchTracker`, 2D
    operator on the sinh-mapped grid at N = ``n``) through the geometric scan k_min,
    k_min·``ratio``, … ≤ ``k_max``, which stops where Re α has turned negative after
    being positive (past the cut-off k_c of the long-wave band: the longitudinal
    instability is long-wave, §4.2 and the ``growth`` metric's check). The largest Re α of
    the scan is refined by parabolic interpolation in ln k (to 2 % in k), and only the mode
    there is judged (drift at N' = 0.8 N and tail), N raised along ``policy``'s ladder
    while it is not physical. If the branch is lost before its maximum the scan is redone
    at the next N (at most :data:`LONGITUDINAL_RUNGS` resolutions).

    Raises
    ------
    ConvergenceError
        If the branch cannot be followed past its maximum at those resolutions.
    """
    policy = policy or RejectionPolicy(n_start=n, n_max=160)
    last_exc: Exception | None = None
    tried: list[int] = []
    for n_t in policy.ladder(n)[:LONGITUDINAL_RUNGS]:
        tried.append(n_t)
        tr = BranchTracker(flow, n_t, policy=policy, cache=cache)
        ks: list[float] = []
        alphas: list[complex] = []
        vecs: list[np.ndarray] = []
        k, lost = float(k_min), False
        while True:
            got = None
            # a step that ends where the branch meets a continuum eigenvalue fails (the
            # advected continuum Im α = −k u0(y) crosses it at isolated k): restart from
            # the last scan point with a nudged target, stepping over that k
            for kk in (k, k * NUDGE) if ks else (k,):
                try:
                    if kk != k:
                        tr = BranchTracker(flow, n_t, policy=policy, cache=cache)
                        tr.advance(ks[-1], max_halvings=SCAN_HALVINGS)
                    got = tr.advance(kk, max_halvings=SCAN_HALVINGS)
                    k = kk
                    break
                except ConvergenceError as exc:
                    last_exc = exc.with_traceback(None)  # (for its message; no frame cycle)
            if got is None:
                lost = True
                break
            a, v = got
            ks.append(k)
            alphas.append(complex(a))
            vecs.append(v)
            if a.real <= 0 and any(b.real > 0 for b in alphas):
                break  # past the cut-off
            if k >= k_max:
                break
            k = min(k * ratio, float(k_max))
        g = np.array([a.real for a in alphas])
        if len(g) and not (lost and int(np.argmax(g)) == len(g) - 1):
            return _peak_2d(flow, tr, ks, alphas, vecs, policy, cache)
    raise ConvergenceError(
        f"longitudinal branch at theta = {flow.theta:g}, nu0 = {flow.nu0:g} lost before its "
        f"maximum at N = {tried} ({last_exc})"
    )


def _peak_2d(flow, tr, ks, alphas, vecs, policy, cache) -> GrowthPeak:
    """Refine and judge the maximum of a longitudinal scan (:func:`longitudinal_peak`)."""
    g = np.array([a.real for a in alphas])
    j = peak_index(g) or 0  # the branch scan's rule (chuteflow.stability.scan)
    n = tr.n
    solves = len(ks)
    k_best, a_best, v_best = ks[j], alphas[j], vecs[j]
    if 0 < j < len(ks) - 1:
        br = slice(j - 1, j + 2)

        def at(x):
            kk = math.exp(x)
            pred = _quad_log(ks[br], alphas[br], kk)
            i = int(np.argmin([abs(math.log(q / kk)) for q in ks[br]])) + j - 1
            try:
                pencil = stability_operator(flow, n, cache=cache).pencil(kk)
                a, w = nearest_eigenpair(pencil, pred, v0=vecs[i])
            except ConvergenceError:
                return None
            # the branch, not a neighbour of the continuum: close to the interpolation
            if abs(a - pred) > 0.05 * abs(pred):
                return None
            return a.real, (kk, complex(a), w)

        _, _, pay, ev = _refine_peak(at, [math.log(q) for q in ks[br]], list(g[br]))
        solves += ev
        if pay is not None:
            k_best, a_best, v_best = pay
    mode = judge_resolved(flow, k_best, 0.0, a_best, v_best, n, three_d=False, policy=policy, cache=cache)
    cut = None
    i = critical_index(g)  # k_c of the branch scan's rule (chuteflow.stability.scan)
    if i is not None:  # linear in ln k between the bracketing points
        (k0, a0), (k1, a1) = (ks[i], alphas[i]), (ks[i + 1], alphas[i + 1])
        t = a0.real / (a0.real - a1.real)
        cut = float(math.exp(math.log(k0) + t * math.log(k1 / k0)))
    m_alpha = mode.alpha if mode is not None else a_best
    return GrowthPeak(
        "longitudinal", float(m_alpha.real), float(k_best), float(m_alpha.imag), cut, mode, solves
    )


def transverse_peak(
    flow: SteadyFlow,
    *,
    alpha2z: float | None = None,
    kz_min: float = 1e-5,
    kz_max: float = 3.0,
    ratio: float = PEAK_RATIO,
    n: int | None = None,
    policy: RejectionPolicy = DEFAULT_POLICY,
    cache: OperatorCache | None = None,
) -> GrowthPeak:
    """Largest growth rate of the α(0) = 0 branch across the slope (k_x = 0), for sweeps.

    The branch is followed by :class:`~chuteflow.stability.TransverseTracker` (predictor
    ``alpha2z`` k_z², real inverse iteration on the plain grid at N = ``n``, default
    ``policy.n_start``) through the geometric scan k_z = ``kz_min``·``ratio``^j ≤
    ``kz_max``, until Re α turns negative after being positive or the branch enters the
    continuum of the dilute top. The maximum is refined by parabolic interpolation in
    ln k_z (to 2 %), the cut-off as by :func:`chuteflow.longwave.transverse`
    (:func:`cutoff_of_branch`: Brent's method on the branch, or the root of the quadratic
    through its last points where it is lost as it crosses zero), and only the mode at the
    maximum is judged (:meth:`TransverseTracker.judge
    <chuteflow.stability.transverse_tracking.TransverseTracker.judge>`). Where α2z > 0 but
    the branch is not resolved at its first step, the next N of the ladder is tried (at
    most :data:`LONGITUDINAL_RUNGS`). The same numbers as
    :func:`chuteflow.longwave.transverse` (its dispersion relation on a fixed grid, the
    lateral pressure and check values) at a fraction of the solves.
    """
    solves = 0
    for n_t in policy.ladder(n)[:LONGITUDINAL_RUNGS]:
        tr = TransverseTracker(flow, alpha2z=alpha2z, n=n_t, policy=policy, cache=cache, max_ratio=ratio)
        k, started = float(kz_min), False
        while k <= kz_max * (1 + 1e-12):
            pt = tr.advance(k)
            if pt is None:
                break
            started = True
            if pt.alpha.real <= 0 and any(p.alpha.real > 0 for p in tr.history):
                break
            k *= ratio
        solves += len(tr.history) - 1
        if started or alpha2z is None or alpha2z <= 0:
            break  # where α2z < 0 the branch is inside the continuum from the first step
    # every resolved point of the branch (the scan's and the continuation's own steps)
    pts = [p for p in tr.history if p.kz > 0]
    if not pts:
        return GrowthPeak("transverse", math.nan, math.nan, 0.0, None, None, solves)
    g = np.array([p.alpha.real for p in pts])
    j = peak_index(g) or 0  # the branch scan's rule (chuteflow.stability.scan)
    best = pts[j]
    xs = [math.log(p.kz) for p in pts[max(j - 1, 0) : j + 2]]
    ys = list(g[max(j - 1, 0) : j + 2])
    if j == len(pts) - 1 and j > 0 and tr.lost_at is not None and tr.lost_at > pts[j].kz:
        # the maximum is the last resolved point: the peak lies between it and the loss
        xs.append(math.log(tr.lost_at))
        ys.append(-math.inf)
    if j > 0 and len(xs) == 3:

        def at(x):
            pt = tr.point_at(math.exp(x))
            return None if pt is None else (pt.alpha.real, pt)

        _, _, pay, ev = _refine_peak(at, xs, ys)
        solves += ev
        if pay is not None:
            best = pay
    mode = tr.judge(best)
    ks = np.array([p.kz for p in pts])

    def growth_at(kk):
        a = tr.at(kk)
        return (a.real, a.imag) if a is not None else (-math.inf, 0.0)

    cut = cutoff_of_branch(ks, g, tr, growth_at)
    return GrowthPeak(
        "transverse", float(mode.alpha.real), float(best.kz), float(mode.alpha.imag), cut, mode, solves
    )


def cutoff_of_branch(ks, g, tr, growth_at) -> float | None:
    """Upper edge of the long-wave unstable band, decided as k_c of a branch scan
    (:func:`chuteflow.stability.scan.critical_index`: the first sign change of Re α, when it
    goes from + to −), on the grid or (tracked branch) on the tracker's own steps, refined by
    Brent's method; None where the first sign change goes from − to +.

    ``ks``, ``g``: the scan's wavenumbers and Re α (−∞ where unresolved); ``tr``: the
    :class:`~chuteflow.stability.transverse_tracking.TransverseTracker` that produced them,
    or None (a dense scan); ``growth_at(k)`` → (Re α, Im α) for the refinement. Where the
    tracked branch is lost as it crosses zero, the root of the quadratic through its last
    three points (if it lies before the loss)."""
    pts = list(zip(ks, g))
    if tr is not None:
        pts = sorted({(p.kz, p.alpha.real) for p in tr.history if p.kz > 0} | set(pts))
    gs = [q[1] for q in pts]
    i = critical_index(gs)
    if i is not None:
        (a, _), (b, _) = pts[i], pts[i + 1]
        return float(brentq(lambda k: growth_at(k)[0], float(a), float(b), rtol=1e-3, xtol=1e-12, maxiter=20))
    if sign_changes(gs):
        return None  # long-wave stable on the scan: no band 0 < k < k_c
    if tr is not None and tr.lost_at is not None and len(tr.history) >= 4 and tr.history[-1].alpha.real > 0:
        # the branch enters the continuum (Re α ≈ −1e-8 at P1) as it crosses zero: the root
        # of the quadratic through its last three points, if it lies before the loss
        h = tr.history[-3:]
        c = np.polyfit([p.kz for p in h], [p.alpha.real for p in h], 2)
        roots = [r.real for r in np.roots(c) if abs(r.imag) == 0 and h[-1].kz < r.real <= 1.05 * tr.lost_at]
        if roots:
            return float(min(roots))
    return None

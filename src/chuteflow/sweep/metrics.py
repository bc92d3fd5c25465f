"""Stability metrics of a sweep: long-wave coefficients, k_c, maximum growth, finite-k check.

- ``longwave``: α1 and the long-wave growth coefficient Re α(k)/k² at k = 1e-5 (§5.1.1,
  Appendix B) from :func:`chuteflow.longwave.theory.eigen_sign`; > 0 is long-wave
  instability (§4.2), the rule of :attr:`chuteflow.longwave.LongWave.unstable`.
- ``growth``: the dispersion relation of the α(0) = 0 branch tracked over a k grid: maximum
  growth rate, its k, and the critical k_c (the rule of :mod:`chuteflow.stability.scan`:
  the first sign change of Re α when it goes from + to −, refined). Computed on a
  sample of the points (every ``stride``-th point in θ and ν0, and every marked point), which
  is the check that no finite-k instability is missed by the long-wave criterion, and, with
  ``unstable_points=True``, at every long-wave unstable point.

The stability layer is imported inside ``compute``, so registering these classes never depends
on it.
"""

from __future__ import annotations

import math

import numpy as np

from ..conventions import RATE_UNITS
from ..errors import ConvergenceError, ParameterError
from ..longwave.theory import eigen_sign
from ..stability import BranchTracker, OperatorCache, RejectionPolicy
from ..stability.lost import after_lost_branch, relaxed_branch_modes
from ..stability.modes import check_n, nearest_eigenpair, stability_operator
from ..stability.scan import critical_index, linear_crossing, peak_index
from . import spatial as _spatial  # noqa: F401  (registers the metric "spatial")
from . import transverse as _transverse  # noqa: F401  (registers the metric "transverse")
from .points import PointFunction, Variable, register_point_function

__all__ = ["LongWaveMetric", "GrowthMetric", "default_metrics"]

_RATE = RATE_UNITS


@register_point_function
class LongWaveMetric(PointFunction):
    """Long-wave growth coefficient Re α/k² from the eigenvalue at k = 1e-5, resolved for its sign.

    The sign that classifies a point is that of Re α(k)/k² of the α(0) = 0 branch at
    k = :data:`~chuteflow.longwave.theory.K_EIG` = 1e-5, the rule of
    :attr:`chuteflow.longwave.LongWave.unstable`, so a diagram and ``chuteflow longwave``
    agree. It is computed by :func:`chuteflow.longwave.theory.eigen_sign`: perturbation
    theory at k = 0 and one shift-invert solve at k, at N and N' = round(0.8 N) on the
    sinh-mapped stability grid, N raised from ``n`` by 25 % until the two agree to ``rtol``
    (default 0.05: the sign has a margin of 20) or N = ``n_max``. N starts at 60 (version 6;
    48 before): on the 60 × 60 φ = 0.05 diagram 76 % of the flows need N ≥ 60, and for them
    the rung N = 38 was computed for nothing (their values are the same); the 24 % that
    passed at N = 48 now report the value at N = 60 (relative change ≤ 9 %, no sign changed
    at any of the 2645 flows; ``benchmarks/probes/metric_work.py longwave 2 --lw-n=60``), and
    the metric costs 11 % less. Version 7: the check rung N' is solved from the eigenpair at
    N (shift α(N), start vector interpolated) without the Taylor coefficients, which only
    the finer rung reports (one real LU less a flow, −12 % CPU of the metric on 661 flows
    of the 60 × 60 φ = 0.05 grid; α2 the same bit for bit, the estimate moved within the
    round-off of Re α(N'), ~1e-9 |α|). Version 8: the strict Taylor α2 (which feels the
    dilute top's continuum and converges only algebraically, docs/errata.md, and was never
    used) is computed only with the option ``taylor=True`` (``alpha2_taylor_re``, at the same
    N; missing otherwise): its bordered perturbation theory was a sixth of the metric's
    work. The eigenvalue at N is then found from the exact slope, shift α1 k, and the k = 0
    null vector V0 (eq. (B 2) and the steady tangent) instead of the grid's α1 k and
    V0 + k V1: on 661 flows of the 60 × 60 φ = 0.05 grid the same N everywhere but one
    flow, no sign changed, Re α/k² median 2e-7 relative from version 7; the largest changes
    (≤ 1.4 %) at flows with Re α/k² ≈ 1, where Re α ~ 1e-10 is within a few 1e-12 of
    round-off for either shift (``benchmarks/probes/longwave_start.py``); the metric's CPU
    −15 % (the 60 × 60 diagram's long-wave stage 49.6, 51.1 → 42.7, 41.2 s, alternated
    runs). α1 = −i dQ0/dρ̄0 (eq. (B 2))
    comes from the exact steady tangent (as accurate as the steady flow, ~1e-9), not from
    perturbation theory on the stability grid, which converges to it only as N⁻⁴.
    """

    name = "longwave"
    version = "8"
    requires = ("steady",)
    defaults = {"n": 60, "rtol": 0.05, "n_max": 160, "taylor": False}
    variables = (
        Variable(
            "alpha1_im",
            "sqrt(g sigma)",
            "Im α1 = −dQ0/dρ̄0 from the exact steady tangent (the long-wave phase velocity, "
            "positive down the slope, is −Im α1)",
            source="App. B, eq. (B 2)",
        ),
        Variable(
            "alpha2_re",
            "sigma^(3/2) g^(1/2)",
            "long-wave growth coefficient Re α(k)/k² of the branch's eigenvalue at k = 1e-5 "
            "(> 0: long-wave unstable)",
            source="§4.2, §5.1.1",
        ),
        Variable(
            "alpha2_convergence",
            "1",
            "relative change of Re α(k)/k² between N and round(0.8 N)",
        ),
        Variable(
            "alpha2_eig_re",
            "sigma^(3/2) g^(1/2)",
            "Re α(k)/k² from the eigenvalue at k = 1e-5 (same as alpha2_re; kept for old readers)",
        ),
        Variable(
            "alpha2_taylor_re",
            "sigma^(3/2) g^(1/2)",
            "strict Taylor Re α2 at the same N (perturbation theory; converges only "
            "algebraically; computed with the option taylor=True, else missing)",
        ),
        Variable(
            "longwave_consistent",
            "1",
            "the sign of Re α(k)/k² is the same at N and round(0.8 N) (the sign is resolved)",
            kind="flag",
        ),
        Variable("longwave_n", "1", "Chebyshev intervals of the long-wave computation", kind="int"),
    )

    def validate(self):
        o = self.options
        if not (24 <= int(o["n"]) <= int(o["n_max"]) <= 1000):
            raise ParameterError("longwave: need 24 <= n <= n_max <= 1000 (Chebyshev intervals)")
        if not (0 < float(o["rtol"]) < 1):
            raise ParameterError(
                "longwave: need 0 < rtol < 1: below 1 the resolutions N and 0.8 N agree on the "
                "sign of Re α/k²"
            )
        if not isinstance(o["taylor"], bool):
            raise ParameterError(
                f"longwave: taylor = {o['taylor']!r}: need True or False (whether to compute "
                "the strict Taylor α2 by perturbation theory as well)"
            )

    def compute(self, flow, point):
        o = self.options
        # an own operator cache: the flow's operators are dropped when the point is done
        es = eigen_sign(
            flow,
            n=int(o["n"]),
            n_max=int(o["n_max"]),
            rtol=float(o["rtol"]),
            cache=OperatorCache(2),
            taylor=bool(o["taylor"]),
        )
        if not es.converged:
            point.note(
                f"longwave: Re α/k² = {es.coefficient:.4g} changes by {es.convergence:.1e} "
                f"(relative) between N = {es.n} and {check_n(es.n)}"
            )
        e = es.coefficient if math.isfinite(es.coefficient) else None
        return {
            "alpha1_im": es.alpha1.imag,
            "alpha2_re": e,
            "alpha2_convergence": es.convergence if math.isfinite(es.convergence) else None,
            "alpha2_eig_re": e,
            "alpha2_taylor_re": es.alpha2_taylor.real if math.isfinite(es.alpha2_taylor.real) else None,
            "longwave_consistent": bool(es.convergence < 1.0),
            "longwave_n": es.n,
        }


@register_point_function
class GrowthMetric(PointFunction):
    """Maximum growth rate, its wavenumber and k_c from the tracked dispersion relation.

    The α(0) = 0 branch is tracked from k = 0 (:class:`chuteflow.stability.BranchTracker`,
    drift and tail checked at every k, N raised where needed) over ``num`` wavenumbers
    geometrically spaced in [k_min, k_max]. k_c is decided on these samples by the rule of
    :attr:`chuteflow.stability.BranchScan.k_c` (:func:`~chuteflow.stability.scan.critical_index`:
    the first sign change of Re α between reached neighbours, when it goes from + to −, i.e.
    the upper edge of the long-wave unstable band; missing where the first change goes from
    − to +), and refined by Brent's method on the mode nearest the linear prediction inside
    the bracket (relative tolerance 1e-6); the maximum is the largest sample
    (:func:`~chuteflow.stability.scan.peak_index`), not refined. Points that miss the
    paper's drift and tail tests at N = ``n_max`` are kept with their estimate
    (``growth_converged`` = 0, the largest drift in ``growth_drift``, a note in the point's
    message); where the tracker loses the branch
    near the continuum of the dilute top, the rest of the k grid is followed once more from
    k = 0 with the tail threshold relaxed, up to the first k it does not reach, and the
    values there that fail the paper's tests are recomputed each by its own continuation
    from k = 0 (:func:`chuteflow.stability.lost.relaxed_branch_modes`), as version 5
    did for every k (past ``RejectionPolicy.relaxed_k_max`` each k as
    :func:`~chuteflow.stability.least_stable` answers there,
    :func:`~chuteflow.stability.lost.after_lost_branch`). The k beyond are missing:
    there the branch has dissolved into the continuum (strongly damped, e.g. Re α = −0.2 at
    k = 0.017 for θ = 15.36°, ν0(0) = 0.12), ``growth_k_reached`` says how far it was
    followed, the maximum and k_c are those of the part reached, flagged
    ``growth_converged`` = 0 (version 6; version 5 dropped every value where the largest k
    was not reached, and version 6 also fixes the first step from k = 0, see
    ``TrackingPolicy.first_step_min``; version 7: the tracker gives up
    at once where no shorter step can pass — an eigenvector unresolved at k = 0, the
    branch's own tail rising through the threshold, a predictor that misses by a fixed
    fraction of any step, see ``TrackingPolicy.crossing_near`` and
    ``TrackingPolicy.stall_rejections`` — so it no longer carries a
    point accepted off the branch at N = 60 up the ladder: θ = 17.19°, ν0(0) = 0.144 was
    lost at N = 160 and is now tracked, converged, at N = 118; version 8: k_c by the one
    rule of :mod:`chuteflow.stability.scan`, missing where the first sign change goes from −
    to + (a long-wave stable flow with a finite-k band), where version 7 stored that band's
    upper edge). Only where not even the first
    k is reached are the values missing (``dispersion_sampled`` = 1, the reason in the
    message).
    Evaluated at the sampled points (every ``stride``-th point in θ
    and in ν0, and every marked point) and, if ``unstable_points``, at every point with
    Re α2 > 0 (about 5 s a point: off by default for diagrams).
    """

    name = "growth"
    version = "8"
    requires = ("steady", "longwave")
    critical = False  # a cross-check: its failure leaves the point's classification alone
    defaults = {
        "k_min": 1e-4,
        "k_max": 0.05,
        "num": 16,
        "stride": 6,
        "n": 48,
        "n_max": 160,
        "unstable_points": False,
    }
    variables = (
        Variable(
            "growth_max",
            _RATE,
            "largest Re α of the α(0) = 0 branch on the k grid",
            source="figures 7, 9, 13",
        ),
        Variable("k_growth_max", "1/sigma", "wavenumber of the largest Re α on the k grid"),
        Variable(
            "k_c",
            "1/sigma",
            "critical wavenumber: first sign change of Re α, from + to − (upper edge of the "
            "long-wave unstable band 0 < k < k_c; missing where the flow is long-wave stable)",
            source="§4.2",
        ),
        Variable("growth_n", "1", "largest Chebyshev N used along the branch", kind="int"),
        Variable(
            "growth_drift",
            _RATE,
            "largest |α(N) − α(round(0.8 N))| over the k grid (the convergence estimate)",
        ),
        Variable(
            "growth_converged",
            "1",
            "every k of the grid passed the paper's drift and tail tests (§4.1)",
            kind="flag",
        ),
        Variable(
            "growth_k_reached",
            "1/sigma",
            "largest k of the grid where the branch was reached (below k_max: the branch "
            "dissolved into the continuum of the dilute top there, larger k are missing)",
        ),
        Variable(
            "dispersion_sampled",
            "1",
            "the dispersion relation was sampled here (unstable or check point)",
            kind="flag",
        ),
    )

    def validate(self):
        o = self.options
        if not (0 < float(o["k_min"]) < float(o["k_max"])):
            raise ParameterError("growth: need 0 < k_min < k_max (wavenumbers, 1/sigma)")
        if int(o["num"]) < 3:
            raise ParameterError("growth: num (k grid points) must be at least 3")
        if int(o["stride"]) < 1:
            raise ParameterError("growth: stride must be >= 1 (1 = check every point)")
        if not (24 <= int(o["n"]) <= int(o["n_max"])):
            raise ParameterError("growth: need 24 <= n <= n_max (Chebyshev intervals)")

    def k_grid(self) -> np.ndarray:
        o = self.options
        return np.geomspace(float(o["k_min"]), float(o["k_max"]), int(o["num"]))

    def sampled(self, point) -> bool:
        """Marked points, and every ``stride``-th point in θ and ν0 offset by stride // 2 (off
        the grid's edges, where the existence boundaries make every solver slowest)."""
        s = int(self.options["stride"])
        return point.i < 0 or (point.i % s == s // 2 and point.j % s == s // 2)

    def compute(self, flow, point):

        a2 = point.values.get("alpha2_re", np.nan)
        unstable = bool(np.isfinite(a2) and a2 > 0)
        if not ((unstable and self.options["unstable_points"]) or self.sampled(point)):
            return {"dispersion_sampled": False}
        o = self.options
        ks = self.k_grid()
        # an own operator cache: the flow's operators are dropped when the point is done
        cache = OperatorCache(2)  # N and N′ (the drift check; the next rung reuses N)
        policy = RejectionPolicy(n_max=int(o["n_max"]))
        modes: list = []  # one per k of the grid; None where the branch was not reached
        try:
            tr = BranchTracker(flow, int(o["n"]), policy=policy, cache=cache)
            for k in ks:
                try:
                    modes.append(tr.mode(k))
                except ConvergenceError as exc:
                    # lost near the continuum: the rest of the grid followed once more from
                    # k = 0 with the relaxed tail threshold, up to the first k not reached
                    # (relaxed_branch_modes); past policy.relaxed_k_max, where the branch lies
                    # in a band of critical-layer eigenvalues, each k as least_stable answers
                    # there (after_lost_branch: the band search and the direct mode)
                    lost = str(exc).split(" (theta")[0]
                    rest = [float(kk) for kk in ks[len(modes) :]]
                    below = [kk for kk in rest if kk <= policy.relaxed_k_max]
                    found = relaxed_branch_modes(flow, below, n=tr.n, policy=policy, cache=cache, lost=lost)
                    modes.extend(found)
                    modes.extend([None] * (len(below) - len(found)))
                    modes.extend(
                        after_lost_branch(flow, kk, n=tr.n, policy=policy, cache=cache, lost=lost)
                        for kk in rest[len(below) :]
                    )
                    reached = [float(kk) for kk, m in zip(ks, modes) if m is not None]
                    lost_note = f"growth: {lost}; followed with the relaxed tail threshold from there"
                    if len(reached) < len(ks):
                        lost_note += (
                            f", up to k = {reached[-1]:.3g} ({len(ks) - len(reached)} of {len(ks)} k "
                            f"not reached: their values are missing)"
                            if reached
                            else f", not reached at any k of the grid (N = {tr.n})"
                        )
                    point.note(lost_note)
                    break
        except ConvergenceError as exc:
            # sampled, but no trustworthy branch: the values stay missing, the message says why
            point.note(f"growth: {exc}")
            return {"dispersion_sampled": True}
        got = [m for m in modes if m is not None]
        if not got:
            return {"dispersion_sampled": True}
        bad = [m for m in got if not m.physical]
        if bad:
            m = bad[0]
            point.note(
                f"growth: {len(bad)} of {len(ks)} k not converged to the paper's thresholds, "
                f"first at k = {m.k:.3g}, N = {m.n} (drift {m.drift:.1e}, tail {m.tail:.1e})"
            )
        re = np.array([np.nan if m is None else m.alpha.real for m in modes])
        imax = peak_index(re)  # the branch scan's rule for the largest sampled Re α
        assert imax is not None  # some mode was reached
        out = {
            "dispersion_sampled": True,
            "growth_max": float(re[imax]),
            "k_growth_max": float(ks[imax]),
            "growth_n": max(m.n for m in got),
            "growth_drift": max(m.drift for m in got),
            "growth_converged": not bad and len(got) == len(ks),
            "growth_k_reached": max(m.k for m in got),
        }
        # k_c by the branch scan's rule (chuteflow.stability.scan.critical_index): the first
        # sign change of Re α between reached neighbours, when it goes from + to −
        i = critical_index(re)
        if i is not None:
            try:
                out["k_c"] = self._refine(flow, modes[i], modes[i + 1], cache)
            except (ConvergenceError, ValueError) as exc:
                # the refinement left the branch: the bracket's linear estimate, noted
                ka, kb = float(ks[i]), float(ks[i + 1])
                out["k_c"] = linear_crossing(ks, re, i)
                point.note(f"growth: k_c in [{ka:.3g}, {kb:.3g}] by linear interpolation ({exc})")
        return out

    @staticmethod
    def _refine(flow, ma, mb, cache=None):
        """Brent on Re α(k) of the eigenvalue nearest the linear prediction between two
        tracked modes (at the finer of their resolutions; no drift check: only Re α is
        used)."""
        from .._memory import brentq  # scipy's, without a reference cycle that keeps the cache

        ka, kb, aa, ab = ma.k, mb.k, ma.alpha, mb.alpha
        n = max(ma.n, mb.n)

        def f(k):
            pred = aa + (ab - aa) * (k - ka) / (kb - ka)
            pencil = stability_operator(flow, n, cache=cache).pencil(k)
            return float(nearest_eigenpair(pencil, pred)[0].real)

        return float(brentq(f, ka, kb, xtol=1e-6 * kb, rtol=1e-6))


def default_metrics() -> list[str]:
    """Point functions of a default sweep, in evaluation order."""
    return ["steady", "kinematic", "longwave", "growth"]

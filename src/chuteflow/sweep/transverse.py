"""Sweep metric ``transverse``: transverse stability and which instability wins.

The paper (§5.3) leaves open how its longitudinal long-wave instability and the transverse
instability of Forterre & Pouliquen (2002) compete. At each point this metric gives

- α2z of α(0, k_z) = α2z k_z² + … (bordered perturbation theory at k = 0,
  :func:`chuteflow.longwave.transverse_longwave`), and, where α2z > 0, the most unstable
  k_z* with its growth rate and the cut-off of the band, from the α(0) = 0 branch tracked in
  k_z (:func:`chuteflow.stability.axis_peaks.transverse_peak`: a geometric scan that stops
  past the cut-off, the maximum refined by a bounded search, only the mode there judged);
- where the point is long-wave unstable along the slope (Re α2 > 0, the verdict of the
  metric ``longwave`` of the same sweep, not recomputed), the largest growth rate of the
  longitudinal branch and its k_x (:func:`chuteflow.stability.axis_peaks.longitudinal_peak`,
  the same scan on the 2D sinh-mapped grid from N = 48);
- the classification ``winner``: 0 stable, 1 longitudinal only (the paper's A, B, C
  unstable regions), 2 transverse only, 3 both; and the largest growth rate of the two with
  its wavevector (k_x, k_z) — ``fastest`` says which (1 longitudinal, 2 transverse); missing
  where the longitudinal branch could not be followed (noted in the point's message).

The comparison is between the two axes of the (k_x, k_z) plane; at P1 the maximum over the
plane lies on the k_x axis (:func:`chuteflow.stability.transverse.growth_plane`). A point
that is stable in both directions costs the bordered solve of α2z; an unstable one a scan per
unstable direction. Measured on a heavily loaded 2-core machine, version 2 (every point of
fixed 40- and 20-point grids judged at N = 80) and this version on the same flows in one
process: 2–6× less per unstable flow (θ = 17.14°, ν0(0) = 0.044: 8.2 → 1.4 s; 16.29°, 0.181:
5.8 → 1.7 s), the same on stable ones; in the 40 × 40 φ = 0.10 diagram the metric took 0.34 s
per grid point against 1.42 s for the steady flows (``benchmarks/bench_transverse.py``).
"""

from __future__ import annotations

import math

import numpy as np

from ..conventions import RATE_UNITS
from ..errors import ConvergenceError, ParameterError
from ..longwave.spanwise import transverse_longwave
from ..stability import OperatorCache, RejectionPolicy
from ..stability.axis_peaks import PEAK_RATIO, longitudinal_peak, transverse_peak
from .points import PointFunction, Variable, register_point_function

__all__ = ["TransverseMetric", "WINNER_CODES"]

#: Codes of the ``winner`` variable.
WINNER_CODES = {0: "stable", 1: "longitudinal only", 2: "transverse only", 3: "both"}


def _policy2d(options) -> RejectionPolicy:
    """The resolution ladder of the longitudinal (2D, sinh-mapped grid) branch: from N = 48,
    where the paper's 1e-7 is met at most points (:class:`RejectionPolicy`)."""
    return RejectionPolicy(n_start=48, n_max=int(options["n_max"]))


@register_point_function
class TransverseMetric(PointFunction):
    """Transverse stability (α2z, k_z*, growth) and which instability wins (module docstring).

    Options: ``kz_max``, ``k_max`` (largest k_z and k_x of the scans), ``ratio`` (their
    geometric step), ``n`` (Chebyshev intervals of α2z), ``n_track`` (first N of the
    transverse branch, plain grid), ``n_max`` (largest N of both ladders).
    """

    name = "transverse"
    # 4: the longitudinal branch's first step from k = 0 must hit α1 k
    # (TrackingPolicy.first_step_min): in dilute flows it was "lost" at k = 1e-5;
    # and longitudinal_peak tries N = 75 also where the branch is lost before k_min at 48, 60.
    # 5: the transverse branch is followed over its flat maximum whatever the round-off (10
    # step halvings of TransverseTracker.advance instead of 6: P1 was "lost" at k_z = 1.93e-3
    # for flows a round-off apart)
    version = "5"
    requires = ("steady", "longwave")
    defaults = {"kz_max": 3.0, "k_max": 0.05, "ratio": PEAK_RATIO, "n": 80, "n_track": 48, "n_max": 160}
    variables = (
        Variable(
            "alpha2_z",
            "sigma^(3/2) g^(1/2)",
            "α2z of α(0, kz) = α2z kz² + … (> 0: long-wave transverse instability)",
            source="analogue of App. B",
        ),
        Variable("transverse_growth_max", RATE_UNITS, "largest Re α of the transverse (kx = 0) branch"),
        Variable("transverse_kz_max", "1/sigma", "kz of that maximum (missing where every kz decays)"),
        Variable("transverse_kz_cutoff", "1/sigma", "upper edge of the transverse unstable band"),
        Variable("longitudinal_growth_max", RATE_UNITS, "largest Re α of the longitudinal (kz = 0) branch"),
        Variable("longitudinal_kx_max", "1/sigma", "kx of that maximum (long-wave unstable points)"),
        Variable(
            "winner",
            "1",
            "0 stable, 1 longitudinal only, 2 transverse only, 3 both",
            kind="int",
            source="§5.3 question",
        ),
        Variable("fastest", "1", "which grows faster: 0 none, 1 longitudinal, 2 transverse", kind="int"),
        Variable("fastest_growth", RATE_UNITS, "largest growth rate of the two directions"),
        Variable("fastest_kx", "1/sigma", "kx of the fastest-growing perturbation"),
        Variable("fastest_kz", "1/sigma", "kz of the fastest-growing perturbation"),
    )

    def validate(self):
        """Check the scan and resolution options (ParameterError naming the option)."""
        o = self.options
        if not (float(o["kz_max"]) > 1e-5 and float(o["k_max"]) > 1e-4):
            raise ParameterError("transverse: need kz_max > 1e-5 and k_max > 1e-4 (wavenumbers, 1/sigma)")
        if not (1.1 <= float(o["ratio"]) <= 4.0):
            raise ParameterError("transverse: need 1.1 <= ratio <= 4 (step of the geometric wavenumber scan)")
        if not (24 <= int(o["n"]) <= int(o["n_max"]) and 24 <= int(o["n_track"]) <= int(o["n_max"])):
            raise ParameterError("transverse: need 24 <= n, n_track <= n_max (Chebyshev intervals)")

    def compute(self, flow, point):
        """The metric's variables at one steady flow (module docstring)."""
        o = self.options
        out: dict = {}
        policy = RejectionPolicy(n_start=int(o["n_track"]), n_max=int(o["n_max"]))
        # this flow's operators only, dropped with it: the module's cache keeps six, and
        # three-dimensional ones at N = 160 hold ~70 MB each (a worker of the 40 × 40 §5.3
        # diagram reached 577 MiB)
        cache = OperatorCache(2)
        a2z = float(transverse_longwave(flow, int(o["n"]), cache=cache, strict=True).alpha2_z.real)
        out["alpha2_z"] = a2z
        t_unstable = a2z > 0
        if t_unstable:
            tp = transverse_peak(
                flow,
                alpha2z=a2z,
                kz_max=float(o["kz_max"]),
                ratio=float(o["ratio"]),
                policy=policy,
                cache=cache,
            )
            if math.isfinite(tp.growth):
                out["transverse_growth_max"] = tp.growth
            t_unstable = bool(tp.growth > 0)
            if t_unstable:
                out["transverse_kz_max"] = tp.k
            if tp.cutoff is not None:
                out["transverse_kz_cutoff"] = tp.cutoff
            if tp.mode is not None and not tp.physical:
                m = tp.mode
                point.note(f"transverse: growth maximum unresolved at N = {m.n} (drift {m.drift:.1e})")
        # the 2D long-wave verdict of the same sweep (metric "longwave": Re α/k² at k = 1e-5)
        a2 = point.values.get("alpha2_re", np.nan)
        l_unstable = bool(np.isfinite(a2) and a2 > 0)
        l_known = True
        if l_unstable:
            try:
                lp = longitudinal_peak(
                    flow, k_max=float(o["k_max"]), ratio=float(o["ratio"]), policy=_policy2d(o), cache=cache
                )
                out["longitudinal_growth_max"], out["longitudinal_kx_max"] = lp.growth, lp.k
                l_unstable = lp.growth > 0
                if lp.mode is not None and not lp.physical:
                    m = lp.mode
                    point.note(f"transverse: longitudinal maximum unresolved (N {m.n}, drift {m.drift:.1e})")
            except ConvergenceError as exc:
                # long-wave unstable (Re α2 > 0) but its growth unknown: no "fastest" claim
                l_known = False
                point.note(f"transverse: longitudinal branch not followed ({exc})")
        out["winner"] = int(l_unstable) + 2 * int(t_unstable)
        gl = out.get("longitudinal_growth_max", -math.inf) if l_unstable else -math.inf
        gt = out.get("transverse_growth_max", -math.inf) if t_unstable else -math.inf
        if not l_known:
            return out  # fastest and its wavevector stay missing
        if max(gl, gt) > 0:
            if gl >= gt:
                out.update(
                    fastest=1, fastest_growth=gl, fastest_kx=out["longitudinal_kx_max"], fastest_kz=0.0
                )
            else:
                out.update(fastest=2, fastest_growth=gt, fastest_kx=0.0, fastest_kz=out["transverse_kz_max"])
        else:
            out["fastest"] = 0
        return out

"""Sweep metric ``spatial``: convective or absolute instability and the most amplified inlet
frequency over (θ, ν0(0)) (:mod:`chuteflow.spatial`).

At each point:

1. the temporal branch scan of the α(0) = 0 branch over (0, ``k_max``]
   (:func:`chuteflow.stability.branch_scan`, the rule of §4.2). Where its largest growth rate
   is ≤ 0 the flow is temporally stable: ``spatial_verdict`` = 0 and nothing else is
   computed (the scan is the whole cost, ~0.3 s);
2. the most amplified frequency of the signalling problem directly, without sampling ω: the
   complex k* with Re α(k*) = Re α'(k*) = 0 from the refined temporal peak
   (:func:`chuteflow.spatial.branches.spatial_peak`), so ``omega_max`` = −Im α(k*) and
   ``spatial_growth_max`` = −Im k* (the same, to 1e-9, as the maximum of
   :func:`~chuteflow.spatial.spatial_dispersion`, tests/spatial/test_spatial_metric.py);
3. with ``absolute=True`` (default), the Briggs–Bers analysis
   (:func:`chuteflow.spatial.absolute_instability`, reusing the scan): the verdict, the
   packet's edges V−, V+ and, where the saddle family reaches the lab frame, the absolute
   growth rate Re α(k*₀). ``absolute=False`` leaves them missing and the verdict at
   1 ("unstable, not classified") for an unstable flow.

Measured per point after the steady flow, on the shared 2-core machine at load ≈ 5 (about
2.5× an idle core): stable P2, P3 0.6 s; without / with Briggs–Bers P1 1.9 / 8.8 s, P4
2.4 / 10.0 s, P5 1.0 / 6.5 s. The Briggs–Bers continuation is most of an unstable point's
cost (docs/spatial.md, "Speed").

A non-critical metric: where a solver fails its variables stay missing and the point's
message says why; the point keeps its classification.
"""

from __future__ import annotations

import math

from ..conventions import RATE_UNITS, VELOCITY_UNITS, WAVENUMBER_UNITS
from ..errors import ChuteflowError, ParameterError
from ..stability import OperatorCache, branch_scan
from .points import PointFunction, Variable, register_point_function

__all__ = ["SpatialMetric", "VERDICT_CODES"]

#: Codes of the ``spatial_verdict`` variable (−1: missing).
VERDICT_CODES = {
    0: "stable",
    1: "unstable (not classified)",
    2: "convective",
    3: "absolute",
    4: "undetermined",
}
_CODE = {"stable": 0, "convective": 2, "absolute": 3, "undetermined": 4}


@register_point_function
class SpatialMetric(PointFunction):
    """Convective/absolute verdict, most amplified frequency and its spatial growth (module
    docstring). Options: ``absolute`` (run the Briggs–Bers analysis), ``k_max`` and ``num``
    (the temporal scan's grid)."""

    name = "spatial"
    version = "1"
    requires = ("steady",)
    critical = False
    defaults = {"absolute": True, "k_max": 0.05, "num": 40}
    variables = (
        Variable(
            "spatial_verdict",
            "1",
            "0 stable, 1 unstable (not classified), 2 convective, 3 absolute, 4 undetermined",
            kind="int",
            source="Briggs–Bers (Huerre & Monkewitz 1990)",
        ),
        Variable(
            "spatial_growth_max",
            WAVENUMBER_UNITS,
            "largest spatial growth rate −Im k over real frequencies (the most amplified inlet forcing)",
        ),
        Variable("omega_max", RATE_UNITS, "the most amplified angular frequency ω (α(k) = −iω)"),
        Variable("k_spatial_max", WAVENUMBER_UNITS, "Re k of the most amplified spatial wave"),
        Variable(
            "absolute_growth",
            RATE_UNITS,
            "Re α(k*0) at the lab-frame saddle (missing where the saddle family does not reach V = 0)",
        ),
        Variable("v_minus", VELOCITY_UNITS, "lower edge V− of the growing wave packet"),
        Variable("v_plus", VELOCITY_UNITS, "upper edge V+ of the growing wave packet"),
        Variable(
            "spatial_converged",
            "1",
            "the scan, the spatial maximum and (with absolute) the Briggs–Bers analysis converged",
            kind="flag",
        ),
    )

    def validate(self):
        o = self.options
        if not isinstance(o["absolute"], bool):
            raise ParameterError(f"spatial: absolute = {o['absolute']!r}: need True or False")
        if not (0 < float(o["k_max"]) <= 1):
            raise ParameterError(f"spatial: k_max = {o['k_max']!r} is outside (0, 1] (1/sigma)")
        if int(o["num"]) < 3:
            raise ParameterError(f"spatial: num = {o['num']!r}: the scan needs at least 3 wavenumbers")

    def compute(self, flow, point):
        from ..spatial import DEFAULT_SPATIAL_POLICY, absolute_instability
        from ..spatial._core import Branch
        from ..spatial.branches import spatial_peak

        o = self.options
        policy = DEFAULT_SPATIAL_POLICY
        # this flow's operators only, dropped with it
        cache = OperatorCache(2)
        scan = branch_scan(
            flow, k_max=float(o["k_max"]), num=int(o["num"]), policy=policy.rejection, cache=cache
        )
        peak = scan.peak()
        if not (math.isfinite(peak.growth)):
            point.note("spatial: the temporal branch scan reached no point")
            return {"spatial_converged": False}
        ok = scan.converged
        if not ok:
            point.note(f"spatial: the temporal scan is not converged ({scan.note})")
        if peak.growth <= 0:
            return {"spatial_verdict": 0, "spatial_converged": ok}
        out: dict = {"spatial_verdict": 1}
        try:
            e = spatial_peak(Branch(flow, float(peak.k), policy, cache), float(peak.k), policy)
            out.update(
                spatial_growth_max=float(-e.k.imag),
                omega_max=float(-e.alpha.imag),
                k_spatial_max=float(e.k.real),
            )
        except ChuteflowError as exc:
            ok = False
            point.note(f"spatial: {exc}")
        if o["absolute"]:
            try:
                res = absolute_instability(flow, policy=policy, cache=cache, scan=scan)
            except ChuteflowError as exc:
                point.note(f"spatial: Briggs–Bers: {exc}")
                return {**out, "spatial_converged": False}
            out["spatial_verdict"] = _CODE.get(res.verdict, 4)
            for key, v in (
                ("absolute_growth", res.absolute_growth),
                ("v_minus", res.v_minus),
                ("v_plus", res.v_plus),
            ):
                if math.isfinite(v):
                    out[key] = float(v)
            if not res.converged:
                ok = False
                point.note(f"spatial: Briggs–Bers not converged ({res.note})")
        out["spatial_converged"] = ok
        return out

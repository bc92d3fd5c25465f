"""Stability metrics of a sweep: long-wave coefficients, k_c, maximum growth, finite-k check.

- ``longwave``: α1, α2 of α(k) = α1 k + α2 k² + … (§5.1.1, Appendix B) from
  :func:`chuteflow.longwave.longwave`; Re α2 > 0 is long-wave instability (§4.2).
- ``growth``: the dispersion relation of the α(0) = 0 branch sampled on a k grid
  (:func:`chuteflow.stability.dispersion`): maximum growth rate, its k, and the critical k_c
  (first sign change of Re α, refined). Computed where Re α2 > 0 (unless
  ``unstable_points=False``) and on a sample of the other points (every ``stride``-th point in θ
  and ν0, and every marked point), which is the check that no finite-k instability is missed by
  the long-wave criterion.

The stability layer is imported inside ``compute``, so registering these classes never depends
on it.
"""
from __future__ import annotations

import math

import numpy as np

from ..errors import ParameterError
from .points import PointFunction, Variable, register_point_function

__all__ = ["LongWaveMetric", "GrowthMetric", "default_metrics"]

_RATE = "sqrt(g/sigma)"


@register_point_function
class LongWaveMetric(PointFunction):
    """Long-wave coefficients α1, α2 (perturbation theory at k = 0, with its convergence)."""

    name = "longwave"
    version = "1"
    requires = ("steady",)
    defaults = {"n": 96, "rtol": 0.1, "n_max": 480}
    variables = (
        Variable("alpha1_im", "sqrt(g sigma)", "Im α1 (= −dQ0/dρ̄0, long-wave phase velocity)",
                 source="App. B, eq:vp0"),
        Variable("alpha2_re", "sigma^(3/2) g^(1/2)", "Re α2, long-wave growth coefficient "
                 "(> 0: long-wave unstable)", source="§4.2, §5.1.1"),
        Variable("alpha2_im", "sigma^(3/2) g^(1/2)", "Im α2"),
        Variable("alpha2_convergence", "1",
                 "relative change of α2 between the two finest resolutions"),
        Variable("alpha2_eig_re", "sigma^(3/2) g^(1/2)",
                 "Re (α(k) − α1 k)/k² from the eigenvalue at k = 1e-6 (cross-check of α2)"),
        Variable("longwave_n", "1", "Chebyshev intervals of the long-wave computation",
                 kind="int"),
    )

    def validate(self):
        o = self.options
        if not (int(o["n"]) >= 24 and int(o["n_max"]) >= int(o["n"])):
            raise ParameterError("longwave: need 24 <= n <= n_max (Chebyshev intervals)")
        if not (0 < float(o["rtol"]) < 1):
            raise ParameterError("longwave: rtol must lie in (0, 1): below 1 the two finest "
                                 "resolutions agree on the sign of Re α2")

    def compute(self, flow, point):
        from ..longwave import longwave

        o = self.options
        lw = longwave(flow, n=int(o["n"]), rtol=float(o["rtol"]), n_max=int(o["n_max"]))
        eig = lw.alpha2_from_eigenvalue
        return {"alpha1_im": lw.alpha1.imag, "alpha2_re": lw.alpha2.real,
                "alpha2_im": lw.alpha2.imag, "alpha2_convergence": lw.convergence_alpha2,
                "alpha2_eig_re": eig.real if math.isfinite(eig.real) else None,
                "longwave_n": lw.n}


@register_point_function
class GrowthMetric(PointFunction):
    """Maximum growth rate, its wavenumber and k_c from the sampled dispersion relation."""

    name = "growth"
    version = "1"
    requires = ("steady", "longwave")
    defaults = {"k_min": 1e-4, "k_max": 0.05, "num": 24, "stride": 4, "n": None,
                "n_max": 320, "unstable_points": True}
    variables = (
        Variable("growth_max", _RATE, "largest Re α of the α(0) = 0 branch on the k grid",
                 source="figs disp, disp-AC, disp01"),
        Variable("k_growth_max", "1/sigma", "wavenumber of the largest Re α"),
        Variable("k_c", "1/sigma", "critical wavenumber: first sign change of Re α "
                 "(upper edge of the unstable band 0 < k < k_c)", source="§4.2"),
        Variable("dispersion_sampled", "1",
                 "the dispersion relation was sampled here (unstable or check point)",
                 kind="flag"),
    )

    def validate(self):
        o = self.options
        if not (0 < float(o["k_min"]) < float(o["k_max"])):
            raise ParameterError("growth: need 0 < k_min < k_max (wavenumbers, 1/sigma)")
        if int(o["num"]) < 3:
            raise ParameterError("growth: num (k grid points) must be at least 3")
        if int(o["stride"]) < 1:
            raise ParameterError("growth: stride must be >= 1 (1 = check every point)")

    def k_grid(self) -> np.ndarray:
        o = self.options
        return np.geomspace(float(o["k_min"]), float(o["k_max"]), int(o["num"]))

    def sampled(self, point) -> bool:
        s = int(self.options["stride"])
        return point.i < 0 or (point.i % s == 0 and point.j % s == 0)

    def compute(self, flow, point):
        from scipy.optimize import brentq

        from ..stability import dispersion

        a2 = point.values.get("alpha2_re", np.nan)
        unstable = bool(np.isfinite(a2) and a2 > 0)
        if not ((unstable and self.options["unstable_points"]) or self.sampled(point)):
            return {"dispersion_sampled": False}
        o = self.options
        ks = self.k_grid()
        kw = {"n_max": int(o["n_max"])}
        if o["n"] is not None:
            kw["n"] = int(o["n"])
        d = dispersion(flow, ks, **kw)
        re = np.asarray(d["alpha_re"].values)
        imax = int(np.argmax(re))
        out = {"dispersion_sampled": True, "growth_max": float(re[imax]),
               "k_growth_max": float(ks[imax])}
        # k_c: first change of sign from unstable to stable along the grid, refined on the
        # tracked branch (Brent on the eigenvalue nearest the linear prediction)
        k_c = None
        for i in range(len(ks) - 1):
            if re[i] > 0 >= re[i + 1]:
                k_c = self._refine(flow, ks[i], ks[i + 1], kw, brentq)
                break
        if unstable and k_c is None and re[-1] > 0:
            k_c = None  # unstable up to k_max: k_c beyond the grid, left missing
        out["k_c"] = k_c
        return out

    @staticmethod
    def _refine(flow, ka, kb, kw, brentq):
        from ..stability import dispersion

        def f(k):
            return float(dispersion(flow, [k], **kw)["alpha_re"].values[0])

        fa, fb = f(ka), f(kb)
        if not (fa > 0 >= fb):
            return 0.5 * (ka + kb)
        return float(brentq(f, ka, kb, xtol=1e-6 * kb, rtol=1e-8))


def default_metrics() -> list[str]:
    """Point functions of a default sweep, in evaluation order."""
    return ["steady", "kinematic", "longwave", "growth"]

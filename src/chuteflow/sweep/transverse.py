"""Sweep metric ``transverse``: transverse stability and which instability wins (issue 10).

The paper (§5.3) leaves open how its longitudinal long-wave instability and the transverse
instability of Forterre & Pouliquen (2002) compete. At each point this metric gives

- α2z of α(0, k_z) = α2z k_z² + … (bordered perturbation theory at k = 0,
  :func:`chuteflow.longwave.transverse_longwave`), and, where α2z > 0, the most unstable
  k_z* with its growth rate and the cut-off of the band, from the α(0) = 0 branch tracked in
  k_z (:func:`chuteflow.longwave.transverse`, ``method="track"``);
- where the point is long-wave unstable along the slope (Re α2 > 0, metric ``longwave``),
  the largest growth rate of the longitudinal branch and its k_x (the branch tracked on a
  geometric k_x grid, the maximum refined by a bounded search);
- the classification ``winner``: 0 stable, 1 longitudinal only (the paper's A, B, C
  unstable regions), 2 transverse only, 3 both; and the largest growth rate of the two with
  its wavevector (k_x, k_z) — ``fastest`` says which (1 longitudinal, 2 transverse); missing
  where the longitudinal branch could not be followed (noted in the point's message).

The comparison is between the two axes of the (k_x, k_z) plane; at P1 the maximum over the
plane lies on the k_x axis (:func:`chuteflow.stability.transverse.growth_plane`). A point
whose steady flow is transversely stable costs one bordered solve (~0.05 s); an unstable one
~0.3 s more per direction.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import minimize_scalar

from ..conventions import RATE_UNITS
from ..errors import ConvergenceError, ParameterError
from ..longwave.transverse import transverse, transverse_longwave
from ..stability import BranchTracker, RejectionPolicy, mode_near
from .points import PointFunction, Variable, register_point_function

__all__ = ["TransverseMetric", "WINNER_CODES"]

#: Codes of the ``winner`` variable.
WINNER_CODES = {0: "stable", 1: "longitudinal only", 2: "transverse only", 3: "both"}


@register_point_function
class TransverseMetric(PointFunction):
    """Transverse stability (α2z, k_z*, growth) and which instability wins (module docstring).

    Options: ``kz_max`` (largest k_z of the transverse grid), ``num`` (its points),
    ``k_max``, ``k_num`` (the longitudinal k_x grid), ``n`` (Chebyshev intervals),
    ``n_max``.
    """

    name = "transverse"
    version = "2"
    requires = ("steady", "longwave")
    defaults = {"kz_max": 3.0, "num": 40, "k_max": 0.05, "k_num": 20, "n": 80, "n_max": 160}
    variables = (
        Variable(
            "alpha2_z",
            "sigma^(3/2) g^(1/2)",
            "α2z of α(0, kz) = α2z kz² + … (> 0: long-wave transverse instability)",
            source="issue 10; analogue of App. B",
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
        """Check the grid and resolution options (ParameterError naming the option)."""
        o = self.options
        if not (float(o["kz_max"]) > 1e-5 and float(o["k_max"]) > 1e-4):
            raise ParameterError("transverse: need kz_max > 1e-5 and k_max > 1e-4 (wavenumbers, 1/sigma)")
        if int(o["num"]) < 5 or int(o["k_num"]) < 5:
            raise ParameterError("transverse: num and k_num (grid points) must be at least 5")
        if not (24 <= int(o["n"]) <= int(o["n_max"])):
            raise ParameterError("transverse: need 24 <= n <= n_max (Chebyshev intervals)")

    def _longitudinal(self, flow):
        """(growth, k) of the longitudinal branch's maximum on the k_x grid, refined."""
        o = self.options
        ks = np.geomspace(1e-4, float(o["k_max"]), int(o["k_num"]))
        tr = BranchTracker(flow, int(o["n"]), policy=RejectionPolicy(n_max=int(o["n_max"])))
        modes = [tr.mode(k) for k in ks]
        re = np.array([m.alpha.real for m in modes])
        j = int(np.argmax(re))
        best_g, best_k = float(re[j]), float(ks[j])
        if 0 < j < len(ks) - 1:
            n = max(m.n for m in modes[j - 1 : j + 2])
            lk = np.log(ks[j - 1 : j + 2])
            cre = np.polyfit(lk, [m.alpha.real for m in modes[j - 1 : j + 2]], 2)
            cim = np.polyfit(lk, [m.alpha.imag for m in modes[j - 1 : j + 2]], 2)

            def minus(x):
                pred = complex(np.polyval(cre, x), np.polyval(cim, x))
                try:
                    a = mode_near(flow, math.exp(x), pred, n=n).alpha
                except ConvergenceError:
                    return math.inf
                # the branch, not a neighbour of the continuum: close to the interpolation
                return -a.real if abs(a - pred) < 0.05 * abs(pred) else math.inf

            opt = minimize_scalar(
                minus,
                bounds=(math.log(ks[j - 1]), math.log(ks[j + 1])),
                method="bounded",
                options={"xatol": 0.02, "maxiter": 12},
            )
            if -opt.fun > best_g:
                best_g, best_k = float(-opt.fun), float(math.exp(opt.x))
        return best_g, best_k

    def compute(self, flow, point):
        """The metric's variables at one steady flow (module docstring)."""
        o = self.options
        out: dict = {}
        a2z = float(transverse_longwave(flow, max(int(o["n"]), 80)).alpha2_z.real)
        out["alpha2_z"] = a2z
        t_unstable = a2z > 0
        if t_unstable:
            r = transverse(flow, kz_max=float(o["kz_max"]), num=int(o["num"]))
            out["transverse_growth_max"] = r.growth_max
            t_unstable = r.kz_max is not None
            if t_unstable:
                out["transverse_kz_max"] = r.kz_max
            if r.kz_cutoff is not None:
                out["transverse_kz_cutoff"] = r.kz_cutoff
        a2 = point.values.get("alpha2_re", np.nan)
        l_unstable = bool(np.isfinite(a2) and a2 > 0)
        l_known = True
        if l_unstable:
            try:
                g, k = self._longitudinal(flow)
                out["longitudinal_growth_max"], out["longitudinal_kx_max"] = g, k
                l_unstable = g > 0
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

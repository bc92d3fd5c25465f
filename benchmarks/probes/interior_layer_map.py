"""Probe (issue 9, item 2 root cause): convergence of the α(0) = 0 branch eigenvalue with N on
the plain Chebyshev grid and on a sinh-mapped grid clustering nodes around y_c (Tee &
Trefethen 2006, y = y_c + ε sinh(s)). Monkeypatches the operator's grid; not part of the package.

    PYTHONPATH=src python benchmarks/probes/interior_layer_map.py 14 0.05 0.04 1.136,0.1
    PYTHONPATH=src python benchmarks/probes/interior_layer_map.py 16 0.05 0.02 19.52,3.5

Arguments: θ, ν0(0) (φ = 0.05), k, then any number of "y_c,ε" maps; prints
|α(N) − α(320)| for N = 48 … 200 on each grid.
"""

from __future__ import annotations

import math
import sys

import numpy as np

import chuteflow.stability.operator as operator_module
from chuteflow.closures import ChuteModel
from chuteflow.errors import ConvergenceError
from chuteflow.spectral import ChebyshevGrid
from chuteflow.stability import BranchTracker, OperatorCache
from chuteflow.steady import solve_steady

MAP = {"yc": 0.0, "eps": 1.0}


class MappedGrid(ChebyshevGrid):
    """Chebyshev nodes in s, y = y_c + ε sinh(s), s linear in the Chebyshev variable ξ."""

    def __init__(self, n, a=0.0, b=1.0):
        super().__init__(n, -1.0, 1.0)
        x, dx, wx = self.y.copy(), self.D.copy(), self.weights.copy()
        yc, eps = MAP["yc"], MAP["eps"]
        s0, s1 = math.asinh((a - yc) / eps), math.asinh((b - yc) / eps)
        s = s0 + (s1 - s0) * (x + 1) / 2
        self.a, self.b, self._s = a, b, (s0, s1)
        self.y = yc + eps * np.sinh(s)
        y1 = eps * np.cosh(s) * (s1 - s0) / 2
        y2 = eps * np.sinh(s) * ((s1 - s0) / 2) ** 2
        self.D = dx / y1[:, None]
        self._d2 = (dx @ dx) / (y1**2)[:, None] - (y2 / y1**3)[:, None] * dx
        self.weights = wx * y1

    @property
    def D2(self):
        return self._d2

    def interpolate(self, f, y):
        s0, s1 = self._s
        xq = 2 * (np.arcsinh((np.asarray(y) - MAP["yc"]) / MAP["eps"]) - s0) / (s1 - s0) - 1
        return ChebyshevGrid(self.n, -1.0, 1.0).interpolate(f, xq)


def errors(flow, k):
    # the plain grid: the operator builds it as operator_module.ChebyshevGrid, patched below
    cache = OperatorCache(4, mapped=False)
    res = {}
    for n in (48, 64, 80, 100, 125, 160, 200, 320):
        try:
            res[n] = BranchTracker(flow, n, n_max=n, cache=cache).advance(k)[0]
        except ConvergenceError:
            res[n] = None
    ref = res[320]
    return ref, {n: (abs(a - ref) if a is not None else None) for n, a in res.items() if n < 320}


def main(argv):
    theta, nu0, k = float(argv[0]), float(argv[1]), float(argv[2])
    flow = solve_steady(theta, nu0, ChuteModel(roughness=0.05))
    print(f"theta = {theta:g}, nu0 = {nu0:g}, h = {flow.h:.4g}, y_max = {flow.y_max:.4g}, k = {k:g}")
    for spec in [None, *argv[3:]]:
        if spec is None:
            operator_module.ChebyshevGrid, label = ChebyshevGrid, "plain Chebyshev"
        else:
            MAP["yc"], MAP["eps"] = map(float, spec.split(","))
            operator_module.ChebyshevGrid = MappedGrid
            label = f"sinh map y_c = {MAP['yc']:g}, ε = {MAP['eps']:g}"
        ref, err = errors(flow, k)
        row = " ".join(f"N={n}:{e:.1e}" if e is not None else f"N={n}:lost" for n, e in err.items())
        print(f"{label}: alpha(320) = {ref:.10e}\n   {row}", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])

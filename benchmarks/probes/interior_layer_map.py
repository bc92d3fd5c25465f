"""Probe (issue 9, item 2 root cause): convergence of the α(0) = 0 branch eigenvalue with N on
the plain Chebyshev grid and on a sinh-mapped grid clustering nodes around y_c (Tee &
Trefethen 2006, y = y_c + ε sinh(s)). Monkeypatches the operator's grid; not part of the package.

    PT=14,0.05 PYTHONPATH=src python benchmarks/probes/interior_layer_map.py 0.04 1.136,0.1
    PT=16,0.05 PYTHONPATH=src python benchmarks/probes/interior_layer_map.py 0.02 19.52,3.5

Arguments: k, then any number of "y_c,ε" maps; prints |α(N) − α(320)| for N = 48 … 200.
"""
import numpy as np
import sys
import math
from chuteflow.closures import ChuteModel
from chuteflow.steady import solve_steady
from chuteflow.stability import BranchTracker, OperatorCache
import sys as _s; O = _s.modules["chuteflow.stability.operator"]
from chuteflow.spectral import ChebyshevGrid

YC, EPS = None, None
class MappedGrid(ChebyshevGrid):
    """sinh map clustering nodes around y_c (Tee & Trefethen 2006)."""
    def __init__(self, n, a=0.0, b=1.0):
        super().__init__(n, -1.0, 1.0)
        x = self.y.copy(); Dx = self.D.copy(); wx = self.weights.copy()
        L = b - a; yc, eps = YC, EPS
        A0, A1 = math.asinh((a - yc)/eps), math.asinh((b - yc)/eps)
        s = A0 + (A1 - A0)*(x + 1)/2
        self.a, self.b = a, b
        self.y = yc + eps*np.sinh(s)
        Y1 = eps*np.cosh(s)*(A1 - A0)/2
        Y2 = eps*np.sinh(s)*((A1 - A0)/2)**2
        self.D = Dx / Y1[:, None]
        self._D2m = (Dx @ Dx) / (Y1**2)[:, None] - (Y2/Y1**3)[:, None]*Dx
        self.weights = wx*Y1
        self._x = x
    @property
    def D2(self): return self._D2m
    def interpolate(self, f, y):
        L = self.b - self.a
        A0, A1 = math.asinh((self.a - YC)/EPS), math.asinh((self.b - YC)/EPS)
        xq = 2*(np.arcsinh((np.asarray(y) - YC)/EPS) - A0)/(A1 - A0) - 1
        g = ChebyshevGrid(self.n, -1.0, 1.0)
        return g.interpolate(f, xq)

import os; th_, nu_ = map(float, os.environ["PT"].split(",")); flow = solve_steady(th_, nu_, ChuteModel(roughness=0.05)); print("h", flow.h)
k = float(sys.argv[1])
for yc, eps in [(None, None)] + [tuple(map(float, s.split(","))) for s in sys.argv[2:]]:
    YC, EPS = yc, eps
    O.ChebyshevGrid = ChebyshevGrid if yc is None else MappedGrid
    cache = OperatorCache(4)
    res = {}
    for n in (48, 64, 80, 100, 125, 160, 200, 320):
        try:
            tr = BranchTracker(flow, n, n_max=n, cache=cache); res[n] = tr.advance(k)[0]
        except Exception: res[n] = None
    ref = res[320]
    print(f"map yc={yc} eps={eps} ref={ref}")
    print("   " + " ".join(f"N={n}:{abs(a-ref):.1e}" if a is not None else f"N={n}:lost" for n, a in res.items()), flush=True)

"""Probe (issue 9, item 2): the smallest N at which the least-stable mode passes the paper's
drift and tail tests (1e-7), on the plain grid and on sinh maps of several widths.

    PYTHONPATH=src python benchmarks/probes/map_width.py P1,P4 0.005,0.5,3 plain,0.45,1,2

Arguments: paper points, wavenumbers, grids ("plain" or a width factor of
``chuteflow.spectral.LAYER_MAP_WIDTH``, shared with the steady grid). Prints N_needed (or
">256") per combination.
"""

from __future__ import annotations

import sys
import time

import chuteflow.spectral as spectral
import chuteflow.stability.operator as opmod
from chuteflow.closures import ChuteModel
from chuteflow.papers.mitarai2004.points import POINTS
from chuteflow.stability import OperatorCache, least_stable
from chuteflow.steady import solve_steady

LADDER = (32, 40, 48, 56, 64, 80, 100, 125, 160, 200, 256)


def n_needed(flow, k, cache):
    for n in LADDER:
        m = least_stable(flow, k, n=n, cache=cache)
        if m.physical:
            return n, m
    return None, m


def main(argv):
    names, ks, grids = (a.split(",") for a in argv[:3])
    # layer_map is cached per flow: uncached, each grid reads the LAYER_MAP_WIDTH set below
    # (the steady grid reads it too: each flow is solved with the default width)
    default = spectral.LAYER_MAP_WIDTH
    opmod.layer_map = opmod.layer_map.__wrapped__
    for name in names:
        p = POINTS[name]
        spectral.LAYER_MAP_WIDTH = default
        flow = solve_steady(p.theta, p.nu0, ChuteModel(roughness=p.roughness))
        for k in map(float, ks):
            row = []
            for g in grids:
                if g == "plain":
                    cache = OperatorCache(4, mapped=False)
                else:
                    spectral.LAYER_MAP_WIDTH = float(g)
                    cache = OperatorCache(4)
                t0 = time.perf_counter()
                n, m = n_needed(flow, k, cache)
                row.append(f"{g}:N={n or '>256'} a={m.alpha:.10g} ({time.perf_counter() - t0:.1f}s)")
            print(f"{name} k={k:g}  " + "  ".join(row), flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])

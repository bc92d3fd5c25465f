"""Benchmarks of the transverse (k_x = 0) analysis, one BLAS thread.

``run(quick)`` returns rows with keys name, seconds, baseline_seconds, ratio, note (the
interface of ``benchmarks/run.py``). Run alone: ``python benchmarks/bench_transverse.py
[--quick]``. Flow: P1 (θ = 16°, ν0(0) = 0.05, φ = 0.05). Targets (the 3D stability issue):
one transverse analysis (α2z, k_z*, growth) under 0.5 s; a transverse dispersion of 50 k_z
under 2 s.

- ``transverse_alpha2z``: α2z by bordered perturbation theory at k = 0 (one LU per
  resolution) against the plain alternative, a fit of Re α / k_z² to dense-QZ eigenvalues
  at k_z = 1e-5 and 3e-5 extrapolated linearly to 0 (the next term is O(|k_z|³)).
- ``transverse_dispersion_50``: ``transverse_dispersion`` at 50 k_z on [0.06, 3] (dense scan
  with drift and tail rejection at every k_z) against 50 × one dense QZ with eigenvectors at
  N = 100 (what the paper's method needs per point, without the drift check).
- ``transverse_analysis``: the whole ``transverse(flow, num=25)`` (α2z, the dispersion on a
  geometric grid, k_z* refined, the cut-off of the unstable band); no baseline.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

import numpy as np

THETA, NU0, N = 16.0, 0.05, 100


def _best(fn, repeat):
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def run(quick: bool = False) -> list[dict]:
    import scipy.linalg as sla

    from chuteflow._threads import limit_blas_threads
    from chuteflow.longwave import transverse, transverse_longwave
    from chuteflow.stability import stability_operator, transverse_dispersion
    from chuteflow.steady import solve_steady

    limit_blas_threads(1)
    rep = 1 if quick else 3
    flow = solve_steady(THETA, NU0)
    op = stability_operator(flow, N, three_d=True)  # warm-up: compilation, caches
    rows = []

    # 1. alpha2z: perturbation theory vs eigenvalue fit
    t_lw, lw = _best(lambda: transverse_longwave(flow), rep)

    def eig_fit():
        vals = []
        for kz in (1e-5, 3e-5):
            A, B = op.pencil(0.0, kz).equilibrated()
            w = sla.eig(A, B, right=False, check_finite=False)
            w = w[np.isfinite(w) & (abs(w) < 1.0)]
            # the physical mode grows (P1); the dilute-top continuum sits at Re α ≈ −1e-8
            vals.append(w[np.argmax(w.real)].real / kz**2)
        return vals[0] - (vals[1] - vals[0]) / 2.0  # linear in k_z through 1e-5, 3e-5 → 0

    t_fit, a2_fit = _best(eig_fit, rep)
    rows.append(
        {
            "name": "transverse_alpha2z",
            "seconds": t_lw,
            "baseline_seconds": t_fit,
            "ratio": t_fit / t_lw,
            "note": f"P1: alpha2_z = {lw.alpha2_z.real:.6g} (N = {lw.n}, "
            f"change {lw.convergence_alpha2:.1e}); "
            f"baseline: dense QZ at k_z = 1e-5, 3e-5, N = {N}, extrapolated {a2_fit:.6g}",
        }
    )

    # 2. a transverse dispersion of 50 kz vs 50 dense QZ with vectors
    kz = np.geomspace(0.06, 3.0, 50)
    t_disp, disp = _best(lambda: transverse_dispersion(flow, kz), 1)
    A, B = op.pencil(0.0, 0.5).equilibrated()
    t_one, _ = _best(lambda: sla.eig(A, B, check_finite=False), rep)
    rows.append(
        {
            "name": "transverse_dispersion_50",
            "seconds": t_disp,
            "baseline_seconds": 50 * t_one,
            "ratio": 50 * t_one / t_disp,
            "note": f"target < 2 s; k_z on [0.06, 3]; N used {sorted(set(disp.n.tolist()))}; "
            f"max Re alpha {np.nanmax(disp.alpha_re):.3g}; baseline = 50 x QZ with vectors at "
            f"N = {N} ({t_one:.2f} s)",
        }
    )

    # 3. the whole transverse analysis (no baseline)
    t_all, res = _best(lambda: transverse(flow, num=25), 1)
    s = res.summary()
    rows.append(
        {
            "name": "transverse_analysis",
            "seconds": t_all,
            "baseline_seconds": float("nan"),
            "ratio": float("nan"),
            "note": f"target < 0.5 s; 25 k_z; kz_max = {s['kz_max']}, growth_max = "
            f"{s['growth_max']:.3g}, stationary = {s['stationary']}",
        }
    )
    return rows


def main(argv=None):
    from run import print_table  # the harness's table, when run as a script from benchmarks/

    print_table(run("--quick" in (argv if argv is not None else sys.argv[1:])))


if __name__ == "__main__":
    main()

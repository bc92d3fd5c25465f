"""Benchmark of the long-wave coefficients α1, α2 (issue 3, §5.1.1, Appendix B), one BLAS thread.

``run(quick)`` returns rows with keys name, seconds, baseline_seconds, ratio, note (the
interface of ``benchmarks/run.py``). Run alone: ``python benchmarks/bench_longwave.py
[--quick]``. Flow: P1 (θ = 16°, ν0(0) = 0.05, φ = 0.05); full mode adds P3 and P5. Times are
the best of a few repetitions after a warm-up (sympy compilation excluded).

- ``longwave_sign_<P>``: ``solve_steady`` + ``longwave(flow, rtol=0.2)`` — enough to decide
  the sign of Re α2 (the default N = 200 and 4N/5 = 160 already agree to 7 % at P1). Target
  < 0.2 s.
- ``longwave_1pct_<P>`` (full mode): the same to ``rtol=0.01`` (N raised until α2 changes by
  < 1 %).
- ``eigen_sign_<P>`` (issue 9): ``eigen_sign`` with the options of the sweep's long-wave
  metric (``LongWaveMetric``), Re α/k² at k = 1e-5 from one shift-invert solve at N and
  0.8 N on the sinh-mapped grid — against the
  sweep's previous metric in the same run: ``longwave(n=64, rtol=0.5, n_max=256,
  eig_ks=None)`` (Taylor α2 on the plain grid, its first pass). Note: both values and N.
- Baseline of both: what one does without perturbation theory — dense QZ
  (``scipy.linalg.eig(A, B)``, eigenvalues only, equilibrated pencil) at the same N at three
  small k (1e-6, 2e-6, 4e-6; the k² regime ends near 1e-5, ERRATA), the eigenvalue nearest
  −i (dQ0/dρ̄0) k picked at each, and Re α = a2 k² + a3 k³ fitted; plus the same steady solve.
  The baseline's accuracy (|a2 − Re α2| / |Re α2|, α2 the Taylor ``LongWave.alpha2_taylor``)
  is in the note. In quick mode one QZ is
  timed and multiplied by three.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np
from benchmarks._timing import best_of as _best

POINTS = {"P1": (16.0, 0.05), "P3": (16.0, 0.10), "P5": (17.0, 0.10)}
K_FIT = (1e-6, 2e-6, 4e-6)


def _qz_fit(flow, n, dq, ks, quick):
    """(seconds of the QZ part, fitted Re α2) by dense QZ at the wavenumbers ``ks``."""
    import scipy.linalg as sla

    from chuteflow.stability import StabilityOperator

    op = StabilityOperator(flow, n, mapped=False)  # longwave()'s Taylor grid
    t_qz, alphas = 0.0, []
    for i, k in enumerate(ks):
        A, B = op.pencil(k).equilibrated()
        t0 = time.perf_counter()
        w = sla.eig(A, B, right=False, check_finite=False)
        t_qz += time.perf_counter() - t0
        w = w[np.isfinite(w)]
        alphas.append(w[np.argmin(np.abs(w + 1j * dq * k))])
        if quick and i == 0:  # same pencil size at every k: time one, fit from all
            t_qz *= len(ks)
            quick = None
    k = np.asarray(ks)
    re = np.array([a.real for a in alphas])
    coef, *_ = np.linalg.lstsq(np.c_[k**2, k**3], re, rcond=None)
    return t_qz, float(coef[0])


def run(quick: bool = False) -> list[dict]:
    import warnings

    from chuteflow._threads import limit_blas_threads
    from chuteflow.longwave import longwave
    from chuteflow.steady import solve_steady

    limit_blas_threads(1)
    warnings.simplefilter("ignore", RuntimeWarning)
    rep = 3 if quick else 5
    rows = []
    names = ["P1"] if quick else list(POINTS)
    for name in names:
        th, nu0 = POINTS[name]
        longwave(solve_steady(th, nu0), rtol=0.2)  # warm-up: compilation, caches
        t_steady, flow = _best(lambda th=th, nu0=nu0: solve_steady(th, nu0), rep)

        def sign(th=th, nu0=nu0):
            return longwave(solve_steady(th, nu0), rtol=0.2)

        t_sign, lw = _best(sign, rep)
        t_qz, a2_fit = _qz_fit(flow, lw.n, lw.dQ_drho, K_FIT, quick)
        baseline = t_steady + t_qz
        err_fit = abs(a2_fit - lw.alpha2_taylor.real) / abs(lw.alpha2_taylor.real)
        rows.append(
            {
                "name": f"longwave_sign_{name}",
                "seconds": t_sign,
                "baseline_seconds": baseline,
                "ratio": baseline / t_sign,
                "note": f"target < 0.2 s; θ={th:g}, ν0={nu0:g}: Taylor Re α2 = {lw.alpha2_taylor.real:.5g} "
                f"(N = {lw.n}, change vs 4N/5 {lw.alpha2_taylor_convergence:.1e}), α1 = "
                f"{lw.alpha1.imag:.8g}i vs −dQ0/dρ̄0 = {-lw.dQ_drho:.8g}; steady "
                f"{t_steady * 1e3:.0f} ms; baseline: QZ at N = {lw.n}, k = 1e-6, 2e-6, "
                f"4e-6{' (1 timed × 3)' if quick else ''}, fit a2 = {a2_fit:.5g} "
                f"({err_fit:.1e} from α2)",
            }
        )
        from chuteflow.longwave.theory import eigen_sign
        from chuteflow.sweep.metrics import LongWaveMetric

        o = LongWaveMetric().options  # as the sweep calls it
        kw = dict(n=int(o["n"]), n_max=int(o["n_max"]), rtol=float(o["rtol"]), taylor=bool(o["taylor"]))
        t_es, es = _best(lambda flow=flow, kw=kw: eigen_sign(flow, **kw), rep)

        def old_metric(flow=flow):
            try:
                return longwave(flow, n=64, rtol=0.5, n_max=256, eig_ks=None)
            except Exception:  # the old first pass raised where it did not converge
                return None

        t_old, lw_old = _best(old_metric, 1)
        rows.append(
            {
                "name": f"eigen_sign_{name}",
                "seconds": t_es,
                "baseline_seconds": t_old,
                "ratio": t_old / t_es,
                "note": f"Re α/k² = {es.coefficient:.6g} (N = {es.n}, change vs 0.8N "
                f"{es.convergence:.1e}); old metric: Taylor Re α2 = "
                + (
                    f"{lw_old.alpha2_taylor.real:.4g} (N = {lw_old.n})"
                    if lw_old is not None
                    else "not converged"
                ),
            }
        )
        if not quick:
            t_full, lw1 = _best(lambda th=th, nu0=nu0: longwave(solve_steady(th, nu0), rtol=0.01), 2)
            t_qz1, a2_fit1 = _qz_fit(flow, lw1.n, lw1.dQ_drho, K_FIT, False)
            rows.append(
                {
                    "name": f"longwave_1pct_{name}",
                    "seconds": t_full,
                    "baseline_seconds": t_steady + t_qz1,
                    "ratio": (t_steady + t_qz1) / t_full,
                    "note": f"rtol 1e-2: Taylor Re α2 = {lw1.alpha2_taylor.real:.5g} (N = {lw1.n}, change "
                    f"{lw1.alpha2_taylor_convergence:.1e}); baseline QZ at N = {lw1.n}: fit "
                    f"a2 = {a2_fit1:.5g}",
                }
            )
    return rows


def main(argv=None):
    from run import print_table  # the harness's table, when run as a script from benchmarks/

    print_table(run("--quick" in (argv if argv is not None else sys.argv[1:])))


if __name__ == "__main__":
    main()

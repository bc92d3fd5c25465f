"""Benchmarks of the stability solvers (issue 3) against dense QZ, one BLAS thread.

``run(quick)`` returns rows with keys name, seconds, baseline_seconds, ratio, note (the
interface of ``benchmarks/run.py``). Run alone: ``python benchmarks/bench_stability.py
[--quick]``. Flow: P1 (θ = 16°, ν0(0) = 0.05, φ = 0.05), k = 0.002, N = 100. Times are the
best of a few repetitions after a warm-up (sympy compilation is excluded).

- ``shift_invert_vs_qz``: the targeted solver on one pencil — LU of A − σB and inverse
  iteration / Arnoldi — from a shift 1e-4 away from the answer, against
  ``scipy.linalg.eig(A, B)`` (eigenvalues only) on the same pencil. Target ≥ 20×, same
  eigenvalue to 1e-9.
- ``least_stable_vs_qz``: the whole ``least_stable(flow, k, n=100)`` — branch continuation
  from k = 0, drift check at N' = 80, Chebyshev tail — against what the paper's method needs
  for the same answer: QZ with eigenvectors at N (tail test) and QZ at N' (drift test).
- ``dispersion_50``: ``solve_steady`` + ``dispersion`` at 50 wavenumbers on [0, 0.02]
  (adaptive N, drift and tail at every point). Target < 2 s. Baseline: the paper's method
  on the same 50 points, two dense QZ per point, timed on one point and multiplied (on the
  paper's plain grid).
- ``mapped_vs_plain_<P>_<k>`` (issue 9): ``least_stable`` with the adaptive N on the default
  sinh-mapped grid (ladder from 48) against the same on the plain grid with the old ladder
  (80, 100, 125, …), measured in the same run; ratio = plain / mapped time; the note gives
  both N and |Δα|.
- ``operator_assembly_N<n>`` (issue 9, stop 32): building one ``StabilityOperator`` of P1
  (mapped grid, N = 48; also N = 96 in the full run) with the terms scattered by the
  compiled loop (:mod:`chuteflow.stability._assembly`) against the numpy road of the same
  plan (``scatter_kernel`` disabled), in the same run, medians of 100 builds of each,
  interleaved; the pieces must be equal bit for bit. Memory as in the sweep workers
  (``keep_freed_memory``).
- ``large_k_direct_P1_3`` (full run only, one repetition): ``least_stable(P1, k = 3)``, the
  direct solve past the continuum (dense QZ up the ladder 80 … 244), against the same with
  a second QZ for every rung's check at N' (no eigenvalues kept by the operators) and the
  check past the continuum at the top rung N = 256 (``TrackingPolicy.top_check_below`` = 1): the code
  before issue 9's ladder reuse, in the same run; the answers must agree.
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

THETA, NU0, K, N = 16.0, 0.05, 2e-3, 100


def run(quick: bool = False) -> list[dict]:
    import scipy.linalg as sla

    from chuteflow._threads import limit_blas_threads
    from chuteflow.stability import (
        OperatorCache,
        RejectionPolicy,
        StabilityOperator,
        dispersion,
        least_stable,
        qz,
    )
    from chuteflow.stability.modes import check_n, nearest_eigenpair
    from chuteflow.steady import solve_steady

    limit_blas_threads(1)
    rep = 2 if quick else 5
    flow = solve_steady(THETA, NU0)
    ref_mode = least_stable(flow, K, n=N)  # warm-up: compilation, caches
    rows = []

    # 1. one pencil: targeted vs QZ
    op = StabilityOperator(flow, N, mapped=False)  # the paper's grid for the QZ baseline
    A, B = op.pencil(K).equilibrated()
    t_qz, w = _best(lambda: sla.eig(A, B, right=False, check_finite=False), max(1, rep // 2))
    ref = w[np.argmin(np.abs(w - ref_mode.alpha))]

    def targeted():
        return nearest_eigenpair(op.pencil(K), ref_mode.alpha + 1e-4)[0]

    t_si, alpha = _best(targeted, rep)
    rows.append(
        {
            "name": "shift_invert_vs_qz",
            "seconds": t_si,
            "baseline_seconds": t_qz,
            "ratio": t_qz / t_si,
            "note": f"N={N}, M={A.shape[0]}; |alpha - alpha_QZ| = {abs(alpha - ref):.1e} "
            "(target 1e-9); target ratio >= 20",
        }
    )

    # 2. least-stable mode with its convergence estimate, end to end
    n2 = check_n(N)
    A2, B2 = StabilityOperator(flow, n2, mapped=False).pencil(K).equilibrated()

    def paper():
        qz(A, B)  # with eigenvectors, for the tail test
        qz(A2, B2, vectors=False)  # the drift test

    t_paper, _ = _best(paper, 1)
    t_ls, mode = _best(lambda: least_stable(flow, K, n=N), rep)
    rows.append(
        {
            "name": "least_stable_vs_qz",
            "seconds": t_ls,
            "baseline_seconds": t_paper,
            "ratio": t_paper / t_ls,
            "note": f"from k = 0 by continuation + drift at N'={n2} + tail; "
            f"|alpha - alpha_QZ| = {abs(mode.alpha - ref):.1e}, drift "
            f"{mode.drift:.1e}",
        }
    )

    # 3. a 50-point dispersion relation including the steady solve
    ks = np.linspace(0.0, 0.02, 50)

    def disp():
        f = solve_steady(THETA, NU0)
        return dispersion(f, ks)

    t_disp, ds = _best(disp, max(1, rep // 2))
    per_point = t_qz_vec = _best(lambda: qz(A, B), 1)[0]
    baseline = len(ks) * (per_point + t_qz * (n2 / N) ** 3)
    rows.append(
        {
            "name": "dispersion_50",
            "seconds": t_disp,
            "baseline_seconds": baseline,
            "ratio": baseline / t_disp,
            "note": f"target < 2 s; N used {sorted(set(ds['n'].values.tolist()))}, max "
            f"drift {float(ds['drift'].max()):.1e}; baseline = 50 x (QZ with "
            f"vectors at N={N}: {t_qz_vec:.2f} s, + QZ at N'={n2}, scaled)",
        }
    )

    # 4. the sinh-mapped grid against the plain grid (adaptive N, same run)
    cases = (
        [("P1", 16.0, 0.05, 0.005)]
        if quick
        else [
            ("P1", 16.0, 0.05, 0.005),
            ("P1", 16.0, 0.05, 0.02),
            ("P4", 14.0, 0.05, 0.005),
            ("P5", 17.0, 0.10, 0.005),
        ]
    )
    for name, th, nu0, k in cases:
        f = solve_steady(th, nu0)
        old = RejectionPolicy(n_start=80)
        t_m, mm = _best(lambda f=f, k=k: least_stable(f, k, cache=OperatorCache(4)), rep)
        t_p, mp = _best(
            lambda f=f, k=k, old=old: least_stable(f, k, policy=old, cache=OperatorCache(4, mapped=False)),
            rep,
        )
        rows.append(
            {
                "name": f"mapped_vs_plain_{name}_{k:g}",
                "seconds": t_m,
                "baseline_seconds": t_p,
                "ratio": t_p / t_m,
                "note": f"N mapped {mm.n} (drift {mm.drift:.0e}) vs plain {mp.n} (drift "
                f"{mp.drift:.0e}); |Δα|/|α| = {abs(mm.alpha - mp.alpha) / abs(mp.alpha):.1e}",
            }
        )
    rows += _assembly(flow, (48,) if quick else (48, 96))
    if not quick:
        rows.append(_large_k())
    return rows


def _assembly(flow, sizes, repeat: int = 100) -> list[dict]:
    import importlib

    from chuteflow._memory import keep_freed_memory

    keep_freed_memory()  # as in the sweep workers: fresh pages for every operator otherwise
    operator = importlib.import_module("chuteflow.stability.operator")
    kernel = operator.scatter_kernel
    out = []
    for n in sizes:
        # interleaved, medians: one build after another, as a solver builds them (a tight
        # loop of one road alone keeps its arrays in cache and flatters both)
        times: dict = {"compiled": [], "numpy": []}
        ops = {}
        for _ in range(repeat):
            for road in ("compiled", "numpy"):
                operator.scatter_kernel = kernel if road == "compiled" else (lambda: None)
                try:
                    t0 = time.perf_counter()
                    ops[road] = operator.StabilityOperator(flow, n, mapped=True)
                    times[road].append(time.perf_counter() - t0)
                finally:
                    operator.scatter_kernel = kernel
        op_c, op_p = ops["compiled"], ops["numpy"]
        same = all(np.array_equal(op_c.pieces[k], op_p.pieces[k]) for k in op_p.pieces) and np.array_equal(
            op_c.B_eq, op_p.B_eq
        )
        t_c, t_p = float(np.median(times["compiled"])), float(np.median(times["numpy"]))
        out.append(
            {
                "name": f"operator_assembly_N{n}",
                "seconds": t_c,
                "baseline_seconds": t_p,
                "ratio": t_p / t_c,
                "note": f"P1, mapped grid, M = {op_c.size}; compiled scatter vs the numpy road of the "
                f"same plan, medians of {repeat} interleaved builds; bit for bit: {same}"
                + ("" if kernel() is not None else " (no C compiler: both the numpy road)"),
            }
        )
    return out


def _remember_nothing(self, k, kz, w) -> None:
    """``StabilityOperator.remember_eigenvalues`` as before it existed: nothing kept."""


def _large_k() -> dict:
    """Row ``large_k_direct_P1_3`` (module docstring)."""
    from unittest import mock

    from chuteflow.stability import DEFAULT_POLICY, OperatorCache, TrackingPolicy, least_stable
    from chuteflow.stability.operator import StabilityOperator
    from chuteflow.steady import solve_steady

    f = solve_steady(THETA, NU0)
    t0 = time.perf_counter()
    new = least_stable(f, 3.0, cache=OperatorCache(4))
    t_new = time.perf_counter() - t0
    at_top = DEFAULT_POLICY.replace(tracking=TrackingPolicy(top_check_below=1.0))
    with mock.patch.object(StabilityOperator, "remember_eigenvalues", _remember_nothing):
        t0 = time.perf_counter()
        old = least_stable(f, 3.0, cache=OperatorCache(4), policy=at_top)
        t_old = time.perf_counter() - t0
    return {
        "name": "large_k_direct_P1_3",
        "seconds": t_new,
        "baseline_seconds": t_old,
        "ratio": t_old / t_new,
        "note": f"α = {new.alpha:.10g} at N = {new.n} (drift {new.drift:.1e}); baseline (a QZ per "
        f"check, the check at 256): α = {old.alpha:.10g} at N = {old.n}; same: {new.alpha == old.alpha}",
    }


def main(argv=None):
    from run import print_table  # the harness's table, when run as a script from benchmarks/

    print_table(run("--quick" in (argv if argv is not None else sys.argv[1:])))


if __name__ == "__main__":
    main()

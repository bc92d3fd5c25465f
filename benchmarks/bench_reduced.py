"""Benchmarks of the reduced 1D model (issue 5): diagram, model build, nonlinear runs.

``run(quick)`` returns rows with keys name, seconds, baseline_seconds, ratio (baseline /
chuteflow), note — the interface of ``benchmarks/run.py``. Run alone:
``python benchmarks/bench_reduced.py [--quick]``.

- ``reduced_diagram``: 1D stability diagram, φ = 0.05, 7 × 7 (quick) or 13 × 13 grid over the
  full-model diagram's range, through the sweep engine (one process). Baseline: a cold-start
  steady solve at every grid point, no continuation. The note gives the ``walk`` engine's
  time. Target: seconds.
- ``reduced_model_build``: F, T̄, a over the θ = 16° family (tolerance 1e-4, midpoints
  checked). No baseline.
- ``simulate_L2000``: θ = 16°, ν0(0) = 0.12 (L_c ≈ 14σ), L = 2000σ (quick: 500σ), N = 4 L
  cells, from noise until the wave leaves the steady family (no saturation exists, see the
  report), in the co-moving frame. Baseline: the same run in the lab frame (same scheme and
  integrator). Target: < 60 s.
- ``simulate_cli_example``: ``chuteflow simulate --theta 16 --nu0 0.05 --length 2000``
  (defaults: automatic grid and end time). No baseline.
"""

from __future__ import annotations

import math
import sys
import time
import warnings
from pathlib import Path

if __package__ in (None, ""):
    root = Path(__file__).resolve().parents[1]
    sys.path[:0] = [str(root / "src"), str(root)]


def _timed(fn):
    t0, c0 = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - t0, time.process_time() - c0


def _plain_diagram(thetas, nus, model):
    """Baseline: every grid point from the solver's cold start, no continuation."""
    from chuteflow.errors import ConvergenceError, NoSteadyFlowError
    from chuteflow.reduced import local_coefficients
    from chuteflow.steady import solve_steady

    out = []
    for th in thetas:
        for nu in nus:
            try:
                f = solve_steady(float(th), float(nu), model, continuation=False)
            except (NoSteadyFlowError, ConvergenceError):
                continue
            out.append(local_coefficients(f).unstable)
    return out


def run(quick: bool = False) -> list[dict]:
    from chuteflow._threads import limit_blas_threads
    from chuteflow.closures import ChuteModel
    from chuteflow.reduced import reduced_diagram, reduced_model, simulate

    limit_blas_threads(1)
    warnings.simplefilter("ignore", RuntimeWarning)
    rows = []
    model = ChuteModel()
    model.evaluate(0.1, 1.0)  # sympy/lambdify warm-up, not part of any timing
    from chuteflow.steady import solve_steady

    solve_steady(16.0, 0.05)

    shape = (7, 7) if quick else (13, 13)
    ds, t_sweep, c_sweep = _timed(lambda: reduced_diagram(0.05, shape=shape, workers=1))
    _, t_walk, _ = _timed(lambda: reduced_diagram(0.05, shape=shape, engine="walk"))
    plain, t_plain, c_plain = _timed(lambda: _plain_diagram(ds["theta"].values, ds["nu0"].values, model))
    n_ok = int((ds["status"].values == 0).sum())
    rows.append(
        {
            "name": f"reduced_diagram_{shape[0]}x{shape[1]}",
            "seconds": t_sweep,
            "baseline_seconds": t_plain,
            "ratio": t_plain / t_sweep,
            "note": f"{n_ok} points with a flow; sweep engine, one process; CPU "
            f"{c_sweep:.1f} s vs {c_plain:.1f} s; walk engine {t_walk:.1f} s; "
            f"baseline: a cold start at every point ({len(plain)} flows found)",
        }
    )

    reduced_model.cache_clear()
    rm, t_build, c_build = _timed(lambda: reduced_model(16.0, model))
    rows.append(
        {
            "name": "reduced_model_build_theta16",
            "seconds": t_build,
            "baseline_seconds": math.nan,
            "ratio": math.nan,
            "note": f"{len(rm.rho)} knots, error ≤ "
            f"{max(rm.accuracy[k] for k in ('F', 'Tbar', 'a')):.1e}; CPU "
            f"{c_build:.1f} s",
        }
    )

    L = 500.0 if quick else 2000.0
    N = int(4 * L)
    kw = dict(nu0=0.12, n_cells=N, on_exit="stop", amplitude=1e-3, seed=0)
    ds, t_w, c_w = _timed(lambda: simulate(rm, L, **kw))
    t_stop = float(ds["t"].values[-1])
    lab, t_l, c_l = _timed(lambda: simulate(rm, L, frame_speed="lab", time=t_stop, **kw))
    rows.append(
        {
            "name": f"simulate_L{L:g}",
            "seconds": t_w,
            "baseline_seconds": t_l,
            "ratio": t_l / t_w,
            "note": f"θ 16°, ν0 0.12, N {N}: {ds.attrs['status']} at t = {t_stop:.4g}, "
            f"{ds.attrs['steps']} steps (lab frame {lab.attrs['steps']}); "
            f"mass drift {ds.attrs['mass_drift']:.1e}; CPU {c_w:.1f} s vs "
            f"{c_l:.1f} s",
        }
    )

    ds, t_c, c_c = _timed(lambda: simulate(rm, 2000.0, nu0=0.05, on_exit="stop"))
    rows.append(
        {
            "name": "simulate_cli_example",
            "seconds": t_c,
            "baseline_seconds": math.nan,
            "ratio": math.nan,
            "note": f"θ 16°, ν0 0.05, L 2000, N {ds.attrs['n_cells']} (auto): "
            f"{ds.attrs['status']} at t = {float(ds['t'].values[-1]):.4g}; "
            f"(ρ̄T̄)' < 0 here: all k grow; CPU {c_c:.1f} s",
        }
    )
    return rows


if __name__ == "__main__":
    quick = "--quick" in sys.argv
    for r in run(quick):
        print(
            f"{r['name']:32s} {r['seconds']:9.3f} s  baseline {r['baseline_seconds']:9.3f} s"
            f"  ratio {r['ratio']:7.2f}  {r['note']}"
        )

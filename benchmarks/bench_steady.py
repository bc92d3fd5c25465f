"""Benchmarks of the steady solver (issue 2): one converged solution and a 40 × 40 map.

``run(quick)`` returns rows with keys name, seconds, baseline_seconds, ratio (baseline /
chuteflow), note — the interface of ``benchmarks/run.py``. Run alone:
``python benchmarks/bench_steady.py [--quick]``.

- ``steady_one_solution``: median wall time of ``solve_steady(16, 0.05)`` from the cold start,
  every quantity computed and converged (change < 1e-8 between n and 3n/2). Baseline: the
  paper's method done plainly — scipy ``solve_ivp`` (DOP853, rtol 1e-11) shooting on u0(0)
  with a bracketing scan and ``brentq`` (``tests/steady/shooting.py``), which reaches the same
  accuracy (the two agree to 1e-10). Target: < 20 ms.
- ``steady_one_solution_continued``: the same from a neighbouring solution (ν0(0) = 0.051),
  as inside families and maps.
- ``steady_map_paper_60x60`` (30 × 30 with ``--quick``): the φ = 0.05 diagram grid of the
  paper, steady flows only, every point decided; baseline: continuation alone (points it does
  not reach left 'unreached'). Target (issue 9): < 10 s.
- ``steady_existence_scan``: the shooting scan (:func:`~chuteflow.steady.shooting.steady_existence`)
  at six points of the φ = 0.05 map (flows, too small, too large with a separatrix), CPU time.
  Baseline: the same scan with the right-hand side of before issue 9 item 4 (the closures'
  and equations' numpy code called with scalars); the verdicts and u0(0), h must agree.
- ``steady_existence_loop``: the same scan, CPU time, with the trials in scipy's compiled
  Dormand–Prince loop (``dopri5`` of ``scipy.integrate.ode``, events located on the step's
  interpolant and refined) against ``solve_ivp(method="RK45")`` with terminal events (the
  same pair; its stepping loop in Python), as before; the verdicts and u0(0) must agree.
- ``steady_diagram_rows``: the steady metric of the quick φ = 0.05 stability diagram (40 × 40,
  ``stage_config(0.05, True)``; every 4th row with ``--quick``), row by row as a sweep task
  solves it (:func:`chuteflow.sweep.runner._steady_chunk`), one process, CPU time. Baseline:
  the same rows with the resolution ladder run to n_max at the round-off floor
  (``Options.noise_exit = False``); the statuses must agree.
- ``steady_stage_maps``: the two maps of the ``steady`` stage of ``chuteflow reproduce
  --quick`` (φ = 0.05 over θ ∈ [8°, 21°] by 1/3°, φ = 0.10 over [11°, 27°] by 0.4°, 40 floor
  densities; 20 × 20 with ``--quick``), two processes. No baseline is run (the ratio is NaN);
  the note gives the status counts. Target (issue 9): the steady stage 3× faster than the
  339 s it took in the quick reproduce before.
- ``steady_map_40x40``: φ = 0.05, θ ∈ [10°, 20°] × ν0(0) ∈ [0.005, 0.5] (geometric), 40 × 40,
  two processes (one BLAS thread each). Baseline: the shooting baseline's median time per
  solution times the number of points with a flow (estimated, not run: ~half an hour).
  Target: < 20 s. The note also gives the one-process time.
"""

from __future__ import annotations

import dataclasses
import statistics
import sys
import time
import warnings
from pathlib import Path

if __package__ in (None, ""):
    root = Path(__file__).resolve().parents[1]
    sys.path[:0] = [str(root / "src"), str(root)]

import numpy as np


def _median_time(fn, repeat, cpu=None):
    """Median wall time; if ``cpu`` is a list, the median CPU time of this process is
    appended to it (less sensitive to other jobs on a shared machine)."""
    ts, cs = [], []
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        fn()
        ts.append(time.perf_counter() - t0)
        cs.append(time.process_time() - c0)
    if cpu is not None:
        cpu.append(statistics.median(cs))
    return statistics.median(ts)


def run(quick: bool = False) -> list[dict]:
    from tests.steady.shooting import Material, solve_by_shooting

    from chuteflow._threads import limit_blas_threads
    from chuteflow.steady import solve_steady, steady_map

    limit_blas_threads(1)
    warnings.simplefilter("ignore", RuntimeWarning)
    rows = []
    ref = solve_steady(16.0, 0.05)  # compiles the closures and equations (≈2 s, once)
    cpu = []
    t_one = _median_time(lambda: solve_steady(16.0, 0.05), 5 if quick else 30, cpu)
    shot = solve_by_shooting(16.0, 0.05, Material())
    t_base = _median_time(lambda: solve_by_shooting(16.0, 0.05, Material()), 1 if quick else 3)
    agree = max(
        abs(getattr(shot, k) / getattr(ref, k) - 1) for k in ("u_floor", "T_floor", "rho_bar", "Q", "h")
    )
    rows.append(
        {
            "name": "steady_one_solution",
            "seconds": t_one,
            "baseline_seconds": t_base,
            "ratio": t_base / t_one,
            "note": f"θ=16°, ν0=0.05, cold start, n={ref.n}, change {ref.convergence:.0e}, "
            f"CPU {cpu[-1] * 1e3:.1f} ms; "
            f"baseline solve_ivp+brentq ({shot.shots} shots), agrees to "
            f"{agree:.0e}; target < 0.020 s",
        }
    )
    near = solve_steady(16.0, 0.051)
    t_cont = _median_time(lambda: solve_steady(16.0, 0.05, guess=near), 5 if quick else 30, cpu)
    rows.append(
        {
            "name": "steady_one_solution_continued",
            "seconds": t_cont,
            "baseline_seconds": t_base,
            "ratio": t_base / t_cont,
            "note": f"from the solution at ν0=0.051 (as in families and maps), CPU {cpu[-1] * 1e3:.1f} ms",
        }
    )

    rows.append(_existence_row())
    rows.append(_existence_loop_row())
    rows.append(_diagram_rows_row(quick))
    rows.append(_stage_maps_row(quick))

    size = 20 if quick else 40
    ths = np.linspace(10.0, 20.0, size)
    nus = np.geomspace(0.005, 0.5, size)
    t0 = time.perf_counter()
    ds = steady_map(ths, nus, workers=2)
    t_map = time.perf_counter() - t0
    t0, c0 = time.perf_counter(), time.process_time()
    ds1 = steady_map(ths, nus, workers=1)
    t_map1, c_map1 = time.perf_counter() - t0, time.process_time() - c0
    st = ds.status.values
    n_ok = int(((st == "ok") | (st == "thin")).sum())
    same = bool((st == ds1.status.values).all())
    counts = ", ".join(
        f"{k} {int((st == k).sum())}" for k in ("ok", "thin", "no_steady_flow", "not_converged", "unreached")
    )
    rows.append(
        {
            "name": f"steady_map_{size}x{size}",
            "seconds": t_map,
            "baseline_seconds": n_ok * t_base,
            "ratio": n_ok * t_base / t_map,
            "note": f"φ=0.05, θ∈[10,20]°, ν0∈[0.005,0.5]; 2 processes; 1 process "
            f"{t_map1:.1f} s, CPU {c_map1:.1f} s (same statuses: {same}); "
            f"{counts}; baseline "
            f"estimated = {n_ok} flows × shooting time; target < 20 s",
        }
    )
    # the diagram grid of the paper (φ = 0.05, DIAGRAM_RANGES) at 60 × 60, steady flows only,
    # every point decided (continuation + shooting scan); baseline: continuation alone, which
    # leaves the points it does not reach 'unreached' (issue 9: target < 10 s on 2 cores)
    from chuteflow.papers.mitarai2004.points import DIAGRAM_RANGES

    size = 30 if quick else 60
    (t0_, t1_), (n0_, n1_) = DIAGRAM_RANGES[0.05]
    ths, nus = np.linspace(t0_, t1_, size), np.geomspace(n0_, n1_, size)
    t0 = time.perf_counter()
    base = steady_map(ths, nus, workers=2, decide=False)
    t_base_map = time.perf_counter() - t0
    t0 = time.perf_counter()
    ds = steady_map(ths, nus, workers=2)
    t_map = time.perf_counter() - t0

    def _counts(d):
        st = d.status.values
        return ", ".join(
            f"{k} {int((st == k).sum())}"
            for k in ("ok", "thin", "no_steady_flow", "not_converged", "unreached")
        )

    rows.append(
        {
            "name": f"steady_map_paper_{size}x{size}",
            "seconds": t_map,
            "baseline_seconds": t_base_map,
            "ratio": t_base_map / t_map,
            "note": f"φ=0.05, θ∈[{t0_:g},{t1_:g}]°, ν0∈[{n0_:g},{n1_:g}], 2 processes, every point "
            f"decided: {_counts(ds)}; baseline = continuation only: {_counts(base)}; "
            "target < 10 s",
        }
    )
    return rows


#: Points of the shooting-scan benchmark: (θ, ν0(0)) at φ = 0.05.
_SCAN_POINTS = ((16.0, 0.05), (12.0, 0.01), (20.0, 0.3), (14.67, 0.45), (10.67, 0.5), (18.67, 0.2))


def _numpy_ode():
    """SteadyODE with the right-hand side of before issue 9 item 4 (baseline)."""
    from chuteflow.closures.model import FUNCTIONS, ORDERS, _compiled
    from chuteflow.equations import BASE, compiled_equations
    from chuteflow.steady.shooting.ode import SteadyODE, _term_index

    class NumpyODE(SteadyODE):
        def __init__(self, theta, model):
            super().__init__(theta, model)
            eqs = compiled_equations()
            self._ymom, self._energy = eqs["ymom"], eqs["energy"]
            self._i_nu_y = _term_index(self._ymom, "nu", 1)
            self._i_T_yy = _term_index(self._energy, "T", 2)
            self._partials = _compiled(*model.closures)[0]
            self._ip = FUNCTIONS.index("p") * len(ORDERS) + ORDERS.index((0, 0))
            self._imu = FUNCTIONS.index("mu") * len(ORDERS) + ORDERS.index((0, 0))
            self._slot = {b: i for i, b in enumerate(BASE)}

        def rhs(self, y, z):
            s, u, T, T_y = (np.float64(v) for v in z)
            nu = np.exp(s)
            flat = [np.float64(v) for v in self._partials(nu, T, *self._params)]
            u_y = self.tan * flat[self._ip] / flat[self._imu]
            base = [np.float64(0.0)] * len(self._slot)
            for name, value in (("nu", nu), ("u", u), ("u_y", u_y), ("T", T), ("T_y", T_y)):
                base[self._slot[name]] = value
            args = base + flat + [self.sin, self.cos]
            r, c = self._ymom.evaluate_arguments(args)
            nu_y = -np.float64(r) / np.float64(c[self._i_nu_y])
            args[self._slot["nu_y"]] = nu_y
            r, c = self._energy.evaluate_arguments(args)
            T_yy = -np.float64(r) / np.float64(c[self._i_T_yy])
            return [float(nu_y / nu), float(u_y), float(T_y), float(T_yy)]

        def rhs_bounded(self, y, z):
            # what the compiled Dormand–Prince loop calls: the baseline's right-hand side
            # with the same bounding of non-finite values
            try:
                out = self.rhs(y, z)
            except (ArithmeticError, ValueError, TypeError):
                return [1e300] * 4
            return [v if np.isfinite(v) else 1e300 for v in out]

    return NumpyODE


def _solve_ivp_integrate(fun, z0, y_cap, rtol, events, *, dense=False):
    """``steady.shooting.integrate`` as it was before: scipy's ``solve_ivp`` (RK45, its
    stepping loop in Python) with terminal events on its dense output (baseline)."""
    from scipy.integrate import solve_ivp

    from chuteflow.steady.shooting.trajectory import Trajectory

    evs = []
    for _, g, d in events:

        def ev(y, z, g=g):
            return g(z)

        ev.terminal, ev.direction = True, float(d)  # type: ignore[attr-defined]
        evs.append(ev)
    with np.errstate(all="ignore"):
        sol = solve_ivp(
            fun, (0.0, y_cap), z0, method="RK45", rtol=rtol, atol=1e-12, events=evs, dense_output=dense
        )
    hit = next((events[i][0] for i, te in enumerate(sol.t_events) if len(te)), None)
    status = 0 if (hit or sol.status == 0) else -1
    return Trajectory(sol.t, sol.y, hit, status, sol.sol if dense else None)


def _scan_pair(name: str, baseline, note) -> dict:
    """The shooting scan at :data:`_SCAN_POINTS` (CPU time), then again inside the context
    manager ``baseline`` (which swaps in the baseline's piece); the verdicts and u0(0) of the
    two are compared. ``note(new, same, agree)`` writes the row's note."""
    from chuteflow.closures import ChuteModel
    from chuteflow.steady import shooting as existence

    model = ChuteModel(roughness=0.05)
    existence.steady_existence(16.0, 0.05, model)  # generated code loaded (or derived) once

    def scan():
        c0 = time.process_time()
        out = [existence.steady_existence(th, nu, model) for th, nu in _SCAN_POINTS]
        return time.process_time() - c0, out

    t_new, new = scan()
    with baseline(existence):
        t_old, old = scan()
    same = all(a.kind == b.kind for a, b in zip(new, old))
    agree = max(
        (abs(a.u_floor / b.u_floor - 1) for a, b in zip(new, old) if a.exists and b.exists), default=0.0
    )
    return {
        "name": name,
        "seconds": t_new,
        "baseline_seconds": t_old,
        "ratio": t_old / t_new,
        "note": note(new, same, agree),
    }


def _existence_loop_row() -> dict:
    from unittest import mock

    return _scan_pair(
        "steady_existence_loop",
        lambda existence: mock.patch.object(existence, "integrate", _solve_ivp_integrate),
        lambda new, same, agree: (
            f"the scan's {len(_SCAN_POINTS)} points, CPU time: scipy's compiled "
            f"dopri5 with events against solve_ivp RK45 (Python loop); same verdicts: {same}, u0(0) "
            f"agree to {agree:.0e}"
        ),
    )


def _existence_row() -> dict:
    from unittest import mock

    return _scan_pair(
        "steady_existence_scan",
        lambda existence: mock.patch.object(existence, "SteadyODE", _numpy_ode()),
        lambda new, same, agree: (
            f"{len(_SCAN_POINTS)} points (φ=0.05), CPU time, "
            f"{sum(v.shots for v in new)} shots; baseline: numpy right-hand side (both in scipy's "
            f"compiled dopri5 loop); same verdicts: {same}, u0(0) agree to {agree:.0e}"
        ),
    )


def _diagram_rows_row(quick: bool) -> dict:
    from unittest import mock

    from chuteflow.papers.mitarai2004.stages.diagrams import stage_config
    from chuteflow.steady import family, options
    from chuteflow.sweep.runner import _steady_chunk

    cfg = stage_config(0.05, True)
    rows = range(0, len(cfg.theta), 4 if quick else 1)

    def sweep():
        with np.errstate(all="ignore"):
            return [s for i in rows for _, s, _ in _steady_chunk(cfg, cfg.theta[i], list(cfg.nu0), cfg.model)]

    c0 = time.process_time()
    new = sweep()
    c_new = time.process_time() - c0
    plain = options.Options(noise_exit=False)
    with mock.patch.object(family, "Options", lambda **kw: dataclasses.replace(plain, **kw)):
        c0 = time.process_time()
        old = sweep()
        c_old = time.process_time() - c0
    counts = ", ".join(f"{k} {new.count(k)}" for k in sorted(set(new)))
    return {
        "name": "steady_diagram_rows",
        "seconds": c_new,
        "baseline_seconds": c_old,
        "ratio": c_old / c_new,
        "note": f"quick φ=0.05 diagram, {len(rows)} of {len(cfg.theta)} rows × {len(cfg.nu0)}, 1 process, "
        f"CPU time; {counts}; same statuses as the baseline: {new == old}",
    }


def _stage_maps_row(quick: bool) -> dict:
    from chuteflow.closures import ChuteModel
    from chuteflow.steady import steady_map

    size = 20 if quick else 40
    grids = {0.05: (8.0, 21.0, 1.0 / 3.0), 0.10: (11.0, 27.0, 0.4)}
    t0 = time.perf_counter()
    parts = []
    for phi, (lo, hi, step) in grids.items():
        ths = np.round(np.arange(lo, hi + 0.5 * step, step), 10)
        if quick:
            ths = ths[:: max(1, len(ths) // size)]
        ds = steady_map(ths, np.geomspace(0.005, 0.55, size), ChuteModel(roughness=phi), workers=2)
        st = ds.status.values
        counts = ", ".join(
            f"{k} {int((st == k).sum())}" for k in ("ok", "thin", "no_steady_flow", "not_converged")
        )
        parts.append(f"φ={phi:g} {len(ths)}×{size}: {counts}")
    t = time.perf_counter() - t0
    return {
        "name": "steady_stage_maps",
        "seconds": t,
        "baseline_seconds": float("nan"),
        "ratio": float("nan"),
        "note": "the steady stage's two maps, 2 processes; " + "; ".join(parts),
    }


if __name__ == "__main__":
    import json

    out = run(quick="--quick" in sys.argv)
    print(json.dumps(out, indent=1))

"""Benchmark of the time-dependent simulation (issue 11, docs/dns.md), one BLAS thread.

``run(quick)`` returns rows with keys name, seconds, baseline_seconds, ratio, note (the
interface of ``benchmarks/run.py``). Run alone: ``python benchmarks/bench_dns.py [--quick]``.

- ``dns_linear_P1``: the linear-phase verification at P1 (θ = 16°, ν0(0) = 0.05, φ = 0.05,
  L = 2π/0.003): steady flow, least-stable eigenmode and two wave periods at Δt = period/100.
  Baseline: the issue's target of 5 minutes (ratio = target / measured, > 1 is within
  target). The note has the time per step, the steps per growth time 1/Re α and the errors.
- ``dns_step_L1000`` (full mode): time per step of the nonlinear run of the reproduce stage
  (L = 1000, nx = 65, ny = 80, Δt = 4) over 200 steps from noise of amplitude 1e-3; no
  baseline (no other solver of these equations here).
- ``dns_wave_P1_coarse``: one density wave from noise (amplitude 1e-2) to saturation at P1,
  L = 1000, on the reproduce stage's coarse grid (nx = 7, N = 24, Δt = 20, stopped once the
  amplitude has settled to 5 %). Baseline: the 3-minute target for the saturated P1 wave
  (which asks for the resolved wave; this grid's tails say it is coarse: see the note).
- ``dns_wave_P1_adaptive``: the same wave from noise (amplitude 1e-3) to saturation (2 %) at
  nx = 9, N = 32 with the time-step control (``NewtonSettings(dt_tol=1e-3)``, Δt from 4 up
  to 256; issue 42 item 2). Baseline: the 3-minute target. The fixed Δt = 4 run of this grid
  to t = 24000 took 100 s (6000 steps) and gives the same ρ̄ range to 3e-4
  (docs/dns.md, *Time-step control*).
- ``dns_columns_large_wave``: the column preconditioner at a large wave (P1, L = 2000,
  nx = 65, N = 64, ln ν perturbed by 0.25 in mode 1 and 0.08 in mode 2), four BDF2 steps
  of Δt = 4 with ``NewtonSettings(preconditioner="columns")`` from the same state, the build
  included: the default (the exact Chebyshev blocks by the block-tridiagonal LU,
  ``column_y="chebyshev"``, each row's own x-transport upwind, ``column_x="upwind"``)
  against the plain baseline of finite differences in y by the sparse LU and central
  x-differences (``column_y="fd"``, ``column_x="central"``) in the same run; the note has
  GMRES per step of both and of the Chebyshev blocks with central x, and the end states'
  distance (docs/dns.md, *The block-tridiagonal LU*, *Upwind transport*). Measured
  2026-12-07: 9.6 s against 13.8 s, GMRES 78.5 against 157.5 (central Chebyshev 89.2).
- ``dns_columns_solve``: one solve of the column preconditioner's block LU
  (:class:`~chuteflow.dns.cyclic.CyclicBlockLU`) at a large wave on the grid of P1's
  saturated wave at L = 2000 (nx = 225, N = 96, ln ν perturbed by 0.5 in mode 1 and 0.15 in
  mode 2), averaged over 20: the couplings L_i, U_i in CSR form (13 % nonzero,
  ``cyclic.SPARSE_BELOW``) against the baseline of dense couplings (as before 2026-12-08) in
  the same run; the note has the two factorisations' seconds and the solves' distance
  (docs/dns.md, *The columns' couplings kept sparse*). Measured 2026-12-08 at a run's
  checkpoint: 50.8 against 64.6 ms.
- ``dns_coupled_apply``: one application of the mode-coupled preconditioner
  (:class:`~chuteflow.dns.CoupledPreconditioner`) at P1, L = 1000, nx = 41, N = 80 (the
  grid of the 3-minute target) at a ±20 % wave, averaged over 100: the couplings applied
  from their factors (two products with S_m⁻¹ per mode) against the baseline of the same
  elimination with the couplings as dense blocks (S_m⁻¹, K_m = S_m⁻¹ L_m and
  W_m = U_{m−1} S_m⁻¹: three dense products per mode, as before 2026-12-07) in the same
  run; the note has the distance of the two corrections.
- ``dns_coupled_build``: one build of the same preconditioner (coefficients, harmonics,
  elimination) with U_m S_m⁻¹ L_m from the couplings' factors (real products with the
  Chebyshev matrices) against the baseline of the dense elimination as before 2026-12-07
  (U_m, D_m, L_m assembled dense, :func:`~chuteflow.dns.coupled.coupled_blocks`; S_m⁻¹ L_m
  and U_m (S_m⁻¹ L_m) as complex products), averaged over 2; the note has the distance of
  the S_m⁻¹. On a finer grid than the other rows: P1, L = 2000, nx = 129, N = 96 (ln ν
  perturbed by 0.25 in mode 1), the grid P5's bore is refined through.
- ``dns_residual_padding``: one residual evaluation at the same ±20 % wave and grid (41 × 80)
  on the default padded x grid (:func:`~chuteflow.dns.discretisation.padded_points`: 64
  points) against the baseline of 3M + 1 = 61 points (a prime FFT length, the default before
  2026-12-07) in the same run, averaged over 200; the note has the residuals' distance.
- ``dns_newton_rtol``: P1, L = 1000 from noise (amplitude 1e-3) to saturation (2 %) at
  nx = 33, N = 48 with ``"coupled"`` and the step control (``dt_tol`` = 1e-3): Newton stopped
  at 1e-3 of its guess's residual (``NewtonSettings.newton_rtol``, the default) against the
  baseline of ``newton_rtol = 0`` (every step to ``atol`` = 1e-10, as before 2026-12-07) in
  the same run; the note has the steps, GMRES per step and how far the two waves' ρ̄ ranges
  are apart (docs/dns.md, *Newton's tolerance relative to the step*).
- ``dns_step_L1000_nonlinear`` (full mode): the same grid over 50 steps from the eigenmode at
  amplitude 0.2 (ρ̄ within ±6 %, a finite-amplitude start): the nonlinear phase's time per
  step, Newton–Krylov with GMRES. No baseline; the docs compare with the earlier solver.
"""

from __future__ import annotations

import math
import sys
import time
import warnings
from pathlib import Path

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))


def _timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return out, time.perf_counter() - t0


def _per_call(fn, repeats: int):
    """(mean seconds per call, the last result) of ``repeats`` calls of ``fn`` after one
    warm-up call."""
    out = fn()
    t0 = time.perf_counter()
    for _ in range(repeats):
        out = fn()
    return (time.perf_counter() - t0) / repeats, out


def run(quick: bool = False) -> list[dict]:
    from chuteflow._threads import limit_blas_threads
    from chuteflow.closures import ChuteModel
    from chuteflow.dns import NewtonSettings, simulate, summary
    from chuteflow.steady import solve_steady

    limit_blas_threads(1)
    warnings.simplefilter("ignore", RuntimeWarning)
    model = ChuteModel(roughness=0.05)
    solve_steady(16.0, 0.05, model)  # warm-up: compiled code loaded, not timed
    L = 2 * math.pi / 0.003
    ds, t_lin = _timed(lambda: simulate(solve_steady(16.0, 0.05, model), L))
    s = summary(ds)
    steps_growth = 1.0 / s["alpha_re"] / s["dt"]
    rows = [
        {
            "name": "dns_linear_P1",
            "seconds": t_lin,
            "baseline_seconds": 300.0,
            "ratio": 300.0 / t_lin,
            "note": f"{s['steps']} steps, {1e3 * s['time_per_step']:.1f} ms/step, "
            f"{steps_growth:.0f} steps per growth time; growth error {s['growth_rate_error']:.1e}, "
            f"phase-velocity error {s['phase_velocity_error']:.1e}, mass drift {s['mass_drift']:.1e}; "
            "baseline: the issue's 5-minute target",
        }
    ]
    flow = solve_steady(16.0, 0.05, model)
    w, t_w = _timed(
        lambda: simulate(
            flow, 1000.0, time=30000.0, dt=20.0, modes=3, n=24, init="noise", amplitude=1e-2,
            saturation_tol=0.05, record_every=5,
        )
    )  # fmt: skip
    ws = summary(w)
    rows.append(
        {
            "name": "dns_wave_P1_coarse",
            "seconds": t_w,
            "baseline_seconds": 180.0,
            "ratio": 180.0 / t_w,
            "note": f"{ws['verdict']} at t = {ws['time_end']:.0f}, ρ̄ {100 * ws['rho_min_rel']:+.1f} … "
            f"{100 * ws['rho_max_rel']:+.1f} % (resolved run: −23 … +29 %), {ws['steps']} steps, "
            f"GMRES {ws['krylov_mean']:.1f}/step, tails x {ws['x_tail']:.1e} y {ws['y_tail']:.1e} "
            f"(coarse), mass drift {ws['mass_drift']:.1e}; baseline: the 3-minute target",
        }
    )
    a_w, t_aw = _timed(
        lambda: simulate(
            flow, 1000.0, time=40000.0, dt=4.0, modes=4, n=32, init="noise", amplitude=1e-3,
            saturation_tol=0.02, settings=NewtonSettings(dt_tol=1e-3),
        )
    )  # fmt: skip
    aws = summary(a_w)
    rows.append(
        {
            "name": "dns_wave_P1_adaptive",
            "seconds": t_aw,
            "baseline_seconds": 180.0,
            "ratio": 180.0 / t_aw,
            "note": f"{aws['verdict']} at t = {aws['time_end']:.0f}, ρ̄ {100 * aws['rho_min_rel']:+.1f} … "
            f"{100 * aws['rho_max_rel']:+.1f} %, {aws['steps']} steps (Δt control 1e-3), "
            f"GMRES {aws['krylov_mean']:.1f}/step, mass drift {aws['mass_drift']:.1e}; "
            "baseline: the 3-minute target",
        }
    )
    rows.append(_columns_row(model))
    rows.append(_columns_solve_row(model))
    rows.extend(_coupled_rows(model))
    rows.append(_padding_row(model))
    rows.append(_newton_rtol_row(flow))
    if not quick:
        kw = dict(time=800.0, dt=4.0, modes=32, init="noise", amplitude=1e-3, n=80)
        a, t_a = _timed(lambda: simulate(flow, 1000.0, **kw))
        rows.append(
            {
                "name": "dns_step_L1000",
                "seconds": t_a,
                "baseline_seconds": math.nan,
                "ratio": math.nan,
                "note": f"{a.attrs['steps']} steps, {1e3 * a.attrs['time_per_step']:.1f} ms/step "
                f"(Newton {a.attrs['newton_mean']:.2f}/step); no baseline",
            }
        )
        kw = dict(time=200.0, dt=4.0, modes=32, init="mode", amplitude=0.2, n=80)
        b, t_b = _timed(lambda: simulate(flow, 1000.0, frame_speed=7.8, **kw))
        rows.append(
            {
                "name": "dns_step_L1000_nonlinear",
                "seconds": t_b,
                "baseline_seconds": math.nan,
                "ratio": math.nan,
                "note": f"{b.attrs['steps']} steps, {1e3 * b.attrs['time_per_step']:.1f} ms/step "
                f"(Newton {b.attrs['newton_mean']:.2f}/step), mass drift {b.attrs['mass_drift']:.1e}; "
                "no baseline",
            }
        )
    return rows


def _newton_rtol_row(flow) -> dict:
    """``dns_newton_rtol`` (module docstring)."""
    from chuteflow.dns import NewtonSettings, simulate, summary

    out = {}
    for rtol in (1e-3, 0.0):
        settings = NewtonSettings(dt_tol=1e-3, preconditioner="coupled", newton_rtol=rtol)
        ds, t = _timed(
            lambda settings=settings: simulate(
                flow, 1000.0, time=40000.0, dt=4.0, modes=16, n=48, init="noise", amplitude=1e-3,
                saturation_tol=0.02, settings=settings,
            )
        )  # fmt: skip
        out[rtol] = (t, summary(ds))
    (t_r, s_r), (t_0, s_0) = out[1e-3], out[0.0]
    apart = max(abs(s_r["rho_min_rel"] - s_0["rho_min_rel"]), abs(s_r["rho_max_rel"] - s_0["rho_max_rel"]))
    return {
        "name": "dns_newton_rtol",
        "seconds": t_r,
        "baseline_seconds": t_0,
        "ratio": t_0 / t_r,
        "note": f"33 × 48 from noise to {s_r['verdict']} at t = {s_r['time_end']:.0f}: "
        f"{s_r['steps']} steps, GMRES {s_r['krylov_mean']:.1f}/step with newton_rtol = 1e-3 against "
        f"{s_0['steps']} steps, {s_0['krylov_mean']:.1f}/step to atol alone (baseline); "
        f"ρ̄ {100 * s_r['rho_min_rel']:+.3f} … {100 * s_r['rho_max_rel']:+.3f} %, the ranges "
        f"{apart:.1e} apart; mass drift {s_r['mass_drift']:.1e}",
    }


def _p1_wave(model, length: float, n: int, modes: int, lnnu: dict[int, complex]):
    """(Discretisation, coefficients) of P1's steady flow on an L = ``length`` period with
    ln ν perturbed by ``lnnu[m]`` in mode m (a large-amplitude state without a run)."""
    import numpy as np

    from chuteflow.dns import Discretisation
    from chuteflow.steady import solve_steady

    flow = solve_steady(16.0, 0.05, model)
    d = Discretisation(16.0, model, length, flow.y_max, n, modes, frame=7.8)
    p = flow.profiles(d.grid.y)
    C = np.zeros(d.shape, complex)
    C[0, :, 0], C[1, :, 0], C[3, :, 0] = np.log(p["nu"]), p["u"], p["T"]
    for m, a in lnnu.items():
        C[0, :, m] += a
    return d, C


def _padding_row(model) -> dict:
    """``dns_residual_padding`` (module docstring)."""
    import dataclasses

    import numpy as np

    from chuteflow.dns import Stepper

    d, C = _p1_wave(model, 1000.0, 80, 20, {1: 0.2 * (1 + 0.5j)})
    plain = dataclasses.replace(d, nxp=3 * d.modes + 1)
    times = {}
    for name, disc in (("fast", d), ("plain", plain)):
        st = Stepper(disc)
        hist = (st.physical(C), st.physical(C))
        times[name] = _per_call(lambda disc=disc, hist=hist: disc.residual(C, hist, 4.0), 200)
    (t_f, r_f), (t_p, r_p) = times["fast"], times["plain"]
    return {
        "name": "dns_residual_padding",
        "seconds": t_f,
        "baseline_seconds": t_p,
        "ratio": t_p / t_f,
        "note": f"one residual at 41 × 80, ±20 % wave: {d.nxp} padded points {1e3 * t_f:.2f} ms "
        f"against {plain.nxp} points {1e3 * t_p:.2f} ms; residuals {np.abs(r_f - r_p).max():.1e} "
        f"apart (of {np.abs(r_p).max():.2f})",
    }


def _columns_row(model) -> dict:
    """``dns_columns_large_wave`` (module docstring)."""
    import numpy as np

    from chuteflow.dns import NewtonSettings, Stepper

    d, C0 = _p1_wave(model, 2000.0, 64, 32, {1: 0.25 * (1 + 0.5j), 2: 0.08 * (0.2 - 1j)})
    rho = d.depth_integrals(C0)[0]
    out = {}
    for y, x in (("fd", "central"), ("chebyshev", "central"), ("chebyshev", "upwind")):
        st = Stepper(d, NewtonSettings(preconditioner="columns", column_y=y, column_x=x))
        C, first = C0.copy(), True
        hist = (st.physical(C), st.physical(C))
        krylov = 0
        t0 = time.perf_counter()
        for _ in range(4):
            C_new, info = st.step(C, hist, 4.0, first=first)
            krylov += info.krylov
            hist = (st.physical(C_new), hist[0])
            C, first = C_new, False
        out[y, x] = (time.perf_counter() - t0, krylov / 4, C)
    (t_fd, k_fd, C_fd), (t_cc, k_cc, _), (t_ch, k_ch, C_ch) = out.values()
    return {
        "name": "dns_columns_large_wave",
        "seconds": t_ch,
        "baseline_seconds": t_fd,
        "ratio": t_fd / t_ch,
        "note": f"4 steps of Δt = 4 at ρ̄ {rho.min() / rho.mean() - 1:+.2f} … "
        f"{rho.max() / rho.mean() - 1:+.2f}, "
        f"65 × 64, build included: GMRES {k_ch:.1f}/step (the default: Chebyshev blocks, block LU, "
        f"upwind transport) against {k_fd:.1f} (baseline: finite differences in y, sparse LU, "
        f"central x) and {k_cc:.1f} ({t_cc:.1f} s: Chebyshev blocks, central x); end states "
        f"{np.abs(C_fd - C_ch).max():.1e} apart",
    }


def _columns_solve_row(model) -> dict:
    """``dns_columns_solve`` (module docstring)."""
    import numpy as np

    from chuteflow.dns import Stepper, cyclic
    from chuteflow.dns.columns import column_blocks, column_coefficients
    from chuteflow.dns.discretisation import BDF2

    d, C = _p1_wave(model, 2000.0, 96, 112, {1: 0.5 * (1 + 0.5j), 2: 0.15 * (0.2 - 1j)})
    st = Stepper(d)
    hist = (st.physical(C), st.physical(C))
    blocks = column_blocks(d, column_coefficients(d, C, hist, 8.0, BDF2))
    rhs = np.random.default_rng(0).normal(size=blocks[0].shape[0] * blocks[0].shape[1])
    out = {}
    keep = cyclic.SPARSE_BELOW
    try:
        for name, below in (("sparse", keep), ("dense", 0.0)):
            cyclic.SPARSE_BELOW = below
            lu, t_build = _timed(lambda: cyclic.CyclicBlockLU(blocks[0], blocks[-1], blocks[1]))
            t_solve, x = _per_call(lambda lu=lu: lu.solve(rhs), 20)
            out[name] = (t_solve, t_build, x)
    finally:
        cyclic.SPARSE_BELOW = keep
    (t_s, b_s, x_s), (t_d, b_d, x_d) = out["sparse"], out["dense"]
    nnz = np.count_nonzero(blocks[-1]) / blocks[-1].size
    return {
        "name": "dns_columns_solve",
        "seconds": t_s,
        "baseline_seconds": t_d,
        "ratio": t_d / t_s,
        "note": f"225 × 96, couplings {100 * nnz:.0f} % nonzero: a solve {1e3 * t_s:.1f} ms (CSR couplings) "
        f"against {1e3 * t_d:.1f} ms (dense, baseline); factorisation {b_s:.1f} s against {b_d:.1f} s; "
        f"solves {np.abs(x_s - x_d).max() / np.abs(x_d).max():.1e} apart (relative)",
    }


def _coupled_rows(model) -> list[dict]:
    """``dns_coupled_apply`` and ``dns_coupled_build`` (module docstring)."""
    import numpy as np

    from chuteflow.dns import CoupledPreconditioner, Stepper
    from chuteflow.dns.columns import jet_coefficients
    from chuteflow.dns.coupled import _dense, coupled_blocks, coupling_factors
    from chuteflow.dns.discretisation import BDF2

    d, C = _p1_wave(model, 1000.0, 80, 20, {1: 0.2 * (1 + 0.5j)})
    st = Stepper(d)
    hist = (st.physical(C), st.physical(C))
    P = CoupledPreconditioner.build(d, C, hist, 4.0, BDF2)
    # the plain baselines: the same elimination from the dense blocks, U_m dense,
    # W_m = U_m S_{m+1}⁻¹ and K_m = S_m⁻¹ L_m stored (as before 2026-12-07)
    B = coupled_blocks(d, jet_coefficients(d, C, hist, 4.0, BDF2), np.arange(d.modes + 1), 1)
    M, size = d.modes, 4 * (d.n + 1)
    W = [None] + [B[m - 1, 0] @ P._sinv[m] for m in range(1, M + 1)]
    K = [None] + [P._sinv[m] @ B[m, 2] for m in range(1, M + 1)]

    def dense_build(d, C, hist):
        # as before 2026-12-07: the three blocks of every mode assembled dense in one einsum
        M, mm = d.modes, d.n + 1
        E = coupling_factors(d, jet_coefficients(d, C, hist, 4.0, BDF2), np.arange(M + 1), 1)
        dy = np.stack((np.eye(mm), d.grid.D, d.grid.D2))
        Bd = np.einsum("iqfcrj,cjl->iqrjfl", E, dy).reshape(M + 1, 3, 4 * mm, 4 * mm)
        Bd[:, 1] = [_dense(d, E[m, 1], m) for m in range(M + 1)]  # (the top conditions)
        sinv = [None] * (M + 1)
        S = Bd[M, 1]
        for m in range(M, 0, -1):
            sinv[m] = np.linalg.inv(S)
            UK = Bd[m - 1, 0] @ (sinv[m] @ Bd[m, 2])
            S = Bd[m - 1, 1] - UK
        sinv[0] = np.linalg.inv(Bd[0, 1].real - 2.0 * UK.real)
        return sinv

    def plain(R):
        r = R.reshape(size, M + 1).T
        rho = r.astype(complex)
        for m in range(M - 1, 0, -1):
            rho[m] -= W[m + 1] @ rho[m + 1]
        x = np.empty_like(rho)
        x[0] = P._sinv[0] @ (r[0].real - 2.0 * (W[1] @ rho[1]).real)
        for m in range(1, M + 1):
            x[m] = P._sinv[m] @ rho[m] - K[m] @ x[m - 1]
        out = x.T.reshape(R.shape)
        out[..., 0] = out[..., 0].real
        return out

    rng = np.random.default_rng(1)
    R = rng.normal(size=d.shape) + 1j * rng.normal(size=d.shape)
    R[..., 0] = R[..., 0].real
    times = {}
    for name, fn in (("factored", P.apply), ("plain", plain)):
        times[name] = _per_call(lambda fn=fn: fn(R), 100)
    (t_f, x_f), (t_p, x_p) = times["factored"], times["plain"]
    # the build on a finer grid (129 × 96, L = 2000: where P5's bore is refined to), where the
    # dense blocks' assembly and products weigh more
    d, C = _p1_wave(model, 2000.0, 96, 64, {1: 0.25 * (1 + 0.5j)})
    st = Stepper(d)
    hist = (st.physical(C), st.physical(C))
    t_b, P_b = _per_call(lambda: CoupledPreconditioner.build(d, C, hist, 4.0, BDF2), 2)
    t_d, sinv_d = _per_call(lambda: dense_build(d, C, hist), 2)
    build_diff = max(np.abs(a - b).max() / np.abs(b).max() for a, b in zip(P_b._sinv, sinv_d))
    grid = f"at 41 × 80 (M = 20, blocks {size} square), ±20 % wave"
    return [
        {
            "name": "dns_coupled_apply",
            "seconds": t_f,
            "baseline_seconds": t_p,
            "ratio": t_p / t_f,
            "note": f"one application {grid}: {1e3 * t_f:.2f} ms against "
            f"{1e3 * t_p:.2f} ms with the couplings as dense blocks; corrections "
            f"{np.abs(x_f - x_p).max() / np.abs(x_p).max():.1e} apart (relative)",
        },
        {
            "name": "dns_coupled_build",
            "seconds": t_b,
            "baseline_seconds": t_d,
            "ratio": t_d / t_b,
            "note": f"one build at 129 × 96 (M = 64, L = 2000), ±25 % wave: U S⁻¹ L from the couplings' "
            f"factors {t_b:.2f} s against the three dense blocks per mode and their products "
            f"{t_d:.2f} s; S_m⁻¹ {build_diff:.1e} apart",
        },
    ]


if __name__ == "__main__":
    for r in run(quick="--quick" in sys.argv):
        print(
            f"{r['name']:<18} {r['seconds']:8.2f} s  baseline {r['baseline_seconds']:8.2f} s  "
            f"ratio {r['ratio']:.2f}  {r['note']}"
        )

"""Where a nonlinear step's time goes: GMRES iterations and seconds per preconditioner.

Two stages (docs/dns.md, *Where a nonlinear step's time goes*):

``--make-state FILE``: P1 (θ = 16°, ν0(0) = 0.05, φ = 0.05; ``--theta``, ``--nu0``), L = 1000
(``--length``), from noise of
amplitude 1e-3 with the time-step control (``dt_tol`` = 1e-3, Δt from 4) and
``--preconditioner``, ``--nx`` × ``--ny``, up to ``--time`` (27000: ρ̄ ≈ ±20 %, the nonlinear
phase), printing the wave and its spectrum's tails there; the final state is
written with the simulation's own :meth:`~chuteflow.dns.simulation.DnsState.save` (C and the
previous level), so that the measurement can be repeated on the same state.

``--state FILE``: from that state (or a run's checkpoint, with its ``--length`` and grid),
``--steps`` implicit steps of Δt = ``--dt`` (the
control's step of the nonlinear phase, 16) once per preconditioner variant (``coupled``
falls back to the columns where its fresh blocks do not serve; ``coupled_only`` never does),
each with a fresh :class:`~chuteflow.dns.Stepper` (the first step includes the build). Prints per
variant the GMRES iterations, residual evaluations and preconditioner applications per
step, the seconds per step (first and later) and the seconds of the build, with the end
state's distance to the first variant's (they solve the same equations to the Newton
tolerance), and before them how far the coefficients of the Jacobian are from their first
R x-harmonics (R = 1: the coupled preconditioner). The machine is shared: compare the
seconds only within one run.

``--newton-rtol R1,R2,…`` (with ``--state``): each variant once per value of
:attr:`~chuteflow.dns.NewtonSettings.newton_rtol` (Newton's tolerance relative to the
residual of the extrapolated guess; 0: ``atol`` alone), the first the reference of
``max_dC_vs_first`` (docs/dns.md, *Newton's tolerance relative to the step*).

``--span T`` (with ``--state``): instead of the fixed steps, continue the state for T time
units with the step control (``dt_tol`` = 1e-3, as the run that made it) once per variant
(``coupled`` and ``coupled_chebyshev`` there go over to the columns as a run does), and print
the wall time, steps, factorisations and the end state's distance to the first variant's —
the end-to-end comparison of docs/dns.md, *Finite differences in y*; ``columns_follow`` (span
only) lets the frame follow the wave (``DnsSimulation(follow_wave=True)``): its end state is
in another frame, so the distance to compare is that of the last ρ̄ record, which stays in
the first frame (``max_drho_rel_vs_first``; docs/dns.md, *A frame that follows the wave*).

Run: ``python benchmarks/probes/dns_krylov.py --make-state /tmp/p1_41x64.npz --nx 41 --ny 64``
then ``python benchmarks/probes/dns_krylov.py --state /tmp/p1_41x64.npz --nx 41 --ny 64
--dt 16,32,64 --variants mean,coupled`` (the table of docs/dns.md).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "src"))

import numpy as np

from chuteflow._threads import limit_blas_threads
from chuteflow.closures import ChuteModel
from chuteflow.dns import DnsSimulation, NewtonSettings, Stepper
from chuteflow.dns.setup import history_coefficients
from chuteflow.spectral import fourier_resample
from chuteflow.steady import solve_steady

VARIANTS = {
    "mean": dict(preconditioner="mean"),
    "columns": dict(preconditioner="columns"),
    # the coupled blocks from the first step (by default they replace the x-mean ones once a
    # GMRES solve needs more than coupled_krylov = 20 iterations)
    "coupled": dict(preconditioner="coupled", coupled_krylov=0),
    # the coupled blocks alone, never the columns (switch_krylov out of reach)
    "coupled_only": dict(preconditioner="coupled", coupled_krylov=0, switch_krylov=10**9),
    # the columns with the exact (Chebyshev) y-derivatives instead of finite differences
    "columns_chebyshev": dict(preconditioner="columns", column_y="chebyshev"),
    "coupled_chebyshev": dict(preconditioner="coupled", coupled_krylov=0, column_y="chebyshev"),
    # the columns with each row's own x-transport by central differences (before 2026-12-07)
    "columns_central": dict(preconditioner="columns", column_y="chebyshev", column_x="central"),
    # the Chebyshev columns in a frame that follows the wave (DnsSimulation(follow_wave=True);
    # --span only: the frame changes by the run's records)
    "columns_follow": dict(preconditioner="columns", column_y="chebyshev", follow_wave=True),
}


def harmonics(sim: DnsSimulation, C: np.ndarray, prev: tuple, dt: float) -> str:
    """How far the Jacobian's coefficients are from their first R x-harmonics: the relative
    L2 error of the truncation, over all coefficients weighted by their size, R = 0, 1, 2, 4, 8
    (R = 0 is the x-mean preconditioner's, R = 1 the coupled one's)."""
    from chuteflow.dns.columns import jet_coefficients
    from chuteflow.dns.discretisation import BDF2

    st = Stepper(sim.disc, NewtonSettings())
    coefs = jet_coefficients(sim.disc, C, (st.physical(C), prev), dt, BDF2)
    A = np.stack(list(coefs.values()))  # (jets, rows, N+1, nxp)
    nxp = A.shape[-1]
    H = np.fft.fft(A, axis=-1)
    out = []
    for R in (0, 1, 2, 4, 8):
        Ht = H.copy()
        Ht[..., R + 1 : nxp - R] = 0.0
        err = np.linalg.norm(np.fft.ifft(Ht, axis=-1).real - A) / np.linalg.norm(A)
        out.append(f"R = {R}: {err:.3f}")
    return "coefficients' truncation error " + ", ".join(out)


def simulation(
    nx: int,
    ny: int,
    t_end: float,
    preconditioner: str = "auto",
    *,
    theta=16.0,
    nu0=0.05,
    length=1000.0,
    **solver,
) -> DnsSimulation:
    """The run of ``--make-state`` (``solver``: further NewtonSettings, e.g. ``column_y``, and
    ``follow_wave``, the simulation's)."""
    flow = solve_steady(theta, nu0, ChuteModel(roughness=0.05))
    follow = bool(solver.pop("follow_wave", False))
    settings = NewtonSettings(**{"dt_tol": 1e-3, "preconditioner": preconditioner, **solver})
    return DnsSimulation(
        flow, length, time=t_end, dt=4.0, n=ny, modes=(nx - 1) // 2,
        init="noise", amplitude=1e-3, snapshots=2, settings=settings, follow_wave=follow,
    )  # fmt: skip


def wave(sim: DnsSimulation, C: np.ndarray) -> str:
    rho = sim.disc.depth_integrals(C)[0]
    tails = sim.resolution(C)
    return (
        f"ρ̄ {rho.min() / rho.mean() - 1:+.4f} … {rho.max() / rho.mean() - 1:+.4f}; "
        f"x_tail {tails['x_tail']:.1e}, y_tail {tails['y_tail']:.1e}"
    )


class Counted:
    """Counts the residual evaluations and preconditioner applications of a stepper."""

    def __init__(self, stepper: Stepper):
        self.residuals = self.applies = 0
        self.apply_s = self.residual_s = 0.0
        d = stepper.disc
        res = d.residual

        def residual(*a, **k):
            t0 = time.perf_counter()
            out = res(*a, **k)
            self.residual_s += time.perf_counter() - t0
            self.residuals += 1
            return out

        object.__setattr__(d, "residual", residual)
        self._restore = lambda: object.__delattr__(d, "residual")
        factor = stepper._factor

        def factor_(*a, **k):
            t0 = time.perf_counter()
            factor(*a, **k)
            self.build_s += time.perf_counter() - t0
            lus = stepper._lus
            app = lus.apply

            def apply(R):
                t1 = time.perf_counter()
                out = app(R)
                self.apply_s += time.perf_counter() - t1
                self.applies += 1
                return out

            object.__setattr__(lus, "apply", apply)

        self.build_s = 0.0
        stepper._factor = factor_  # type: ignore[method-assign]


def measure(sim, settings, C, prev, h_prev, dt, n):
    st = Stepper(sim.disc, settings)
    cnt = Counted(st)
    rows = []
    try:
        for _ in range(n):
            now = st.physical(C)
            guess = C + (dt / h_prev) * (C - history_coefficients(sim.disc, prev))
            t0 = time.perf_counter()
            C_new, info = st.step(C, (now, prev), dt, guess=guess, ratio=dt / h_prev)
            rows.append((time.perf_counter() - t0, info.newton, info.krylov))
            prev, C, h_prev = now, C_new, dt
    finally:
        cnt._restore()
    return np.array(rows), cnt, st.factorisations, C


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--theta", type=float, default=16.0, help="θ in degrees (P1: 16)")
    ap.add_argument("--nu0", type=float, default=0.05, help="ν0(0) (P1: 0.05)")
    ap.add_argument("--length", type=float, default=1000.0, help="period L (a --state's run's)")
    ap.add_argument("--nx", type=int, default=41)
    ap.add_argument("--ny", type=int, default=64)
    ap.add_argument("--make-state", default=None, help="run from noise to --time and save the state here")
    ap.add_argument("--time", type=float, default=27000.0)
    ap.add_argument("--preconditioner", default="auto", help="of the --make-state run")
    ap.add_argument("--state", default=None, help="measure from this saved state")
    ap.add_argument("--dt", default="16", help="comma-separated Δt of the measured steps")
    ap.add_argument("--steps", type=int, default=4)
    ap.add_argument("--variants", default=None, help="comma-separated names (default: all)")
    ap.add_argument("--span", type=float, default=0.0, help="continue the state this long per variant")
    ap.add_argument(
        "--newton-rtol", default=None, help="comma-separated NewtonSettings.newton_rtol, each per variant"
    )
    args = ap.parse_args(argv)
    limit_blas_threads(1)
    warnings.simplefilter("ignore", RuntimeWarning)
    where = dict(theta=args.theta, nu0=args.nu0, length=args.length)
    if args.make_state:
        sim = simulation(args.nx, args.ny, args.time, args.preconditioner, **where)
        t0 = time.perf_counter()
        state = sim.run()
        state.save(args.make_state, sim.key())
        print(
            f"state at t = {state.t:.0f} ({state.status}), {state.step} steps, "
            f"{time.perf_counter() - t0:.1f} s: {wave(sim, state.C)}",
            flush=True,
        )
        if not args.state:
            return
    sim = simulation(args.nx, args.ny, args.time, **where)
    with np.load(args.state) as ck:
        C, prev, h_prev, t = ck["C"], tuple(ck["prev"]), float(ck["scalars"][3]), float(ck["scalars"][0])
        key = str(ck["key"]) if "key" in ck.files else None
    if key is not None:
        from chuteflow.dns.simulation import DnsState

        saved = DnsState.load(args.state, key)
        if saved is not None:
            sim._follow(saved)  # a run's checkpoint: its grid, x map included
    with np.load(args.state) as ck:
        dt_run = float(ck["scalars"][2])
    if prev[0].shape[-1] != sim.disc.nxp:  # a state of an earlier padded grid
        prev = tuple(fourier_resample(np.array(prev), sim.disc.nxp))
    print(
        f"nx = {args.nx}, ny = {args.ny}, t = {t:.0f}, Δt {dt_run:g} (last {h_prev:g}): {wave(sim, C)}",
        flush=True,
    )
    names = args.variants.split(",") if args.variants else list(VARIANTS)
    if args.span > 0:
        span(args, where, names)
        return
    print(harmonics(sim, C, prev, float(args.dt.split(",")[0])), flush=True)
    rtols = [float(v) for v in args.newton_rtol.split(",")] if args.newton_rtol else [None]
    for dt in (float(v) for v in args.dt.split(",")):
        first = None
        for name, rtol in ((n, r) for n in names for r in rtols):
            extra = {} if rtol is None else {"newton_rtol": rtol}
            if VARIANTS[name].get("follow_wave"):
                raise SystemExit(f"{name}: a frame that follows the wave is measured with --span")
            settings = NewtonSettings(**{**VARIANTS[name], **extra})
            r, cnt, fact, C_end = measure(sim, settings, C, prev, h_prev, dt, args.steps)
            first = C_end if first is None else first
            n = len(r)
            row = {
                "variant": name,
                "newton_rtol": settings.newton_rtol,
                "dt": dt,
                "gmres_per_step": float(r[:, 2].mean()),
                "newton_per_step": float(r[:, 1].mean()),
                "residuals_per_step": cnt.residuals / n,
                "applies_per_step": cnt.applies / n,
                "s_first_step": round(float(r[0, 0]), 3),
                "s_per_later_step": round(float(r[1:, 0].mean()), 3) if n > 1 else None,
                "build_s": round(cnt.build_s, 3),
                "factorisations": fact,
                "ms_per_residual": round(1e3 * cnt.residual_s / max(cnt.residuals, 1), 2),
                "ms_per_apply": round(1e3 * cnt.apply_s / max(cnt.applies, 1), 2),
                "max_dC_vs_first": float(np.abs(C_end - first).max()),
            }
            print(json.dumps(row), flush=True)


def span(args, where: dict, names: list[str]) -> None:
    """``--span``: the saved state continued for ``args.span`` time units per variant."""
    from chuteflow.dns.simulation import DnsState

    first = first_rho = None
    for name in names:
        with np.load(args.state) as ck:
            key = str(ck["key"])  # the state's own run: read by the simulation's loader
        state = DnsState.load(args.state, key)
        if state is None:
            raise SystemExit(f"{args.state}: not a saved DNS state")
        step, frames = state.step, len(state.records["frame_t"])
        sim = simulation(args.nx, args.ny, state.t + args.span, **where, **dict(VARIANTS[name]))
        t0 = time.perf_counter()
        end = sim.run(state=state)
        wall = time.perf_counter() - t0
        if first is None:
            first, first_rho = end.C, np.asarray(end.records["rho"][-1])
        row = {
            "variant": name,
            "span": args.span,
            "wall_s": round(wall, 1),
            "s_per_unit_t": round(wall / args.span, 3),
            "steps": end.step - step,
            "factorisations": sim.stepper.factorisations,
            "dt_end": end.dt,
            "gmres_per_step": [int(k) for k in end.records["krylov"][-(end.step - step) :]],
            "wave": wave(sim, end.C),
            "max_dC_vs_first": float(np.abs(end.C - first).max()),
            # (the records are in the run's first frame, whichever frame the end state is in)
            "max_drho_rel_vs_first": float(
                np.abs(end.records["rho"][-1] - first_rho).max() / first_rho.mean()
            ),
            "reframes": len(end.records["frame_t"]) - frames,
            "frame_end": sim.disc.frame,
        }
        print(json.dumps(row, ensure_ascii=False), flush=True)


if __name__ == "__main__":
    main()

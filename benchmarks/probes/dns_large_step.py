"""Cost of large-amplitude steps with each preconditioner (docs/dns.md, *Solver*), no checkpoint needed.

At P1 (θ = 16°, ν0(0) = 0.05, φ = 0.05), L = 1000, frame 7.8: the least-stable eigenmode at
k = 2π/L with ``--amplitude`` (0.2: ρ̄ within about ±6 %, the nonlinear phase), ``--nx``,
``--ny``, Δt = 4. After ``--warm`` steps with the column preconditioner (the state leaves the
pure mode and its harmonics fill in), the same ``--steps`` steps from the same state and
history are taken once per variant: the x-mean preconditioner, the column preconditioner with
second- and fourth-order x-differences. Prints per variant the seconds per step (noisy on a
shared machine: compare the iterations), Newton and GMRES iterations per step, the
factorisations and how far the end states differ from the first variant's.

``--checkpoint FILE`` starts instead from the state of a run's checkpoint (C and the previous
level, e.g. of ``dns_saturation_run.py``: the natural wave, not a scaled one), with ``--warm``
ignored; ``--dt 4,16,64`` takes the steps at each of these Δt (issue 42: the cost per unit
time at large steps).

Run: ``python benchmarks/probes/dns_large_step.py --nx 33 --ny 60 --steps 6``.
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
from chuteflow.steady import solve_steady

VARIANTS = {
    "mean": NewtonSettings(preconditioner="mean"),
    "columns-2": NewtonSettings(preconditioner="columns", column_order=2),
    "columns-4": NewtonSettings(preconditioner="columns", column_order=4),
    "mean-restart40": NewtonSettings(preconditioner="mean", gmres_restart=40, gmres_maxiter=4),
}


def steps(sim, settings, C, prev, h_prev, dt, n):
    st = Stepper(sim.disc, settings)
    rows = []
    for _ in range(n):
        now = st.physical(C)
        guess = C + (dt / h_prev) * (C - history_coefficients(sim.disc, prev))
        t0 = time.perf_counter()
        C_new, info = st.step(C, (now, prev), dt, guess=guess, ratio=dt / h_prev)
        rows.append((time.perf_counter() - t0, info.newton, info.krylov))
        prev, C, h_prev = now, C_new, dt
    return np.array(rows), st.factorisations, C


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--nx", type=int, default=33)
    ap.add_argument("--ny", type=int, default=60)
    ap.add_argument("--amplitude", type=float, default=0.2)
    ap.add_argument("--warm", type=int, default=5)
    ap.add_argument("--steps", type=int, default=6)
    ap.add_argument("--variants", default=",".join(VARIANTS))
    ap.add_argument("--dt", default="4", help="comma-separated step sizes of the measured steps")
    ap.add_argument("--checkpoint", default=None, help="start from this run's checkpoint (.npz)")
    ap.add_argument(
        "--scale",
        type=float,
        default=1.0,
        help="Multiply the wave (modes ≥ 1 of both time levels) by this after the warm-up, then "
        "take --warm more steps: larger amplitudes than a mode of amplitude < 0.5 reaches.",
    )
    args = ap.parse_args(argv)
    limit_blas_threads(1)
    warnings.simplefilter("ignore", RuntimeWarning)
    flow = solve_steady(16.0, 0.05, ChuteModel(roughness=0.05))
    if args.checkpoint:
        with np.load(args.checkpoint) as ck:
            C, prev, h_prev = ck["C"], ck["prev"], float(ck["scalars"][3])
        args.warm = 0
    sim = DnsSimulation(
        flow,
        1000.0,
        time=4.0 * max(args.warm, 1),
        dt=4.0,
        n=args.ny,
        modes=(args.nx - 1) // 2,
        amplitude=1e-3 if args.checkpoint else args.amplitude,
        init="noise" if args.checkpoint else "mode",
        frame_speed=None if args.checkpoint else 7.8,  # a noise run's frame: the mode's phase speed
        snapshots=2,
        settings=NewtonSettings(preconditioner="columns"),
    )
    if args.checkpoint:
        t_label = "checkpoint"
    else:
        state = sim.run()
        C, prev, h_prev = state.C, state.prev, 4.0
        t_label = f"{state.t:g} ({state.status})"
    if args.scale != 1.0:
        C = C.copy()
        C[:, :, 1:] *= args.scale
        P = history_coefficients(sim.disc, tuple(prev))
        P[:, :, 1:] *= args.scale
        st = Stepper(sim.disc, NewtonSettings(preconditioner="columns"))
        prev = np.array(st.physical(P))
        for _ in range(args.warm):  # the scaled state relaxes onto the equations' solutions
            now = st.physical(C)
            C_new, _ = st.step(C, (now, tuple(prev)), 4.0)
            C, prev = C_new, np.array(now)
    rho = sim.disc.depth_integrals(C)[0]
    tails = sim.resolution(C)
    print(
        f"nx = {args.nx}, ny = {args.ny}, t = {t_label}: "
        f"ρ̄ {rho.min() / rho.mean() - 1:+.3f} … "
        f"{rho.max() / rho.mean() - 1:+.3f}; x_tail {tails['x_tail']:.1e}, y_tail {tails['y_tail']:.1e}"
    )
    for dt in (float(v) for v in args.dt.split(",")):
        first = None
        for name in args.variants.split(","):
            r, fact, C_end = steps(sim, VARIANTS[name], C, tuple(prev), h_prev, dt, args.steps)
            first = C_end if first is None else first
            row = {
                "variant": name,
                "dt": dt,
                "s_per_step": round(float(r[:, 0].mean()), 3),
                "s_per_time_unit": round(float(r[:, 0].mean()) / dt, 4),
                "first_step_s": round(float(r[0, 0]), 3),
                "newton_per_step": float(r[:, 1].mean()),
                "gmres_per_step": float(r[:, 2].mean()),
                "factorisations": fact,
                "max_dC_vs_first": float(np.abs(C_end - first).max()),
            }
            print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main()

"""Cost of a step at a large-amplitude state with each preconditioner (docs/dns.md, *Solver*).

Continues a checkpoint (:class:`chuteflow.dns.DnsState`) of ``chuteflow dns`` at P1 (θ = 16°,
ν0(0) = 0.05, φ = 0.05, transport top row) for a few steps, exactly as the run would (the BDF2
history and Newton's extrapolated guess from the checkpoint), once per preconditioner, and
prints seconds, Newton and GMRES iterations per step, the peak memory, and how far the fields
of the two runs differ at the end. The run's parameters are given as options (the checkpoint
is only accepted under its run's key); defaults: L = 1000 from the eigenmode at amplitude
0.02, frame 7.802854, nx = 65, N = 80, Δt = 4 — the run of docs/dns.md. Run:
``python benchmarks/probes/dns_preconditioner.py CHECKPOINT.npz --steps 5``. For a
large-amplitude state without a checkpoint, see ``dns_large_step.py``.
"""

from __future__ import annotations

import argparse
import json
import math
import resource
import sys
import time
from pathlib import Path

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "src"))

import numpy as np

from chuteflow.closures import ChuteModel
from chuteflow.dns import DnsSimulation, DnsState, NewtonSettings, Stepper
from chuteflow.dns.setup import history_coefficients
from chuteflow.steady import solve_steady


def run(ck, disc, name, steps):
    st = Stepper(disc, NewtonSettings(preconditioner=name))
    C, prev, h_prev, dt = ck.C, tuple(ck.prev), ck.h_prev, ck.dt
    rows = []
    for _ in range(steps):
        now = st.physical(C)
        guess = C + (dt / h_prev) * (C - history_coefficients(disc, prev))
        t0 = time.perf_counter()
        C_new, info = st.step(C, (now, prev), dt, guess=guess, ratio=dt / h_prev)
        rows.append((time.perf_counter() - t0, info.newton, info.krylov))
        prev, C, h_prev = now, C_new, dt
    r = np.array(rows)
    out = {
        "preconditioner": name,
        "first_step_s": r[0, 0],
        "later_s_per_step": float(r[1:, 0].mean()) if steps > 1 else math.nan,
        "newton_per_step": float(r[:, 1].mean()),
        "gmres_per_step": float(r[:, 2].mean()),
        "factorisations": st.factorisations,
        "maxrss_MB": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
    }
    return out, C


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("checkpoint")
    ap.add_argument("--steps", type=int, default=5)
    ap.add_argument("--length", type=float, default=1000.0)
    ap.add_argument("--init", default="mode")
    ap.add_argument("--amplitude", type=float, default=0.02)
    ap.add_argument("--frame-speed", type=float, default=7.802854)
    ap.add_argument("--nx", type=int, default=65)
    ap.add_argument("--ny", type=int, default=80)
    ap.add_argument("--dt", type=float, default=4.0)
    ap.add_argument("--snapshots", type=int, default=6)
    ap.add_argument("--record-every", type=int, default=1)
    args = ap.parse_args(argv)
    flow = solve_steady(16.0, 0.05, ChuteModel(roughness=0.05))
    sim = DnsSimulation(
        flow,
        args.length,
        dt=args.dt,
        n=args.ny,
        modes=(args.nx - 1) // 2,
        init=args.init,
        amplitude=args.amplitude,
        frame_speed=args.frame_speed,
        snapshots=args.snapshots,
        record_every=args.record_every,
    )
    ck = DnsState.load(args.checkpoint, sim.key())
    if ck is None:
        raise SystemExit("the checkpoint is not this run's: give the run's parameters (see --help)")
    disc = sim.disc
    rho = disc.depth_integrals(ck.C)[0]
    lo, hi = rho.min() / rho.mean() - 1, rho.max() / rho.mean() - 1
    print(f"L = {args.length:g}, t = {ck.t:g}, ρ̄ {lo:+.3f} … {hi:+.3f}")
    ends = {}
    for name in ("mean", "columns"):
        out, ends[name] = run(ck, disc, name, args.steps)
        print(json.dumps(out), flush=True)
    print(f"max |ΔC| after {args.steps} steps: {np.abs(ends['mean'] - ends['columns']).max():.2e}")


if __name__ == "__main__":
    main()

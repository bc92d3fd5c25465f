"""Cost of a step at a large-amplitude state with each preconditioner (docs/dns.md, *Solver*).

Continues a checkpoint of ``chuteflow dns`` at P1 (θ = 16°, ν0(0) = 0.05, φ = 0.05, N = 80,
Δt = 4, transport top row) for a few steps, exactly as the run would (the BDF2 history and
Newton's extrapolated guess from the checkpoint), once per preconditioner, and prints seconds,
Newton and GMRES iterations per step, the peak memory, and how far the fields of the two runs
differ at the end. The checkpoint's run is recognised by its key: L = 1000 from the eigenmode
(amplitude 0.02, frame 7.802854, nx = 65) or L = 2000 from noise (amplitude 1e-3, seed 0,
frame the eigenmode's phase velocity, nx = 97) — the runs of docs/dns.md. Run:
``python benchmarks/probes/dns_preconditioner.py CHECKPOINT.npz --steps 5``.
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
from chuteflow.dns import Discretisation, NewtonSettings, Stepper
from chuteflow.dns.api import DnsSetup, _coefficients
from chuteflow.stability import OperatorCache, least_stable
from chuteflow.steady import solve_steady


def setup_of(ck, model, flow) -> tuple[DnsSetup, float]:
    C = ck["C"]
    M, N = C.shape[2] - 1, C.shape[1] - 1
    candidates = []
    for L, init, amp in ((1000.0, "mode", 0.02), (2000.0, "noise", 1e-3)):
        mode = least_stable(flow, 2 * math.pi / L, n=N, cache=OperatorCache(mapped=False))
        candidates.extend(
            DnsSetup(16.0, 0.05, L, 1.0, N, M, 4.0, init, amp, 0, model, True, frame)
            for frame in (7.802854, float(mode.wave_speed))
        )
    for s in candidates:
        if s.key() == str(ck["key"]):
            return s, s.length
    raise SystemExit("checkpoint of an unknown run")


def run(ck, disc, name, steps):
    st = Stepper(disc, NewtonSettings(preconditioner=name))
    C, prev, h_prev, dt = ck["C"], tuple(ck["prev"]), float(ck["h_prev"]), float(ck["dt"])
    rows = []
    for _ in range(steps):
        now = st.physical(C)
        guess = C + (dt / h_prev) * (C - _coefficients(disc, prev))
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
    args = ap.parse_args(argv)
    model = ChuteModel(roughness=0.05)
    flow = solve_steady(16.0, 0.05, model)
    with np.load(args.checkpoint) as ck:
        ck = dict(ck)
    setup, L = setup_of(ck, model, flow)
    disc = Discretisation(16.0, model, L, flow.y_max, setup.n, setup.modes, frame=setup.frame)
    rho = disc.depth_integrals(ck["C"])[0]
    lo, hi = rho.min() / rho.mean() - 1, rho.max() / rho.mean() - 1
    print(f"L = {L:g}, t = {float(ck['t']):g}, ρ̄ {lo:+.3f} … {hi:+.3f}")
    ends = {}
    for name in ("mean", "columns"):
        out, ends[name] = run(ck, disc, name, args.steps)
        print(json.dumps(out), flush=True)
    print(f"max |ΔC| after {args.steps} steps: {np.abs(ends['mean'] - ends['columns']).max():.2e}")


if __name__ == "__main__":
    main()

"""Refinement study of the DNS linear phase at P1 and P3 (issue 11, item 2; docs/dns.md).

Runs ``chuteflow.dns.simulate`` from the least-stable eigenmode (amplitude 1e-6) over two
wave periods at L = 2π/0.003 and prints, for a ladder of Δt, N (ny) and M (nx = 2M + 1):
the measured growth rate and phase velocity, their relative errors against
``chuteflow.stability.least_stable`` (at the same N), the BDF2-inverted discrete eigenvalue,
the mass drift, and the time per step. ``--steady`` adds the unperturbed run (amplitude 0):
how far the uniform steady flow moves. Run: ``python benchmarks/probes/dns_convergence.py``.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "src"))

from chuteflow.closures import ChuteModel
from chuteflow.dns import simulate, summary
from chuteflow.stability import least_stable
from chuteflow.steady import solve_steady

L = 2 * math.pi / 0.003


def row(label, s):
    print(
        f"{label:<22} growth {s['growth_rate']:.7e} ({s['growth_rate_error']:.2e})  "
        f"c {s['phase_velocity']:.6f} ({s['phase_velocity_error']:.2e})  "
        f"α_dns {s['alpha_dns_re']:.7e}{s['alpha_dns_im']:+.7e}i  "
        f"mass {s['mass_drift']:.1e}  mean-flow {s['mean_flow_change']:.1e}  "
        f"{1e3 * s['time_per_step']:.1f} ms/step",
        flush=True,
    )


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--steady", action="store_true")
    ap.add_argument("--points", default="P1,P3")
    a = ap.parse_args()
    pts = {"P1": (16.0, 0.05), "P3": (16.0, 0.10)}
    for name in a.points.split(","):
        th, nu0 = pts[name]
        flow = solve_steady(th, nu0, ChuteModel(roughness=0.05))
        m = least_stable(flow, 2 * math.pi / L)
        period = 2 * math.pi / abs(m.alpha.imag)
        print(f"{name}: α = {m.alpha:.8e} (N = {m.n}), period {period:.2f}")
        kw = dict(time=2 * period)
        for div in (25, 50, 100, 200):
            row(f"{name} dt=T/{div}", summary(simulate(flow, L, n=m.n, dt=period / div, **kw)))
        for n in (m.n - 20, m.n + 20):
            mn = least_stable(flow, 2 * math.pi / L, n=n)
            s = summary(simulate(flow, L, n=n, dt=period / 100, **kw))
            row(f"{name} ny={n}", s)
            print(f"{'':<22} eigenvalue at N={n}: {mn.alpha:.8e}")
        for M in (1, 4):
            row(f"{name} nx={2 * M + 1}", summary(simulate(flow, L, n=m.n, modes=M, dt=period / 100, **kw)))
        if a.steady:
            s = summary(simulate(flow, L, n=m.n, dt=period / 100, amplitude=0.0, **kw))
            print(
                f"{name} steady (amplitude 0): mean-flow change {s['mean_flow_change']:.2e}, "
                f"mass {s['mass_drift']:.1e}"
            )


if __name__ == "__main__":
    main()

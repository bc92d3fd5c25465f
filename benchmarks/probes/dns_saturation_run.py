"""One density wave from noise to saturation with the time-step control (issue 42 item 2).

By default P1 (θ = 16°, ν0(0) = 0.05, φ = 0.05), L = 1000 (``--theta``, ``--nu0``,
``--length``), from noise of amplitude 1e-3 (``--amplitude``) in the frame of
the eigenmode's phase velocity, ``--nx`` × ``--ny``, Δt = ``--dt`` as the shortest step and
``NewtonSettings(dt_tol=--dt-tol)`` (0: the fixed Δt of the earlier runs), stopped by
``SaturationStop(--saturation-tol)`` (0.02; 0: at ``--time``). Resumable: the state is
checkpointed to ``--checkpoint`` every 20 s, so the run can be made of pieces
(``timeout 540 python … ; python …`` continues). Prints every
``--every`` seconds the time, step, Δt, wave amplitude, Newton and GMRES iterations per step,
and at the end the wave (ρ̄ min/max over its mean), the wall time of this piece and the total
wall time, and the mass drift.

Run: ``python benchmarks/probes/dns_saturation_run.py --nx 65 --ny 80 --dt-tol 1e-3``.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "src"))

import numpy as np

from chuteflow._threads import limit_blas_threads
from chuteflow.closures import ChuteModel
from chuteflow.dns import DnsSimulation, NewtonSettings
from chuteflow.steady import solve_steady
from chuteflow.trackers import SaturationStop, Tracker


class Progress(Tracker):
    """Prints the run's progress every ``every`` seconds."""

    def __init__(self, every: float, infos: list):
        self.every, self.infos = every, infos

    def initialize(self, sim, initial, t_end):
        self.t0, self.last = time.perf_counter(), 0.0

    def handle(self, sim, step):
        w = time.perf_counter() - self.t0
        if w - self.last >= self.every:
            self.last = w
            last = self.infos[-20:]
            print(
                f"wall {w:7.1f} s  t {step.t:8.1f}  step {step.number:5d}  Δt {step.t - step.t_prev:6.1f}  "
                f"amplitude {sim.wave_amplitude(step.y):.4f}  "
                f"Newton {np.mean([i.newton for i in last]):.1f}  "
                f"GMRES {np.mean([i.krylov for i in last]):.1f}  columns {sim.stepper.columns}",
                flush=True,
            )


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--theta", type=float, default=16.0, help="θ in degrees (P1: 16)")
    ap.add_argument("--nu0", type=float, default=0.05, help="ν0(0) (P1: 0.05)")
    ap.add_argument("--length", type=float, default=1000.0, help="period L in diameters")
    ap.add_argument("--amplitude", type=float, default=1e-3, help="noise amplitude")
    ap.add_argument("--nx", type=int, default=65)
    ap.add_argument("--ny", type=int, default=80)
    ap.add_argument("--dt", type=float, default=4.0)
    ap.add_argument("--dt-tol", type=float, default=1e-3)
    ap.add_argument("--dt-max", type=float, default=0.0)
    ap.add_argument("--time", type=float, default=40000.0)
    ap.add_argument("--preconditioner", default="auto")
    ap.add_argument("--checkpoint", default="dns_saturation_run.ck.npz")
    ap.add_argument("--every", type=float, default=15.0)
    ap.add_argument(
        "--saturation-tol", type=float, default=0.02, help="SaturationStop's tolerance; 0: run to --time"
    )
    args = ap.parse_args(argv)
    limit_blas_threads(1)
    warnings.simplefilter("ignore", RuntimeWarning)
    flow = solve_steady(args.theta, args.nu0, ChuteModel(roughness=0.05))
    settings = NewtonSettings(dt_tol=args.dt_tol, dt_max=args.dt_max, preconditioner=args.preconditioner)
    sim = DnsSimulation(
        flow, args.length, time=args.time, dt=args.dt, n=args.ny, modes=(args.nx - 1) // 2,
        init="noise", amplitude=args.amplitude, snapshots=2, settings=settings,
    )  # fmt: skip
    infos: list = []
    step = sim.stepper.step

    def counted(*a, **k):
        out = step(*a, **k)
        infos.append(out[1])
        return out

    sim.stepper.step = counted  # type: ignore[method-assign]
    t0 = time.perf_counter()
    state = sim.run(
        [Progress(args.every, infos)]
        + ([SaturationStop(args.saturation_tol, interval=150.0)] if args.saturation_tol > 0 else []),
        checkpoint=args.checkpoint,
        checkpoint_every=20.0,
    )
    rho = np.asarray(state.records["rho"])
    mass = rho.mean(axis=-1)
    end = rho[-1]
    lo, hi = end.min() / end.mean() - 1, end.max() / end.mean() - 1
    print(
        f"end: {state.status} at t = {state.t:.0f}, {state.step} steps; ρ̄ {lo:+.4f} … {hi:+.4f}"
        f"; this piece {time.perf_counter() - t0:.1f} s, total wall "
        f"{state.wall:.1f} s; mass drift {np.max(np.abs(mass - mass[0])) / mass[0]:.1e}; "
        f"Newton {np.mean(state.records['newton']):.2f}, "
        f"GMRES {np.mean(state.records['krylov']):.1f} per step"
    )
    xt, yt = np.asarray(state.records["x_tail"]), np.asarray(state.records["y_tail"])
    print(
        f"resolution: x tail max {xt.max():.1e} (end {xt[-1]:.1e}), "
        f"y tail max {yt.max():.1e} (end {yt[-1]:.1e})"
    )


if __name__ == "__main__":
    main()

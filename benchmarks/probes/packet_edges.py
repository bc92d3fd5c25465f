"""The edges of the growing packet, measured on the simulation (issue 43, item 5; docs/spatial.md).

The linear phase of the DNS (:func:`chuteflow.dns.packet.simulate_pulse`) from a Gaussian bump
δ ln ν = 1e-6 exp(−(x − L/2)²/(2·150²)) at P1 (θ = 16°, ν0(0) = 0.05, φ = 0.05), in a periodic
domain L = 60000 that holds the packet (it spans (V+ − V−) t ≈ 29000 at t = 6000), in the frame
moving at (V− + V+)/2 so that it stays centred. The growth along rays σ(V) is measured between
t/2 and t (:func:`chuteflow.dns.packet.ray_growth`, with the ½ ln 2/(t/2) of the saddle's
t^{-1/2}) at t = 3000 and t = 6000; its zeros are the edges V−, V+. They are compared with
:func:`chuteflow.spatial.absolute_instability` (the Briggs–Bers saddles, N = 80) and σ(V)
with its rays. The measured error falls like 1/(t1 t2) (the next term of the saddle-point
expansion): the extrapolation (4 σ(t = 6000) − σ(t = 3000))/3 is printed too.

Resolution: N = 48 (Re α of the temporal branch within 4e-7 of N = 80 at k ≤ 0.005; N = 32
moved V+ by −0.025), Δt = 20 (Δt = 10 moves V+ by 0.002), modes M = 256 (k_max = 0.027, where
the bump's spectrum is e^{-8} and Re α = −0.006). About 1.5 min on one core.

Run: ``python benchmarks/probes/packet_edges.py [--quick]`` (``--quick``: the slow test's
cheap version, L = 30000, M = 128, t = 3000 only).
"""

from __future__ import annotations

import argparse
import sys
import time as _time
import warnings
from pathlib import Path

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "src"))

import numpy as np

from chuteflow.closures import ChuteModel
from chuteflow.dns.packet import ray_growth, simulate_pulse
from chuteflow.spatial import absolute_instability
from chuteflow.steady import solve_steady


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="the slow test's cheap run")
    a = ap.parse_args(argv)
    warnings.simplefilter("ignore")
    flow = solve_steady(16.0, 0.05, ChuteModel(roughness=0.05))
    t0 = _time.perf_counter()
    theory = absolute_instability(flow)
    print(
        f"saddle points (N = {theory.n}): V- = {theory.v_minus:.6f}, V+ = {theory.v_plus:.6f}, "
        f"peak growth {theory.growth_peak:.6e} at V = {theory.v_peak:.4f}, {theory.verdict} "
        f"({_time.perf_counter() - t0:.1f} s)",
        flush=True,
    )
    if a.quick:
        L, N, M, T, times = 30000.0, 48, 128, 3000.0, (3000.0,)
    else:
        L, N, M, T, times = 60000.0, 48, 256, 6000.0, (3000.0, 6000.0)
    frame = 0.5 * (theory.v_minus + theory.v_plus)
    t0 = _time.perf_counter()
    ds = simulate_pulse(
        flow, L, time=T, width=150.0, frame_speed=frame, n=N, modes=M, dt=20.0, record_every=5
    )
    rho = ds["rho_bar"].values
    print(
        f"DNS L = {L:g}, N = {N}, M = {M}, dt = 20, t = {T:g}: {_time.perf_counter() - t0:.0f} s, "
        f"{ds.attrs['steps']} steps, x tail {ds.attrs['x_tail']:.1e}, y tail {ds.attrs['y_tail']:.1e}, "
        f"largest |δρ̄|/ρ̄ {np.max(np.abs(rho[-1] - rho[-1].mean())) / rho[-1].mean():.1e}",
        flush=True,
    )
    x, t = ds["x"].values, ds["time"].values
    V_fine = np.linspace(3.0, 10.5, 301)
    Vr, sr = theory.rays[0], theory.rays[1]
    meas, at_rays = {}, {}
    for t2 in times:
        kw = {"t1": t2 / 2, "t2": t2, "x0": ds.attrs["pulse_centre"], "frame": frame, "length": L}
        meas[t2] = ray_growth(x, t, rho, V_fine, **kw)
        at_rays[t2] = ray_growth(x, t, rho, Vr, **kw).growth
        m = meas[t2]
        print(
            f"t = {t2 / 2:g} -> {t2:g}: V- = {m.v_minus:.4f} ({m.v_minus - theory.v_minus:+.4f}), "
            f"V+ = {m.v_plus:.4f} ({m.v_plus - theory.v_plus:+.4f}), peak growth {m.growth_peak:.5e} "
            f"({m.growth_peak / theory.growth_peak - 1:+.2%}) at V = {m.v_peak:.3f}"
        )
    if len(times) == 2:
        a1, a2 = meas[times[0]], meas[times[1]]
        g = (4 * a2.growth - a1.growth) / 3
        i = int(np.argmax(g))
        from chuteflow.dns.packet import growth_edges

        vm, vp, _ = growth_edges(V_fine, g)
        print(
            f"extrapolated (4 σ(6000) − σ(3000))/3: V- = {vm:.4f} ({vm - theory.v_minus:+.4f}), "
            f"V+ = {vp:.4f} ({vp - theory.v_plus:+.4f}), peak growth {g[i]:.5e} "
            f"({g[i] / theory.growth_peak - 1:+.2%})"
        )
    print("\nσ(V) along the saddle family's rays (theory) and measured:")
    head = "      V   σ saddle  " + "".join(f" t={t2:>6g}  " for t2 in times)
    print(head)
    for j, (v, s) in enumerate(zip(Vr, sr, strict=True)):
        print(f"{v:7.3f} {s:+.3e} " + "".join(f" {at_rays[t2][j]:+.3e}" for t2 in times))


if __name__ == "__main__":
    main()

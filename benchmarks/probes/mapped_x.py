"""How many x modes would a grid that follows the front need? The spectrum of a run's state in
a mapped x coordinate.

A checkpoint's state (the Fourier coefficients C[f, j, m] of ln ν, u, v, T on the Chebyshev
nodes, :class:`~chuteflow.dns.simulation.DnsState`) is evaluated, exactly for its modes, at the
points x = g(s) of a uniform grid in s and transformed in s. The map is the periodic tan map
(Boyd, *Chebyshev and Fourier Spectral Methods*, 2nd ed., §17.6):

    g(s) = x0 + (L/π) arctan(β tan(π (s − x0) / L)),     g'(x0) = β,  g'(x0 ± L/2) = 1/β,

which puts 1/β times the uniform density of points at the front x0 (where max_y |∂_x ln ν|
is largest) and β times it half a period away; β = 1 is the uniform grid the runs use. For
each β and each number of modes M' the probe prints the run's resolution measure of the truncated
series (:func:`~chuteflow.dns.diagnostics.fourier_tail`, the x part of
:func:`~chuteflow.dns.diagnostics.resolution_tails`: the largest coefficient of the top
eighth of the modes ≤ M' over the largest, over fields and nodes);
the smallest M' with the tail ≤ ``--tol`` (1e-4, issue 42's criterion) is what a run on that
map would need. docs/dns.md, *A grid that follows the front*.

``--step K`` (with the run's ``--theta``, ``--nu0``, ``--ny``): K implicit steps of Δt =
``--dt`` from the state (BDF2 with the checkpoint's previous level), on the run's uniform grid
(the reference) and on mapped grids of ``--mapped-nx`` points with each β ≠ 1 of ``--betas``
and each of ``--preconditioners``: GMRES and seconds per step, the x tail at the end and
every tenth step (:func:`~chuteflow.dns.diagnostics.fourier_tail`) and the largest difference
of ln ν, u, v, T from the reference at the mapped points (``--reference none``: the mapped
grids only, e.g. to continue one beyond where the run's grid holds the front).

Run: ``python benchmarks/probes/mapped_x.py --state p5.checkpoint.npz --length 2000`` (the
spectra) and ``… --theta 17 --nu0 0.1 --ny 96 --step 6 --dt 8 --mapped-nx 97,129 --betas 0.5,0.3``.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "src"))

import numpy as np

#: Preconditioner variants beyond the kinds of NewtonSettings: (kind, further settings).
VARIANTS = {
    "columns4": ("columns", {"column_order": 4}),
    "columns_chebyshev": ("columns", {"column_y": "chebyshev"}),
}


def rho_range(d, C: np.ndarray) -> tuple[float, float]:
    """min and max of ρ̄ over its x-average, minus 1 (on the padded grid's points)."""
    rho = d.depth_integrals(C)[0]
    mean = float(d.x_mean(rho))
    return rho.min() / mean - 1.0, rho.max() / mean - 1.0


def steps(a, C: np.ndarray, prev: np.ndarray, h_prev: float, x0: float) -> list[dict]:
    """``--step``: the reference on the run's grid and each mapped grid, K steps each."""
    import dataclasses
    import time

    from chuteflow.closures import ChuteModel
    from chuteflow.dns import DnsSimulation, NewtonSettings, Stepper
    from chuteflow.dns.diagnostics import fourier_tail
    from chuteflow.dns.remap import remap_coefficients
    from chuteflow.dns.setup import history_coefficients
    from chuteflow.dns.xmap import TanMap
    from chuteflow.spectral import fourier_evaluate
    from chuteflow.steady import solve_steady

    L = a.length
    flow = solve_steady(a.theta, a.nu0, ChuteModel(roughness=0.05))
    M = C.shape[-1] - 1
    sim = DnsSimulation(flow, L, time=1e3 * a.dt, dt=a.dt, n=a.ny, modes=M, init="noise", amplitude=1e-3)
    du = sim.disc
    C_prev = history_coefficients(du, tuple(prev))
    refs = [] if a.reference == "none" else a.reference.split(",")
    grids = [("uniform", du, pc, C, C_prev) for pc in refs]
    for nx in (int(v) for v in a.mapped_nx.split(",")):
        for beta in (float(b) for b in a.betas.split(",") if float(b) < 1):
            dm = dataclasses.replace(du, modes=(nx - 1) // 2, nxp=0, x_map=TanMap(x0, beta, L))
            # (the run's own rule: DnsSimulation.refine with x_map)
            Cm, Pm = (remap_coefficients(X, du, dm) for X in (C, C_prev))
            grids.extend((f"nx {nx}, β {beta:g}", dm, pc, Cm, Pm) for pc in a.preconditioners.split(","))
    rows, ref = [], None
    for name, d, pc, C0, P0 in grids:
        kind, extra = VARIANTS.get(pc, (pc, {}))
        st = Stepper(d, NewtonSettings(preconditioner=kind, coupled_krylov=0, **extra))
        X, prev_phys, h = C0.copy(), st.physical(P0), h_prev
        per, tails = [], []
        for i in range(a.step):
            now = st.physical(X)
            guess = X + (a.dt / h) * (X - history_coefficients(d, prev_phys))
            t0 = time.perf_counter()
            X_new, info = st.step(X, (now, prev_phys), a.dt, guess=guess, ratio=a.dt / h)
            per.append((time.perf_counter() - t0, info.krylov, info.newton))
            prev_phys, X, h = now, X_new, a.dt
            if (i + 1) % 10 == 0:
                tails.append(fourier_tail(X))
        if ref is None and refs:
            ref = X
        dmax = (
            np.abs(fourier_evaluate(ref, d.x, L) - d.to_physical(X)).max(axis=(1, 2))
            if ref is not None
            else np.full(4, math.nan)
        )
        r = np.array(per)
        rows.append(
            {
                "grid": name,
                "preconditioner": pc,
                "gmres_per_step": float(r[:, 1].mean()),
                "newton_per_step": float(r[:, 2].mean()),
                "s_per_step": round(float(r[:, 0].mean()), 2),
                "s_first_step": round(float(r[0, 0]), 2),
                "s_per_later_step": round(float(r[1:, 0].mean()), 2) if len(r) > 1 else None,
                "builds": st.factorisations,
                "x_tail": fourier_tail(X),
                "x_tail_every_10_steps": tails,
                "rho_rel": [float(v) for v in rho_range(d, X)],
                "max_diff_s_u_v_T": [float(v) for v in dmax],
            }
        )
        print(json.dumps(rows[-1]), flush=True)
    return rows


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--state", required=True, help="a run's checkpoint (.npz) or a probe's state")
    p.add_argument("--length", type=float, required=True, help="the run's period L")
    p.add_argument("--betas", default="1,0.5,0.35,0.25,0.15", help="map strengths β (1: uniform)")
    p.add_argument("--modes", default="32,48,64,96,128,192,256", help="truncations M'")
    p.add_argument("--tol", type=float, default=1e-4, help="the resolution criterion")
    p.add_argument("--json", action="store_true")
    p.add_argument("--step", type=int, default=0, help="K steps on the run's grid and mapped ones")
    p.add_argument("--theta", type=float, default=17.0, help="the run's θ (P5: 17)")
    p.add_argument("--nu0", type=float, default=0.1, help="the run's ν0(0) (P5: 0.1)")
    p.add_argument("--ny", type=int, default=96, help="the run's Chebyshev intervals")
    p.add_argument("--dt", type=float, default=8.0, help="Δt of the steps")
    p.add_argument("--mapped-nx", default="97,129", help="x points of the mapped grids")
    p.add_argument(
        "--preconditioners",
        default="coupled,columns",
        help="of the mapped grids: NewtonSettings.preconditioner kinds or VARIANTS",
    )
    p.add_argument(
        "--reference", default="coupled", help="preconditioner(s) of the run's grid; none: no reference"
    )
    a = p.parse_args(argv)
    from chuteflow.dns.diagnostics import fourier_tail
    from chuteflow.dns.xmap import TanMap
    from chuteflow.spectral import fourier_evaluate

    with np.load(a.state, allow_pickle=False) as ck:
        C = np.asarray(ck["C"])
        t = float(ck["scalars"][0]) if "scalars" in ck.files else math.nan
        prev = np.asarray(ck["prev"]) if "prev" in ck.files else np.zeros(0)
        h_prev = float(ck["scalars"][3]) if "scalars" in ck.files else a.dt
    L = a.length
    M = C.shape[-1] - 1
    # beyond the state's own M the uniform series is zero: truncations up to M only
    modes = sorted(int(m) for m in a.modes.split(",") if int(m) <= M) or [M]
    nfine = 2 * max(8 * M, 2 * max(modes) + 2)
    # the front: where |∂_x ln ν| is largest over the nodes
    xu = np.arange(nfine) * L / nfine
    k = 2.0 * math.pi * np.arange(M + 1) / L
    sx = fourier_evaluate(C[0] * 1j * k, xu, L)  # (nodes, nfine)
    x0 = float(xu[np.argmax(np.abs(sx).max(axis=0))])
    rows = []
    s = np.arange(nfine) * L / nfine
    for beta in (float(b) for b in a.betas.split(",")):
        x = TanMap(x0, beta, L).x(s)
        f = fourier_evaluate(C, x, L)  # (4, nodes, nfine): the state at the mapped points
        coeffs = np.fft.rfft(f, axis=-1) / nfine
        tl = {m: fourier_tail(coeffs[..., : m + 1]) for m in modes}
        need = next((m for m in modes if tl[m] <= a.tol), None)
        spacing = (L / (2 * M + 1)) * beta if M else math.nan
        rows.append({"beta": beta, "tails": tl, "modes_needed": need, "front_spacing_at_M": spacing})
    if a.step:
        if not prev.size:
            raise SystemExit(f"{a.state}: no previous level to step from (a run's checkpoint has one)")
        steps(a, C, prev, h_prev, x0)
        return 0
    if a.json:
        print(json.dumps({"state": a.state, "t": t, "modes": M, "x0": x0, "rows": rows}))
        return 0
    print(f"state {a.state}: t = {t:g}, M = {M} modes, front at x0 = {x0:.1f} (L = {L:g})")
    print("β      " + "".join(f"{m:>10d}" for m in modes) + "   M' with tail ≤ " + f"{a.tol:g}")
    for r in rows:
        cells = "".join(f"{r['tails'][m]:10.1e}" for m in modes)
        print(f"{r['beta']:<7g}{cells}   {r['modes_needed']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

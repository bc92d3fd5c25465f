"""Stability diagrams and transverse dispersion per closure (docs/closures.md).

* 40 × 40 diagrams (``chuteflow diagram --grid 40x40``) of ``lun``, ``lun_full``,
  ``mfix-lun`` and ``garzo_dufty`` at φ = 0.05 and 0.10; the counts of grid
  points (steady flows, regimes A/B/C) and the verdicts at the paper's points P1–P5 / Q1–Q3;
* the transverse dispersion Re α(k_z) at k_x = 0 (``chuteflow transverse``) at P1
  (θ = 16°, ν0(0) = 0.05, φ = 0.05) for ``lun``, ``lun_full``, ``mfix-lun``, and at the
  dense (16°, 0.2) for ``garzo_dufty`` (no steady flow at P1): α2z, the maximum of Re α,
  where it lies and the cut-off; with ``--figure`` the four curves in one PNG.

The diagrams resume from ``OUT/<name>_phi<φ>.nc`` (the CLI resumes automatically), so an
interrupted run continues. About 30–70 s per lun-type diagram with two workers; more for
``garzo_dufty``.

Run: ``python scripts/closures_diagrams.py [--out /tmp/s48diag] [--workers 2] [--figure F]``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

DIAGRAMS = [  # (name, φ, closure options), in the order of priority
    ("lun", 0.05, ["--transport", "lun"]),
    ("lun_full", 0.05, ["--transport", "lun_full"]),
    ("lun", 0.10, ["--transport", "lun"]),
    ("lun_full", 0.10, ["--transport", "lun_full"]),
    ("mfix_lun", 0.05, ["--preset", "mfix-lun"]),
    ("mfix_lun", 0.10, ["--preset", "mfix-lun"]),
    ("garzo_dufty", 0.05, ["--transport", "garzo_dufty"]),
    ("garzo_dufty", 0.10, ["--transport", "garzo_dufty"]),
]

TRANSVERSE = [  # (name, ν0(0), closure options, model dict); θ = 16°, φ = 0.05
    ("lun", 0.05, ["--transport", "lun"], {"transport": "lun"}),
    ("lun_full", 0.05, ["--transport", "lun_full"], {"transport": "lun_full"}),
    ("mfix_lun", 0.05, ["--preset", "mfix-lun"], "mfix-lun"),
    ("garzo_dufty", 0.2, ["--transport", "garzo_dufty"], {"transport": "garzo_dufty"}),
]

ENV = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MPLBACKEND": "Agg"}


def _cli(*args: str) -> str:
    return subprocess.run(
        [sys.executable, "-m", "chuteflow", *args], env=ENV, check=True, capture_output=True, text=True
    ).stdout


def diagrams(out: Path, grid: str, workers: int) -> None:
    import xarray as xr

    print("| φ | closure | steady flows | A | B | C | not converged | marked points unstable | wall s |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, phi, opts in DIAGRAMS:
        nc = out / f"{name}_phi{phi:.2f}.nc"
        t0 = time.perf_counter()
        _cli(
            "diagram", "--roughness", str(phi), *opts, "--grid", grid, "--workers", str(workers),
            "--no-progress", "--out", str(nc), "--png", str(nc.with_suffix(".png")),
        )  # fmt: skip
        wall = time.perf_counter() - t0
        with xr.open_dataset(nc) as d:
            status = d["status"].values
            regime = d["regime"].values
            marked = [
                str(m) for m, u in zip(d["marker"].values, d["marker_unstable"].values, strict=True) if u == 1
            ]
            cols = [
                f"{phi:.2f}",
                f"`{name}`",
                *(str((status == k).sum()) for k in (0,)),
                *(str((regime == k).sum()) for k in (1, 2, 3)),
                str((status == 2).sum()),
                ", ".join(marked) or "none",
                f"{wall:.0f}",
            ]
            print("| " + " | ".join(cols) + " |")
            for m in d["marker"].values:
                p = d.sel(marker=m)
                th, nu = float(p["marker_theta"]), float(p["marker_nu0"])
                a2 = d["alpha2_re"].where(d["status"] == 0)
                print(
                    f"    {m} ({th:g}°, {nu:g}): status {int(p['marker_status'])}, "
                    f"Re α2 {float(p['marker_alpha2_re']):.4g}, regime {int(p['marker_regime'])}; "
                    f"neutral θ at this ν0(0): {_zeros(d['theta'].values, a2.interp(nu0=nu).values, '.2f')}, "
                    f"neutral ν0(0) at this θ: {_zeros(d['nu0'].values, a2.interp(theta=th).values, '.4f')}"
                )


def _zeros(x, y, fmt: str) -> str:
    """Sign changes of y(x) between finite neighbours, linearly interpolated."""
    out = []
    for i in range(len(x) - 1):
        y0, y1 = y[i], y[i + 1]
        if y0 == y0 and y1 == y1 and (y0 > 0) != (y1 > 0):
            out.append(format(x[i] + (x[i + 1] - x[i]) * y0 / (y0 - y1), fmt))
    return ", ".join(out) or "none"


def transverse(out: Path, figure: Path | None) -> None:
    print("| closure | ν0(0) | α2z | max Re α | at k_z | cut-off k_z | wall s |")
    print("|---|---|---|---|---|---|---|")
    for name, nu0, opts, _ in TRANSVERSE:
        t0 = time.perf_counter()
        text = _cli(
            "transverse", "--theta", "16", "--nu0", str(nu0), "--roughness", "0.05", *opts,
            "--kz-max", "0.005", "--num", "120", "--json",
        )  # fmt: skip
        wall = time.perf_counter() - t0
        r = json.loads(text)
        (out / f"transverse_{name}.json").write_text(text)
        print(
            f"| `{name}` | {nu0} | {r['alpha2_z']:.4g} | {r['growth_max']} | {r['kz_at_growth_max']} "
            f"| {r['kz_cutoff']} | {wall:.0f} |"
        )
    if figure is not None:
        _figure(figure)


def _figure(path: Path) -> None:
    import matplotlib.pyplot as plt
    import numpy as np

    from chuteflow.closures import ChuteModel
    from chuteflow.longwave.spanwise import transverse as transverse_scan
    from chuteflow.steady import solve_steady

    fig, ax = plt.subplots(figsize=(5.5, 3.6))
    for i, (name, nu0, _, spec) in enumerate(TRANSVERSE):
        if isinstance(spec, str):
            model = ChuteModel.preset(spec, roughness=0.05)
        else:
            model = ChuteModel(roughness=0.05, transport={"name": spec["transport"]})
        flow = solve_steady(theta=16.0, nu0=nu0, model=model)
        res = transverse_scan(flow, kz_max=0.005, num=120)
        d = res.dispersion
        if np.isfinite(d.alpha_re).any():
            ax.semilogx(d.kz, d.alpha_re, f"C{i}-", label=f"{name} (ν0(0) = {nu0})")
        else:  # the tracked branch is in the continuum at once (α2z < 0): the long-wave α2z k_z²
            kz = np.geomspace(1e-5, 0.005, 60)
            ax.semilogx(kz, res.alpha2_z * kz**2, f"C{i}--", label=f"{name} (ν0(0) = {nu0}): α2z k_z²")
    ax.axhline(0, color="k", lw=0.6)
    ax.set_ylim(-1e-4, 1e-4)
    ax.set_xlabel("spanwise wavenumber $k_z$ (1/σ)")
    ax.set_ylabel("Re α (k_x = 0)")
    ax.set_title("transverse dispersion, θ = 16°, φ = 0.05", fontsize=10)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("/tmp/s48diag"))
    ap.add_argument("--grid", default="40x40")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--figure", type=Path, default=None, help="PNG of the four transverse curves")
    ap.add_argument("--skip-diagrams", action="store_true")
    a = ap.parse_args()
    a.out.mkdir(parents=True, exist_ok=True)
    if not a.skip_diagrams:
        diagrams(a.out, a.grid, a.workers)
    transverse(a.out, a.figure)


if __name__ == "__main__":
    main()

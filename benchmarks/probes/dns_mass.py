"""Mass conservation of the DNS at finite amplitude (issue 11; docs/dns.md, *Mass*).

From noise of 10 % in ln ν (modes 1 … 2 of L = 1000, P1, co-moving frame), 40 time units at
Δt = 4: the drift of ∫∫ν dx dy (with the isothermal tail) and the size of the uniform mass
source λ (``Discretisation.mass_source``: what the floor and top nodes' boundary rows and the
quadrature of the divergence leave, returned to the column), for a ladder of N. λ is read
from the residual evaluations of the last step. Run: ``python benchmarks/probes/dns_mass.py``.
"""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "src"))

import numpy as np

from chuteflow.closures import ChuteModel
from chuteflow.dns import Discretisation, simulate
from chuteflow.steady import solve_steady


def main() -> None:
    warnings.simplefilter("ignore", RuntimeWarning)
    model = ChuteModel(roughness=0.05)
    flow = solve_steady(16.0, 0.05, model)
    seen: list[float] = []
    original = Discretisation.mass_source

    def spy(self, *args):
        lam = original(self, *args)
        if self.modes:
            seen.append(lam)
        return lam

    Discretisation.mass_source = spy  # type: ignore[method-assign]
    try:
        for n in (40, 60, 80, 100):
            seen.clear()
            ds = simulate(
                flow, 1000.0, time=40.0, dt=4.0, modes=4, n=n,
                init="noise", amplitude=0.1, frame_speed=7.8,
            )  # fmt: skip
            rho = ds["rho_bar"].values[-1]
            lam = np.abs(seen[-5:])
            print(
                f"N = {n:3d}: ρ̄ {rho.min():.4f} … {rho.max():.4f}, mass drift {ds.attrs['mass_drift']:.1e}, "
                f"|λ| at the last step {lam.max():.2e} (status {ds.attrs['status']})",
                flush=True,
            )
    finally:
        Discretisation.mass_source = original  # type: ignore[method-assign]


if __name__ == "__main__":
    main()

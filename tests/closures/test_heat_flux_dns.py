"""The time-dependent simulation with a density-gradient heat flux: its linear phase is the
stability operator's eigenvalue (both derived from chuteflow.equations, where q = −κ∇T −
κ_h∇ν is stated once). Half a wave period from the least-stable mode at k = 0.003 at P1
with ``lun_full``, as tests/dns/test_dns.py::test_linear_phase_short does for the paper's
closure: measured 2.8e-6 relative (5e-5 there), asserted to 1 %.

``garzo_dufty``: tests/closures/test_heat_flux_dns_gd.py (it has no steady flow at P1; at
θ = 16°, ν0(0) = 0.2 it has one).
"""

from __future__ import annotations

import math

from chuteflow import ChuteModel, solve_steady
from chuteflow.dns import simulate, summary
from chuteflow.stability import least_stable

K = 0.003


def test_linear_phase_is_the_eigenvalue_with_kappa_h():
    model = ChuteModel(roughness=0.05, transport="lun_full")
    flow = solve_steady(16.0, 0.05, model)
    mode = least_stable(flow, K)
    period = 2 * math.pi / abs(mode.alpha.imag)
    s = summary(simulate(flow, 2 * math.pi / K, time=period / 2, dt=period / 100))
    assert s["status"] == "ok"
    alpha_dns = complex(s["alpha_dns_re"], s["alpha_dns_im"])
    assert abs(alpha_dns - mode.alpha) < 1e-2 * abs(mode.alpha)
    assert s["mass_drift"] < 1e-12
    # and κ_h moved the eigenvalue by more than the check's resolution (Lun's κ_h is small,
    # not nothing)
    assert abs(mode.alpha - least_stable(solve_steady(16.0, 0.05, ChuteModel()), K).alpha) > 1e-3 * abs(
        mode.alpha
    )

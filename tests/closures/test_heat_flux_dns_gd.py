"""The time-dependent simulation with ``garzo_dufty`` (κ_h and the first-order cooling ζ_U of
Garzó & Dufty 1999): its linear phase is the stability operator's eigenvalue, both derived
from chuteflow.equations.

``garzo_dufty`` has no steady flow at the paper's dilute points (docs/closures.md); at the
denser θ = 16°, ν0(0) = 0.2 (h = 5.556) it has one. There the simulation's steady
relaxation stalls at a scaled Newton residual of 3.7e-10, above the step's ``atol`` 1e-10:
the round-off floor of this denser flow's residual, accepted by ``NewtonSettings.floor_atol``
(1e-9). Half a wave period from the least-stable mode at k = 0.003, as
tests/closures/test_heat_flux_dns.py does for ``lun_full``: measured 4.5e-6 relative,
asserted to 1 %.
"""

from __future__ import annotations

import math

from chuteflow import ChuteModel, solve_steady
from chuteflow.dns import simulate, summary
from chuteflow.stability import least_stable

K = 0.003


def test_linear_phase_is_the_eigenvalue_with_garzo_dufty():
    flow = solve_steady(16.0, 0.2, ChuteModel(roughness=0.05, transport="garzo_dufty"))
    mode = least_stable(flow, K)
    assert mode.converged
    period = 2 * math.pi / abs(mode.alpha.imag)
    s = summary(simulate(flow, 2 * math.pi / K, time=period / 2, dt=period / 100))
    assert s["status"] == "ok"
    alpha_dns = complex(s["alpha_dns_re"], s["alpha_dns_im"])
    assert abs(alpha_dns - mode.alpha) < 1e-2 * abs(mode.alpha)
    assert s["mass_drift"] < 1e-12


def test_the_round_off_floor_rule():
    """A residual that stopped falling below floor_atol is accepted; one still falling, or
    above floor_atol, is not."""
    from chuteflow.dns.stepper import atol_floor_reached

    assert atol_floor_reached([5e-10, 4e-10, 3.7e-10], 1e-10, 1e-9)
    assert not atol_floor_reached([1e-6, 1e-8, 4e-10], 1e-10, 1e-9)  # still falling fast
    assert not atol_floor_reached([5e-9, 4.9e-9, 4.8e-9], 1e-10, 1e-9)  # above the floor
    assert not atol_floor_reached([4e-10, 3.7e-10], 1e-10, 1e-9)  # too few iterations

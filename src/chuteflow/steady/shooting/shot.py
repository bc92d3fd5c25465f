"""One trial of the shooting scan (paper §3): integrate from the floor at a trial u0(0) and
classify the miss of the top condition eq. (3.13).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .dopri_scipy import integrate
from .ode import SteadyODE
from .trajectory import Trajectory, _level

#: A trial whose temperature falls below this fraction of T0(0) is cold (collapsing). Near
#: the upper existence boundary the physical flow has a packed band (ν0 ≈ 0.59) whose
#: temperature is 1e-4–1e-6 of the floor's below a dilute hot top (φ = 0.10, θ = 22.34°,
#: ν0(0) = 0.1039: tests/steady/test_existence_map.py), so the threshold is as low as the
#: independent reference's (tests/steady/shooting.py).
_COLD = 1e-10


@dataclass(frozen=True)
class Shot:
    """One trial integration from the floor."""

    u_floor: float
    sign: int  # +1 hot, −1 cold
    kind: str  # "top" (reached nu_top), "hot" (never thinned out), "cold", "packed"
    dT_top: float  # T0' where ν0 = nu_top (nan if not reached)
    y_end: float
    solution: Any = field(default=None, repr=False)

    @property
    def miss(self) -> float:
        """Signed miss of the top condition (T0'(y_max) if reached, else ±1)."""
        return self.dT_top if self.kind == "top" else float(self.sign)


def shoot(
    ode: SteadyODE,
    nu0: float,
    u_floor: float,
    *,
    nu_top: float = 1e-9,
    rtol: float = 1e-6,
    y_cap: float = 1e5,
    dense: bool = False,
) -> Shot:
    """Integrate the steady equations upwards from the floor at trial ``u_floor``.

    Stops where ν0 = ``nu_top`` (the top), where T0 falls below 1e-10 T0(0) (cold collapse),
    where ν0 reaches 0.999 ν_m (packing), where T0 exceeds 100 T0(0) or at ``y_cap`` (the
    layer heats up and never thins: hot). The physical flows are hottest at the floor or
    close to it (T0 ≤ T0(0) at the paper's points), so these thresholds only cut short
    trials that have already chosen their direction.
    """
    T0, T0p = ode.floor_values(nu0, u_floor)
    ln_top = math.log(nu_top)
    ln_pack = math.log(0.999 * ode.model.nu_max)

    z0 = [math.log(nu0), u_floor, T0, T0p]
    # (name, component k, constant c, direction): the event z[k] − c
    levels = (
        ("top", 0, ln_top, -1),
        ("cold", 2, _COLD * T0, 0),
        ("packed", 0, ln_pack, 0),
        ("hot", 2, 100.0 * T0, 0),
    )
    if not all(map(math.isfinite, z0)):
        # the floor conditions have no solution at this trial (outside the closures'
        # domain): nothing to integrate, and no sign of cooling, so hot (as a trajectory
        # whose integrator gives up at once with T0' not negative, below)
        start = Trajectory(np.zeros(1), np.array(z0, dtype=float)[:, None], None, -1, None)
        return Shot(u_floor, 1, "hot", math.nan, 0.0, start)
    if ode.kernel is not None:
        sol = ode.kernel.integrate(z0, y_cap, rtol, levels, dense=dense)
    else:
        events = tuple((name, _level(k, c), d) for name, k, c, d in levels)
        with np.errstate(all="ignore"):
            sol = integrate(ode.rhs_bounded, z0, y_cap, rtol, events, dense=dense)
    y_end = float(sol.t[-1])
    if sol.event == "top":
        d = float(sol.y[3, -1])
        return Shot(u_floor, 1 if d > 0 else -1, "top", d, y_end, sol)
    if sol.event in ("cold", "packed"):
        return Shot(u_floor, -1, sol.event, math.nan, y_end, sol)
    if sol.event == "hot" or sol.status == 0:
        return Shot(u_floor, 1, "hot", math.nan, y_end, sol)
    # the integrator gave up: a finite-height singularity. Cooling with T0' → −∞ is the
    # collapse of a cold layer; otherwise the temperature blows up (hot).
    last_T_y = float(sol.y[3, -1])
    if last_T_y < 0:
        return Shot(u_floor, -1, "cold", math.nan, y_end, sol)
    return Shot(u_floor, 1, "hot", math.nan, y_end, sol)

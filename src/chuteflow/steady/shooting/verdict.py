"""The verdict of the shooting scan (paper §3): whether a steady flow exists, and the shot
profile that starts Newton.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ...closures import ChuteModel
from ...spectral import ChebyshevGrid
from .._roots import brent_root
from ..inputs import validate_point
from ..state import NewtonState
from .ode import SteadyODE
from .shot import shoot

#: Default admissible range of the floor slip velocity u0(0) (units of √(gσ)). At the
#: paper's parameters the physical flows have u0(0) between ≈ 0.5 and ≈ 150.
U_RANGE = (1e-2, 1e3)


@dataclass(frozen=True)
class ExistenceVerdict:
    """Outcome of :func:`steady_existence`.

    Attributes
    ----------
    exists : bool
        Whether the steady equations have a solution (a hot → cold sign change in u0(0)).
    physical : bool
        ``exists`` and the layer is at least ``min_thickness`` thick.
    kind : str
        ``"flow"``, ``"thin"`` (a solution thinner than ``min_thickness``),
        ``"too_small"`` (every trial hot), ``"too_large"`` (every trial cold) or
        ``"no_sign_change"`` (neither: no hot → cold change from above).
    reason : str
        One sentence for the user, naming the parameters.
    u_floor : float
        u0(0) of the solution (nan when none).
    bracket : tuple
        (cold, hot) trial values of u0(0) enclosing it.
    h, y_max : float
        Thickness (ν0 at 1 % of its maximum) and top of the shot solution.
    shots : int
        Number of trial integrations.
    seconds : float
        Wall time of the scan.
    """

    exists: bool
    physical: bool
    kind: str
    reason: str
    u_floor: float = math.nan
    bracket: tuple = (math.nan, math.nan)
    h: float = math.nan
    y_max: float = math.nan
    shots: int = 0
    seconds: float = 0.0
    solution: Any = field(default=None, repr=False, compare=False)

    def starting_state(self, n: int = 64) -> NewtonState:
        """The shot profile on n + 1 Chebyshev nodes of [0, y_max], as a Newton start."""
        if self.solution is None:
            raise ValueError("no shot profile: " + self.reason)
        grid = ChebyshevGrid(n, 0.0, self.y_max)
        z = self.solution.sol(grid.y)
        return NewtonState(n, z[0].copy(), z[1].copy(), z[2].copy(), self.y_max)


class _Separatrix(Exception):
    """The bracket shrinks without any trial reaching the top."""


def _where(theta, nu0, model):
    return (
        f"theta = {theta:g} deg, nu0 = {nu0:g}, roughness = {model.roughness:g}, "
        f"wall_loss = {model.wall_loss:g}"
    )


def _thickness(sol, y_max) -> float:
    """Height where ν0 falls to 1 % of its maximum above the maximum (as SteadyFlow.h)."""
    y = np.linspace(0.0, y_max, 4001)
    s = sol.sol(y)[0]
    i = int(np.argmax(s))
    target = s[i] + math.log(0.01)
    below = np.nonzero(s[i:] <= target)[0]
    if not len(below):
        return y_max
    j = i + int(below[0])
    return float(brent_root(lambda t: sol.sol(t)[0] - target, y[j - 1], y[j], xtol=1e-10))


def steady_existence(
    theta: float,
    nu0: float,
    model: ChuteModel | None = None,
    *,
    nu_top: float = 1e-9,
    u_range: tuple[float, float] = U_RANGE,
    ratio: float = 2.0,
    rtol: float = 1e-4,
    fine_rtol: float = 1e-6,
    min_thickness: float = 1.0,
) -> ExistenceVerdict:
    """Decide whether a steady flow exists at (``theta``, ``nu0``) by a shooting scan.

    Trials u0(0) = u_max, u_max/ratio, … (down to u_min) are integrated from the floor at
    loose tolerance and classified hot/cold (module docstring). Each hot → cold change,
    coming down from u_max, is refined by Brent's method on the signed miss T0'(y_max) (±1
    for trials that do not reach ``nu_top``) at ``fine_rtol``; the first change where a
    trial reaches ``nu_top`` with T0'(y_max) small (|T0'| y_max < 1e-3 T0(y_max)) is the
    physical flow, and that trial's dense output is what
    :meth:`ExistenceVerdict.starting_state` samples for Newton. A change where no trial
    reaches the top is a separatrix (typically a dense band packing to ν_m that either
    collapses or heats up above it), not a solution, and the scan goes on below it.

    Cost: about 18 coarse trials plus 10–30 refining ones, 0.02–0.4 s per point on one core (the
    right-hand side is generated scalar code, :mod:`chuteflow.steady._scalar_ode`, ~5 µs a call,
    and the stepping loop is scipy's compiled ``dopri5``,
    :func:`~chuteflow.steady.shooting.dopri_scipy.integrate`: most of the time is now the
    right-hand side's Python calls).

    Parameters
    ----------
    theta : float
        Inclination θ in degrees.
    nu0 : float
        Floor packing fraction ν0(0).
    model : ChuteModel, optional
        Closure parameters (paper defaults).
    nu_top : float
        ν0 at the top of the domain (paper: 1e-9).
    u_range : (float, float)
        Admissible floor velocities (u_min, u_max) scanned.
    ratio : float
        Ratio of consecutive trials of the coarse scan.
    rtol : float
        Relative tolerance of the scan's integrations (loose: it needs signs only).
    fine_rtol : float
        Relative tolerance of the integrations that locate the solution in the bracket.
    min_thickness : float
        A solution thinner than this (diameters) is reported as ``physical = False``
        (paper §3.2: decay length below one particle diameter).

    Returns
    -------
    ExistenceVerdict
    """
    t_start = time.perf_counter()
    model = model or ChuteModel()
    theta, nu0 = validate_point(theta, nu0, model, nu_top)
    ode = SteadyODE(theta, model)
    where = _where(theta, nu0, model)
    u_min, u_max = map(float, u_range)
    n_trials = int(math.ceil(math.log(u_max / u_min) / math.log(ratio))) + 1
    trials = np.geomspace(u_max, u_min, n_trials)
    count = [0]

    def trial(u):
        count[0] += 1
        return shoot(ode, nu0, float(u), nu_top=nu_top, rtol=rtol)

    def done(kind, reason, **kw):
        return ExistenceVerdict(
            exists=kind in ("flow", "thin"),
            physical=kind == "flow",
            kind=kind,
            reason=reason,
            shots=count[0],
            seconds=time.perf_counter() - t_start,
            **kw,
        )

    def refine(cold, hot, tol=fine_rtol):
        """Brent on the signed miss in ln u0(0) at ``tol``; trials that do not reach
        nu_top count as ±1. Every trial keeps its dense output: the closest one to the root
        that reached the top is returned (None: a separatrix, see below)."""
        lo, hi = math.log(cold.u_floor), math.log(hot.u_floor)
        ends = {lo: cold, hi: hot}

        def miss(x):
            count[0] += 1
            shot = shoot(ode, nu0, math.exp(x), nu_top=nu_top, rtol=tol, dense=True)
            ends[x] = shot
            if len(ends) > 14 and not any(sh.kind == "top" for sh in ends.values()):
                raise _Separatrix
            return shot.miss

        # the miss jumps at separatrices: scipy's brentq (imported with scipy.integrate, which
        # only a failed cold start needs) bisects those robustly; through the forwarder of
        # chuteflow._memory, so that the shots of this scan are freed with it
        from ..._memory import brentq

        try:
            x = brentq(miss, lo, hi, xtol=1e-10, rtol=1e-12, maxiter=60)
        except (ValueError, RuntimeError, _Separatrix):
            x = 0.5 * (lo + hi)
        # brentq starts with both ends: the scan's trials again, at tol
        fine = (ends[lo], ends[hi])
        # a scan trial within ~1e-4 of the root can change sign with the tolerance (θ =
        # 17.161°, ν0(0) = 0.16556, φ = 0.0455, Φ = 0.469, e_p = 0.688: the trial u0(0) =
        # 17.1907 is cold at 1e-4 and hot at 1e-6, the root 17.1887 lies below it): then
        # both ends have one sign at tol, and the scan's trial keeps its end of the bracket
        # here (the caller goes on from the trial at tol)
        if not any(sh.sign < 0 for sh in ends.values()):
            ends[lo] = cold
        if not any(sh.sign > 0 for sh in ends.values()):
            ends[hi] = hot
        cold_u = max(math.exp(v) for v, sh in ends.items() if sh.sign < 0)
        hot_u = min(math.exp(v) for v, sh in ends.items() if sh.sign > 0)
        # a trial that solves the top condition eq. (3.13): T0' small on the scale of the
        # layer (T0(y_max)/y_max); one far from it is a stray trial beside a separatrix
        reached = [
            v
            for v, sh in ends.items()
            if sh.kind == "top"
            and sh.solution.sol is not None
            and abs(sh.dT_top) * sh.y_end < 1e-3 * float(sh.solution.y[2, -1])
        ]
        best = ends[min(reached, key=lambda v: abs(v - x))] if reached else None
        x_cold = max(v for v, sh in ends.items() if sh.sign < 0)
        x_hot = min(v for v, sh in ends.items() if sh.sign > 0)
        a, b = ends[x_cold], ends[x_hot]
        if (
            best is None
            and a.kind == b.kind == "top"
            and abs(x_hot - x_cold) < 1e-7
            and a.solution.sol is not None
            and b.solution.sol is not None
        ):
            # T0'(y_max) changes sign between two trials that both reach the top, 1e-7
            # apart: a root of a continuous miss, not a separatrix — only too sensitive
            # (a packed, very cold band under the top) for |T0'| to become small
            best = a if abs(a.dT_top) <= abs(b.dT_top) else b
        nu_peak = max(math.exp(float(sh.solution.y[0].max())) for sh in ends.values())
        return best, (cold_u, hot_u), nu_peak, fine

    # the first hot → cold change coming down from u_max that brackets a solution; a change
    # without a trial reaching nu_top is a separatrix (a discontinuity of the miss, e.g. a
    # band packing to nu_max that either collapses or heats up above it), and the scan goes on
    prev = pprev = None
    signs = []
    final = separatrix = None
    for u in trials:
        shot = trial(u)
        signs.append(shot.sign)
        if prev is not None and prev.sign > 0 > shot.sign:
            best, bracket, nu_peak, (lo_fine, hi_fine) = refine(shot, prev)
            if best is None and lo_fine.sign > 0 and hi_fine.sign > 0:
                # this trial heats up at fine_rtol: the change lies below it, the scan goes
                # on from it as a hot trial
                signs[-1] = 1
                pprev, prev = prev, lo_fine
                continue
            cools = lo_fine.sign < 0 and hi_fine.sign < 0
            if best is None and cools and pprev is not None and pprev.sign > 0:
                # the trial above cools at fine_rtol: the change lies above it
                best, bracket, nu_peak, _ = refine(hi_fine, pprev)
            if best is None:
                # near the upper existence boundary the flow packs to within a hair of
                # nu_max below a dilute top, and a trial at fine_rtol can pack spuriously:
                # a separatrix is only believed when it persists at 1e-9 (as the
                # independent reference of tests/steady checks at 1e-11)
                best, bracket, nu_peak, _ = refine(shot, prev, 1e-9)
            if best is not None:
                final = best
                break
            separatrix = separatrix or (bracket, nu_peak)
        pprev, prev = prev, shot
    if final is None and separatrix is not None:
        bracket, nu_peak = separatrix
        packs = nu_peak > 0.95 * model.nu_max
        return done(
            "too_large" if packs else "no_sign_change",
            (
                f"no steady flow at {where}: the change from a heating to a cooling layer at "
                f"u0(0) ≈ {math.sqrt(bracket[0] * bracket[1]):.6g} is a separatrix, not a "
                f"solution — no trial there reaches nu0 = {nu_top:g}"
                + (
                    f" (the density piles up to {nu_peak:.3g}, close to nu_max = "
                    f"{model.nu_max:g}): the angle is too large for this floor density"
                    if packs
                    else ""
                )
            ),
            bracket=bracket,
        )
    if final is None:
        rng = f"u0(0) in [{u_min:g}, {u_max:g}]"
        if all(s > 0 for s in signs):
            return done(
                "too_small",
                (
                    f"no steady flow at {where}: shooting finds no sign change of T0' at the top "
                    f"for {rng} — every trial layer heats up (T0' > 0 where nu0 reaches "
                    f"{nu_top:g}, even the thin cold layer): the angle is too small for this "
                    "roughness and floor density"
                ),
            )
        if all(s < 0 for s in signs):
            return done(
                "too_large",
                (
                    f"no steady flow at {where}: shooting finds no sign change of T0' at the top "
                    f"for {rng} — every trial layer cools and collapses or packs to nu_max: "
                    "the angle is too large for this roughness and floor density"
                ),
            )
        return done(
            "no_sign_change",
            (
                f"no steady flow at {where}: shooting finds no change from a heating to a "
                f"cooling layer as u0(0) decreases over {rng}"
            ),
        )
    kw = {"bracket": bracket}
    kw["u_floor"] = final.u_floor
    y_max = final.y_end
    h = _thickness(final.solution, y_max)
    kw.update(h=h, y_max=y_max, solution=final.solution)
    if h < min_thickness:
        return done(
            "thin",
            (
                f"no steady flow at {where}: the only solution (u0(0) = {final.u_floor:.4g}) "
                f"has thickness h = {h:.3g}, below {min_thickness:g} particle diameter, which the "
                "hydrodynamics cannot describe — the angle is too small for this roughness (or "
                "the floor density too low)"
            ),
            **kw,
        )
    return done("flow", (f"steady flow at {where}: u0(0) = {final.u_floor:.6g}, h = {h:.4g}"), **kw)

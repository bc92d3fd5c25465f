"""The shooting scan's integrator through scipy's ``dopri5`` (used where no C compiler is
available).
"""

from __future__ import annotations

import numpy as np

from .trajectory import Trajectory, _crossing, _hermite, _hermite_output, _secant_event


def integrate(fun, z0, y_cap: float, rtol: float, events, *, dense: bool = False) -> Trajectory:
    """Integrate dz/dy = fun(y, z) from y = 0 with scipy's Dormand–Prince 5(4) (``dopri5``
    of :class:`scipy.integrate.ode`, Hairer's Fortran code: the same method, error norm and
    step control as ``solve_ivp(method="RK45")``, with the stepping loop compiled) until
    one of ``events`` changes sign across an accepted step or y = ``y_cap``.

    ``events`` is a sequence of (name, g, direction) with g(z) a scalar function of the
    state; direction −1 stops only where g goes from positive to non-positive, +1 from
    negative to non-negative, 0 either way (as ``solve_ivp``'s terminal events, which also
    look at the step ends only). The crossing is located on the step's cubic Hermite
    interpolant (by bisection to round-off); the earliest triggered event wins.
    """
    import warnings

    # scipy.integrate costs ~0.3 s to import: only the existence scan needs it
    from scipy.integrate import ode

    ts: list[float] = []
    zs: list[np.ndarray] = []
    hit: list = []
    stop: list = []  # the step where an event triggered: t_old, z_old, crossing estimate, t

    g_prev: list = []  # the events' values at the last accepted step

    def solout(t, z):
        z = np.array(z, dtype=float)
        g_now = [g(z) for _, g, _ in events]
        if ts:
            t_old, z_old = ts[-1], zs[-1]
            found = [(name, g) for (name, g, d), a, b in zip(events, g_prev, g_now) if _crossing(a, b, d)]
            if found:
                f0 = np.asarray(fun(t_old, z_old), dtype=float)
                f1 = np.asarray(fun(t, z), dtype=float)
                best = None
                for name, g in found:
                    lo, hi = t_old, t
                    glo = g(z_old)
                    for _ in range(100):
                        mid = 0.5 * (lo + hi)
                        if mid <= lo or mid >= hi:
                            break
                        gm = g(_hermite(t_old, t, z_old, z, f0, f1, mid))
                        if (gm > 0) == (glo > 0) and gm != 0:
                            lo, glo = mid, gm
                        else:
                            hi = mid
                    if best is None or hi < best[1]:
                        best = (name, hi)
                assert best is not None  # found is not empty
                hit.append(best[0])
                stop.extend([t_old, z_old, best[1], float(t)])
                return -1
        ts.append(float(t))
        zs.append(z)
        g_prev[:] = g_now
        return 0

    r = ode(fun).set_integrator("dopri5", rtol=rtol, atol=1e-12, nsteps=10**6)
    r.set_solout(solout)
    r.set_initial_value(np.asarray(z0, dtype=float), 0.0)
    with warnings.catch_warnings():
        # "step size becomes too small": reported through status −1
        warnings.simplefilter("ignore", UserWarning)
        r.integrate(y_cap)
    if hit:
        # the crossing on the step's interpolant is accurate to O(h⁴); two secant steps on
        # g(z(t)), each integrating afresh from the start of that step to the estimate (the
        # integrator ends exactly there), bring it to the integration's own tolerance, as
        # solve_ivp's events on its dense output
        t_old, z_old, t_ev, t_step = stop
        g = next(gg for name, gg, _ in events if name == hit[0])

        def state_at(t_end):
            if t_end <= t_old:
                return z_old
            rr = ode(fun).set_integrator("dopri5", rtol=rtol, atol=1e-12, nsteps=10**4)
            rr.set_initial_value(z_old, t_old)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", UserWarning)
                return np.array(rr.integrate(t_end), dtype=float)

        t_ev, z_ev = _secant_event(
            g, lambda t, z: np.asarray(fun(t, z), dtype=float), state_at, t_old, t_ev, t_step
        )
        ts.append(t_ev)
        zs.append(z_ev)
    status = 0 if (hit or r.successful()) else -1
    t = np.array(ts)
    y = np.array(zs).T
    sol = None
    if dense and len(t) > 1:
        sol = _hermite_output(t, y.T, np.array([fun(ti, zi) for ti, zi in zip(t, y.T)], dtype=float))
    return Trajectory(t, y, hit[0] if hit else None, status, sol)

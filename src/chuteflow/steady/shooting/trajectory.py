"""A trial integration of the shooting scan (paper §3) and what both integrators share: the
step's cubic Hermite interpolant, event crossings, the secant refinement of an event and
the dense output.
"""

from __future__ import annotations

import math

import numpy as np


class Trajectory:
    """One trial integration: the accepted steps (heights ``t``, states ``y`` of shape
    4 × steps, the last one at the event that stopped it) and, if dense, ``sol``: the
    piecewise cubic Hermite interpolant through them (states and derivatives at the step
    ends, third order like the integrator's own dense output), called as ``sol(y)`` with
    values of shape 4 × len(y) (None otherwise).

    Attributes
    ----------
    t : ndarray
        Heights of the accepted steps.
    y : ndarray
        States (ln ν0, u0, T0, T0') there, shape (4, len(t)).
    event : str or None
        The event that stopped the integration ("top", "cold", "packed", "hot"); None if it
        reached ``y_cap`` (``status`` 0) or the integrator gave up (``status`` −1).
    status : int
        0: ended at an event or at ``y_cap``; −1: the step size fell below round-off (a
        finite-height singularity).
    sol : callable or None
        The dense interpolant.
    """

    def __init__(self, t, y, event, status, sol):
        self.t, self.y, self.event, self.status, self.sol = t, y, event, status, sol


def _hermite(t0, t1, y0, y1, f0, f1, t):
    """Cubic Hermite interpolant of one step at t ∈ [t0, t1]."""
    h = t1 - t0
    s = (t - t0) / h
    h00, h10 = (1 + 2 * s) * (1 - s) ** 2, s * (1 - s) ** 2
    h01, h11 = s * s * (3 - 2 * s), s * s * (s - 1)
    return h00 * y0 + h10 * h * f0 + h01 * y1 + h11 * h * f1


def _crossing(a, b, direction) -> bool:
    """Whether an event function changes sign from a to b in ``direction`` (−1: from
    positive to non-positive; +1: from negative to non-negative; 0: either)."""
    if direction < 0:
        return a > 0 >= b
    if direction > 0:
        return a < 0 <= b
    return (a > 0 >= b) or (a < 0 <= b)


def _secant_event(g, rhs, state_at, t_old, t_ev, t_step):
    """The event g(z(t)) = 0 in the step (t_old, t_step] from its estimate ``t_ev`` on the
    step's interpolant: two secant steps (``rhs(t, z)`` = dz/dt), each integrating afresh
    from the step's start (``state_at``), brought to the integration's own tolerance.
    Returns (t, z(t))."""
    z_ev = state_at(t_ev)
    for _ in range(2):
        f_ev = rhs(t_ev, z_ev)
        eps = 1e-7 * max(1.0, float(np.abs(z_ev).max())) / max(float(np.abs(f_ev).max()), 1e-300)
        slope = (g(z_ev + eps * f_ev) - g(z_ev)) / eps
        if not (math.isfinite(slope) and slope != 0):
            break
        t_new = t_ev - g(z_ev) / slope
        if not (t_old < t_new < 2 * t_step - t_old) or t_new == t_ev:
            break
        t_ev, z_ev = t_new, state_at(t_new)
    return t_ev, z_ev


def _hermite_output(t, zs, fs):
    """Dense output through the accepted steps: the piecewise cubic Hermite interpolant of
    states ``zs`` and derivatives ``fs`` (both steps × 4), called as ``sol(y)`` → 4 × len(y).

    The spline is built at the first call: of the ~20 trials of a scan's bisection, each
    with its dense output, only the one closest to the root is evaluated (building scipy's
    spline for every trial cost a quarter of a scan)."""
    spline = None

    def sol(yy):
        nonlocal spline
        if spline is None:
            from scipy.interpolate import CubicHermiteSpline

            spline = CubicHermiteSpline(t, zs, fs, axis=0, extrapolate=True)
        return np.asarray(spline(yy)).T

    return sol


def _level(k: int, c: float):
    """The event function z ↦ z[k] − c."""
    return lambda z: z[k] - c

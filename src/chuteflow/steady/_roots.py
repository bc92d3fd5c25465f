"""Brent's root finder on a bracket, in plain Python (no scipy import at start-up).

Every steady solution needs two scalar roots (the thickness h and the height of the density
maximum, :func:`chuteflow.steady.result.derived_quantities`); importing ``scipy.optimize``
for them costs about 0.2 s per process, more than the solve itself. This is R. P. Brent's
algorithm (*Algorithms for Minimization without Derivatives*, 1973, ch. 4, procedure
``zero``): inverse quadratic interpolation and secant steps, safeguarded by bisection, so
it converges on any bracket like :func:`scipy.optimize.brentq` does.
"""

from __future__ import annotations

import math
from collections.abc import Callable

_EPS = 2.220446049250313e-16


def brent_root(
    f: Callable[[float], float],
    a: float,
    b: float,
    *,
    xtol: float = 2e-12,
    rtol: float = 4 * _EPS,
    maxiter: int = 100,
) -> float:
    """Root of ``f`` in [a, b] (f(a), f(b) of opposite signs) to xtol + rtol·|x|.

    Raises
    ------
    ValueError
        f(a) and f(b) have the same sign (no bracket).
    RuntimeError
        Not converged in ``maxiter`` iterations.
    """
    fa, fb = float(f(a)), float(f(b))
    if fa == 0.0:
        return a
    if fb == 0.0:
        return b
    if (fa > 0) == (fb > 0):
        raise ValueError("f(a) and f(b) must have different signs")
    c, fc = a, fa
    d = e = b - a
    for _ in range(maxiter):
        if (fb > 0) == (fc > 0):
            c, fc = a, fa
            d = e = b - a
        if abs(fc) < abs(fb):
            a, b, c = b, c, b
            fa, fb, fc = fb, fc, fb
        tol = 2.0 * _EPS * abs(b) + 0.5 * (xtol + rtol * abs(b))
        m = 0.5 * (c - b)
        if abs(m) <= tol or fb == 0.0:
            return b
        if abs(e) < tol or abs(fa) <= abs(fb):
            d = e = m  # bisection
        else:
            s = fb / fa
            if a == c:  # secant
                p, q = 2.0 * m * s, 1.0 - s
            else:  # inverse quadratic interpolation
                q, r = fa / fc, fb / fc
                p = s * (2.0 * m * q * (q - r) - (b - a) * (r - 1.0))
                q = (q - 1.0) * (r - 1.0) * (s - 1.0)
            if p > 0:
                q = -q
            else:
                p = -p
            if 2.0 * p < min(3.0 * m * q - abs(tol * q), abs(e * q)):
                e, d = d, p / q
            else:
                d = e = m
        a, fa = b, fb
        b += d if abs(d) > tol else math.copysign(tol, m)
        fb = float(f(b))
    raise RuntimeError(f"brent_root: not converged in {maxiter} iterations")

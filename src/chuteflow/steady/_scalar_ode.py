"""Generated scalar code of the steady equations as an ODE in y (for the shooting scan).

The shooting scan of :mod:`chuteflow.steady.existence` evaluates the right-hand side of
the steady equations ~10⁴ times per point, one point at a time. Here the right-hand side is
derived symbolically, once, from the same statements as everything else: the y-momentum and
energy residuals of :func:`chuteflow.equations._derive_compiled` (eqs 3.5, 3.6; both affine in
their highest derivative, ν0' and T0'', which they therefore give exactly as
−R(0)/coefficient), u0' = tanθ p/μ (eq. 3.7) and the closures' partials of
:func:`chuteflow.closures.model._derive` substituted in. Common subexpressions are
eliminated and the code is generated for Python floats with the ``math`` module
(:func:`chuteflow._codegen.cached_lambdify`, cached on disk like the other generated code):
about five times faster than calling the closures' and equations' numpy code with scalars.
"""

from __future__ import annotations

import functools
from collections.abc import Callable

from .._codegen import cached_lambdify, lazy_module
from ..closures.model import FUNCTIONS, ORDERS, _derive
from ..equations import BASE, _derive_compiled

sp = lazy_module("sympy")


@functools.cache
def scalar_rhs(transport, radial, wall) -> Callable:
    """``f(nu, u, T, T_y, e_p, nu_m, phi, Phi, sin θ, cos θ)`` → [ν0'/ν0, u0', T0''] for
    the given closure objects (Python floats; raises or returns complex numbers outside the
    closures' domain)."""
    code = cached_lambdify(
        "steady_ode",
        repr((transport, radial, wall)),
        lambda: _derive_rhs(transport, radial, wall),
        sources=(__name__, "chuteflow.equations", "chuteflow.closures.model", transport, radial, wall),
        modules="math",
    )
    return code["rhs"]


def _derive_rhs(transport, radial, wall):
    """Sympy expressions of :func:`scalar_rhs`: {"rhs": (args, [ν0'/ν0, u0', T0''])}."""
    espec, data = _derive_compiled()
    terms = dict(data)
    cspec, _ = _derive(transport, radial, wall)
    (nu, T, e, num, phi, phiw), flat = cspec["partials"]
    eargs = espec["ymom"][0]
    nb, npart = len(BASE), len(FUNCTIONS) * len(ORDERS)
    b = dict(zip(BASE, eargs[:nb]))
    sin_t, cos_t = eargs[nb + npart :]
    u, T_y = sp.symbols("u T_y", real=True)

    def coefficient(name, field, c):
        for t in terms[name]:
            if (t[0], t[1], t[2], t[3], t[4]) == (field, 0, 0, c, 0):
                return espec[name][1][1 + t[5]]
        raise KeyError(f"{name} has no term d^{c} {field}/dy^{c}")

    p00 = flat[FUNCTIONS.index("p") * len(ORDERS) + ORDERS.index((0, 0))]
    mu00 = flat[FUNCTIONS.index("mu") * len(ORDERS) + ORDERS.index((0, 0))]
    u_y = sin_t / cos_t * p00 / mu00  # eq. (3.7)
    sub = dict(zip(eargs[nb : nb + npart], flat))
    sub.update({b["nu"]: nu, b["T"]: T, b["u"]: u, b["T_y"]: T_y, b["u_y"]: u_y})
    sub.update({b["nu_yy"]: 0, b["u_yy"]: 0, b["T_yy"]: 0})
    # y-momentum (eq. 3.5), affine in ν0'
    at0 = {b["nu_y"]: 0}
    nu_y = -espec["ymom"][1][0].xreplace(at0).xreplace(sub) / coefficient("ymom", "nu", 1).xreplace(
        at0
    ).xreplace(sub)
    # energy (eq. (3.6), docs/errata.md, item 1), affine in T0''
    at = {b["nu_y"]: nu_y}
    T_yy = -espec["energy"][1][0].xreplace(sub).xreplace(at) / coefficient("energy", "T", 2).xreplace(
        sub
    ).xreplace(at)
    args = (nu, u, T, T_y, e, num, phi, phiw, sin_t, cos_t)
    return {"rhs": (args, [nu_y / nu, u_y, T_yy])}

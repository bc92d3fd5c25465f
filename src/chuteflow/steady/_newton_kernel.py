"""Compiled rows of the steady Newton system: scaled residual and Jacobian coefficients.

At every Newton iterate :class:`~chuteflow.steady.newton.SteadyNewton` needs, at the nodes, the
scaled residual of each equation of its layout and the coefficients of its exact Jacobian: for
the unknowns s = ln ν0, u0, T0 and each derivative order c, the factor of d^c/dy^c in the row
(diag(d) + diag(e1) D1 + diag(e2) D2 per field). The numpy road
(:meth:`~chuteflow.steady.newton.SteadyNewton._residual`,
:meth:`~chuteflow.steady.newton.SteadyNewton._jacobian`) evaluates the compiled equations term
by term and applies the row scaling and the chain rule of ν = e^s in Python: ~30 small numpy
operations per row block and iterate, which at n = 64 cost four times the LU factorisation
itself.

Here the same quantities are stated symbolically, once, from the expressions that
:func:`chuteflow.equations.compiled_equations` evaluates (the residual R of an equation and
its coefficients ∂R/∂(d^c f/dy^c), :func:`chuteflow.equations._derive_compiled`), and
printed as one C loop over the nodes (:func:`chuteflow._ccode.cached_pointwise`, cached on
disk; no physics is written here). For an equation with row scale σ (1/ν0, 1/κ, 1/ν0(0)
or 1, :data:`SCALES`) the outputs at each node are, with the jets (f, f_y, f_yy) of each
field:

- ``R``: σ R;
- ``Lsum``: σ Σ_terms c · coefficient · d^c f/dy^c (the derivative with respect to the
  height y_max of the domain is −Lsum/y_max, as d^c/dy^c scales like y_max^{−c});
- (``s``, c), (``u``, c), (``T``, c) for c = 0, 1, 2: σ × the coefficient of d^c f/dy^c,
  with ν = e^s differentiated through (d ν_y/ds = ν_y + ν D1, d ν_yy/ds = ν_yy + 2 ν_y D1
  + ν D2) and the derivative of σ itself (dσ/ds, dσ/dT) added to the c = 0 entries.

The kernel's numbers equal the numpy road's to round-off (tests/steady/test_newton_kernel.py);
where no C compiler is available (or ``CHUTEFLOW_CCODE=off``) :func:`row_kernel` returns
None and the solver keeps the numpy road.
"""

from __future__ import annotations

import functools

from .._ccode import Pointwise, cached_pointwise
from .._codegen import lazy_module
from ..closures.model import FUNCTIONS, ORDERS
from ..equations import BASE, _derive_compiled

sp = lazy_module("sympy")

#: Row scales of the layout (:class:`~chuteflow.steady.newton.SteadyNewton`): ν-rows by
#: 1/ν0, T-rows by 1/κ, x-momentum rows by the constant 1/ν0(0), the top condition by 1.
SCALES = ("nu", "T", "u", "one")
#: The outputs per equation, in order: the scaled residual, the y_max sum, then
#: (unknown, derivative order) for s = ln ν0, u0, T0 and c = 0, 1, 2.
OUTPUTS: tuple = ("R", "Lsum") + tuple((f, c) for f in ("s", "u", "T") for c in range(3))
#: Index of each output within an equation's block of :data:`OUTPUTS`.
SLOT = {k: i for i, k in enumerate(OUTPUTS)}


@functools.cache
def row_kernel(layout: tuple[tuple[str, str], ...], vanishing: tuple[str, ...] = ()) -> Pointwise | None:
    """The compiled kernel of the rows ``layout`` = ((equation, scale kind), ...).

    ``vanishing``: closure functions that are identically zero for the closures at hand
    (:func:`chuteflow.closures.model.vanishing_functions`, e.g. ``"kappa_h"`` for the
    paper's closure): their terms are left out of the kernel (their partials are still
    arguments), so that the paper's closure runs the code it ran before κ_h existed.

    Called as ``kernel(*arrays, sin θ, cos θ, 1/ν0(0))`` with the 9 base jets
    (:data:`chuteflow.equations.BASE`) and the closures' partials (:data:`FUNCTIONS` ×
    :data:`ORDERS`) as arrays over the nodes; returns an array (len(layout) ×
    len(:data:`OUTPUTS`), nodes). None where compiled kernels are unavailable.
    """
    for _name, kind in layout:
        if kind not in SCALES:
            raise ValueError(f"scale kind {kind!r}: expected one of {SCALES}")
    return cached_pointwise(
        "steady_rows",
        repr((layout, vanishing)) if vanishing else repr(layout),
        lambda: _derive_rows(layout, vanishing),
        len(BASE) + len(FUNCTIONS) * len(ORDERS),
        sources=(__name__, "chuteflow.equations", "chuteflow.closures.model"),
    )


def _derive_rows(layout, vanishing=()):
    """(args, exprs) of :func:`row_kernel`."""
    spec, data = _derive_compiled()
    terms = dict(data)
    nb, npart = len(BASE), len(FUNCTIONS) * len(ORDERS)
    args = list(spec[layout[0][0]][0])
    b = dict(zip(BASE, args[:nb]))
    part = dict(zip(((f, o) for f in FUNCTIONS for o in ORDERS), args[nb : nb + npart]))
    if vanishing:
        zero = {part[(f, o)]: sp.S.Zero for f in vanishing for o in ORDERS}
        spec = {name: (a, [e.xreplace(zero) for e in ex]) for name, (a, ex) in spec.items()}
    inv_nu0 = sp.Symbol("inv_nu_floor", positive=True)
    jets = {
        "nu": (b["nu"], b["nu_y"], b["nu_yy"]),
        "u": (b["u"], b["u_y"], b["u_yy"]),
        "T": (b["T"], b["T_y"], b["T_yy"]),
    }
    kappa = part[("kappa", (0, 0))]
    exprs = []
    for name, kind in layout:
        eargs, ex = spec[name][:2]
        if list(eargs) != args:
            raise ValueError(f"{name}: its compiled arguments differ from the other equations'")
        res = ex[0]
        scale = {"nu": 1 / b["nu"], "T": 1 / kappa, "u": inv_nu0, "one": sp.S.One}[kind]
        out = dict.fromkeys(OUTPUTS, sp.S.Zero)
        for field, a, bx, c, d, index, k in terms[name]:
            if a or bx or d or k or field not in jets:
                continue  # a uniform steady state feels no t, x, z or |k| terms, v = w = 0
            cf = ex[1 + index]
            out["Lsum"] += c * cf * jets[field][c]
            if field == "nu":  # through ν = e^s
                nu, nu_y, nu_yy = jets["nu"]
                if c == 0:
                    out[("s", 0)] += cf * nu
                elif c == 1:
                    out[("s", 0)] += cf * nu_y
                    out[("s", 1)] += cf * nu
                else:
                    out[("s", 0)] += cf * nu_yy
                    out[("s", 1)] += 2 * cf * nu_y
                    out[("s", 2)] += cf * nu
            else:
                out[(field, c)] += cf
        row = [scale * res, scale * out["Lsum"]] + [scale * out[k] for k in OUTPUTS[2:]]
        # the derivative of the row scale itself (the Jacobian stays exact)
        if kind == "nu":  # d(1/ν)/ds = −1/ν
            row[SLOT[("s", 0)]] -= res * scale
        elif kind == "T":  # d(1/κ)/ds = −κ_ν ν/κ², d(1/κ)/dT = −κ_T/κ²
            row[SLOT[("s", 0)]] -= res * scale**2 * part[("kappa", (1, 0))] * b["nu"]
            row[SLOT[("T", 0)]] -= res * scale**2 * part[("kappa", (0, 1))]
        exprs += row
    return args + [inv_nu0], exprs


__all__ = ["OUTPUTS", "SCALES", "SLOT", "row_kernel"]

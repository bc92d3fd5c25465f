"""The rows of the steady Newton system (paper §3, eqs 3.5–3.7, 3.11–3.13): which compiled
equation is imposed at which nodes with which row scale, the terms a uniform steady state
feels, and the index plan of the compiled rows (:mod:`._newton_kernel`).
"""

from __future__ import annotations

import functools
from typing import Any, NamedTuple

import numpy as np

from ..closures.model import FUNCTIONS, ORDERS
from ..equations import BASE, TOP_OF, compiled_equations
from ._newton_kernel import OUTPUTS, SLOT, row_kernel

_FIELDS = ("nu", "u", "T")


#: Rows of the compiled outputs (:data:`._newton_kernel.SLOT`) by unknown (s = ln ν0, u0, T0:
#: the Jacobian's blocks 0, 1, 2) and derivative order.
_SLOTS = tuple(tuple(SLOT[(f, c)] for c in range(3)) for f in ("s", "u", "T"))


def _rows(v, sl: slice, m: int) -> np.ndarray:
    """The rows ``sl`` of a compiled coefficient or residual: an array over the m nodes,
    or a constant (the generated code returns scalars for node-independent terms)."""
    v = np.asarray(v, dtype=float)
    if v.ndim:
        return v[sl]
    return np.full(len(range(*sl.indices(m))), float(v))


@functools.cache
def _steady_terms(ce) -> tuple[tuple[int, str, int, int], ...]:
    """The terms of a compiled equation that a uniform steady state feels — no t, x, z
    dependence, v = w = 0, |k| = 0 — as (coefficient index, field, field's block, order)."""
    return tuple(
        (i, t.field, _FIELDS.index(t.field), t.c)
        for i, t in enumerate(ce.terms)
        if not (t.a or t.b or t.d or t.k or t.field in ("v", "w"))
    )


@functools.lru_cache(maxsize=32)
def _layout(n: int, integrated: bool) -> tuple[tuple, Any]:
    """The rows of :class:`~chuteflow.steady.newton.SteadyNewton` at n: ((equation, rows of the
    system, nodes it is
    imposed at, row-scaling kind), ...), and :func:`_u_prime_pattern` of them (None where
    u0' is not eliminated)."""
    m = n + 1
    # (equation, rows of the system, nodes it is imposed at, row-scaling kind)
    layout: tuple[tuple[str, slice, slice, str], ...] = (
        ("ymom", slice(1, m), slice(1, m), "nu"),
        ("floor_x", slice(m, m + 1), slice(0, 1), "u"),
        ("floor_energy", slice(2 * m, 2 * m + 1), slice(0, 1), "T"),
        ("energy", slice(2 * m + 1, 2 * m + n), slice(1, n), "T"),
        # T0' = 0 on top (eq. 3.13)
        (TOP_OF["T"], slice(2 * m + n, 2 * m + n + 1), slice(n, n + 1), "one"),
    )
    if integrated:
        # x-momentum in its once-integrated form, eq. (3.7): Σxy = −tanθ Σyy, i.e.
        # μ u0' = tanθ p at nodes 1..n. Integrating the x- and y-momentum balances from
        # y to ∞ with the stresses vanishing at infinity (eq. 2.15) gives it exactly,
        # so the weight of the dilute tail above y_max is kept: the result does not
        # depend on where the domain ends (a stress-free top at y_max instead would make
        # an O(ν_top) error, 1e-7 relative at ν_top = 1e-9). Being first order in u0 it
        # also avoids the D2 round-off (∝ n⁴) of (μ u0')' that otherwise sets the
        # residual floor.
        layout += (("xmom_integrated", slice(m + 1, 2 * m), slice(1, m), "u"),)
    else:
        # second-order form (μ u0')' + ν0 sinθ = 0 inside, u0' = 0 on top: used only for
        # the cold start, where its residual does not favour the collapsed layer (the
        # integrated form's does: every term vanishes with T0)
        layout += (
            ("xmom", slice(m + 1, m + n), slice(1, n), "u"),
            (TOP_OF["u"], slice(m + n, m + n + 1), slice(n, n + 1), "one"),
        )
    return layout, (_u_prime_pattern(layout, compiled_equations()) if integrated else None)


def _u_prime_pattern(layout, eqs):
    """Where u0' enters the steady rows once it is an unknown
    (:meth:`~chuteflow.steady.newton.SteadyNewton.step`):
    (diagonal, full), ``diagonal`` the (rows, first node) of the rows at nodes ≥ 1 other than
    eq. (3.7)'s, each holding u0' at its own node only; ``full`` the rows at the floor,
    holding u0'(0) = g0 · (u0(0), w). None where u0' cannot be eliminated: u0 enters a bulk
    row other than through u0' (Galilean invariance: the bulk equations hold velocity
    differences only; u0(0) appears in the floor rows), or the integrated x-momentum
    eq. (3.7) is not among the rows."""
    if not any(name == "xmom_integrated" for name, *_ in layout):
        return None
    diagonal: list[tuple[slice, int]] = []
    full: list[int] = []
    for name, rows, sl, _ in layout:
        orders = {c for _i, fname, _k, c in _steady_terms(eqs[name]) if fname == "u"}
        node0 = sl == slice(0, 1)
        if not orders <= ({0, 1} if node0 else {1}):
            return None
        if not orders or name == "xmom_integrated":
            continue
        if node0:
            full += list(range(rows.start, rows.stop))
        else:
            diagonal.append((rows, sl.start))
    return diagonal, full


class _RowPlan(NamedTuple):
    """Index arrays of the compiled road of :class:`~chuteflow.steady.newton.SteadyNewton` for one
    layout and n."""

    products: tuple  # (r0, r1, j0, j1, field k, order c, first) of the terms c ≥ 1
    products_w: tuple  # the same without those of u0 (eliminated: SteadyNewton.step)
    n_base: int  # base jets among the kernel's arguments
    n_args: int  # all its arguments (jets and closures' partials)
    n_out: int  # its outputs (layout × OUTPUTS, per node)
    offsets: np.ndarray  # byte offsets of the argument rows (uintp)
    closure_args: np.ndarray  # the rows of ν and T (the closures' arguments)
    gather: np.ndarray  # (OUTPUTS, rows) indices into the outputs (the appended zero: none)
    node: np.ndarray  # the node of each row (0 for the unknowns' own conditions)
    rows: np.ndarray  # rows of equations
    diagonal: tuple  # flat indices of (row, field k's column at the row's node), rows ``rows``
    bulk: np.ndarray  # rows of equations at nodes ≥ 1
    diagonal_w: np.ndarray  # flat indices of (row, w at its node), rows ``bulk``
    floor: np.ndarray  # rows of equations at node 0


@functools.lru_cache(maxsize=16)
def _row_plan(layout_key: tuple, n: int) -> _RowPlan:
    m = n + 1
    N, K = 3 * m + 1, len(OUTPUTS)
    n_base, n_args = len(BASE), len(BASE) + len(FUNCTIONS) * len(ORDERS)
    n_out = len(layout_key) * K * m
    gather = np.full((K, N), n_out, dtype=np.intp)
    node = np.zeros(N, dtype=np.intp)
    has = np.zeros(N, dtype=bool)
    products: list[tuple[int, int, int, int, int, int, bool]] = []
    for r0, r1, j0, j1, orders in layout_key:
        for k, c in orders:
            if c:
                first = not any(p[:2] == (r0, r1) and p[4] == k for p in products)
                products.append((r0, r1, j0, j1, k, c, first))
    products_w = tuple(p for p in products if p[4] != 1)
    for e, (r0, r1, j0, j1, _orders) in enumerate(layout_key):
        r, j = np.arange(r0, r1), np.arange(j0, j1)
        node[r], has[r] = j, True
        for k in range(K):
            gather[k, r] = (e * K + k) * m + j
    rows = np.nonzero(has)[0]
    bulk = np.nonzero(has & (node >= 1))[0]
    floor = np.nonzero(has & (node == 0))[0]
    return _RowPlan(
        tuple(products),
        products_w,
        n_base,
        n_args,
        n_out,
        np.arange(n_args, dtype=np.uintp) * np.uintp(8 * m),
        np.array([BASE.index("nu"), BASE.index("T")]),
        gather,
        node,
        rows,
        tuple(rows * N + k * m + node[rows] for k in range(3)),
        bulk,
        bulk * N + m + node[bulk],
        floor,
    )


def _orders(ce) -> tuple[tuple[int, int], ...]:
    """(field block, derivative order) of the unknowns s = ln ν0, u0, T0 that the rows of
    ``ce`` hold (:mod:`._newton_kernel`: through ν = e^s, d^c ν/dy^c brings s's orders
    0…c)."""
    out = set()
    for _i, fname, k, c in _steady_terms(ce):
        out |= {(k, cc) for cc in range(c + 1)} if fname == "nu" else {(k, c)}
    return tuple(sorted(out))


@functools.lru_cache(maxsize=32)
def _road_parts(n: int, integrated: bool, closures: tuple):
    """(closures' kernel, rows' kernel, plan) of the compiled road of
    :class:`~chuteflow.steady.newton.SteadyNewton`
    for the closure objects ``closures``, or None where compiled kernels are unavailable."""
    from ..closures.model import _compiled_c, vanishing_functions

    layout = _layout(n, integrated)[0]
    rows = row_kernel(tuple((name, kind) for name, _r, _s, kind in layout), vanishing_functions(*closures))
    kernel = _compiled_c(*closures) if rows is not None else None
    if rows is None or kernel is None:
        return None
    eqs = compiled_equations()
    key = tuple((r.start, r.stop, sl.start, sl.stop, _orders(eqs[name])) for name, r, sl, _kind in layout)
    return kernel, rows, _row_plan(key, n)

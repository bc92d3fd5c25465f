"""Compiled scatter of the stability operator's terms into its dense pieces.

:meth:`StabilityOperator._assemble <chuteflow.stability.operator.StabilityOperator>` puts
every term of every row equation, coefficient × d^c/dy^c of a field (:mod:`chuteflow.equations`,
compiled), into the matrix it belongs to (the piece A_{b,d}, B or K): on the numpy road ~80
terms a 2D operator, each a few small numpy operations (~10 µs apiece: a third of the
operator's cost at N = 48), and then the equilibrated copies R P C of every piece.

Here the same arithmetic runs as one C loop (:func:`chuteflow._ccode.cached_library`, the
fixed source below, built once and cached on disk): for each term, in the numpy road's order,
e = coefficient × row scale at each node, then ``target[row, column] += e`` (c = 0: the
field's own node) or ``+= e · D_c[node, j]`` for every column j (``-=`` for the α terms,
which go to B with a minus sign), and the equilibrated copy as (P · r_i) · c_j. Every
product and every sum is the one numpy computes, in the same order, without contraction
(``-ffp-contract=off``): the pieces are the numpy road's bit for bit
(tests/stability/test_assembly.py; also those of the term-by-term assembly this replaced,
checked on 84 operators). The numpy road stays where no C compiler is available (or
``CHUTEFLOW_CCODE=off``): :func:`scatter_kernel` then returns None.

The plan (which coefficient goes where, :func:`term_plan`) depends only on the equations'
term structure, the fields and N; it is built once per (N, fields) and is the one statement
of where each term goes: both roads execute it (the numpy one through
:attr:`TermPlan.where`). That the plan routes each term correctly is checked independently
of it, by an eigenvector of the assembled pencil satisfying every compiled equation term by
term (tests/stability/test_operator.py).
"""

from __future__ import annotations

import ctypes
import functools
from typing import NamedTuple

import numpy as np

from .._ccode import cached_library
from ..equations import TOP_OF, compiled_equations

_SOURCE = r"""
/* entries: nent rows of 9 longs (coefficient row, scale row, order c, target, sign,
   first row, number of rows, first node, first column) */
void cf_scatter(long nent, const long *ent, const double *coef, const double *scale,
                const double *D1, const double *D2, long m, long M, double *const *targets)
{
    long k, i, j;
    for (k = 0; k < nent; k++) {
        const long *p = ent + 9 * k;
        const double *cf = coef + p[0] * m, *sc = scale + p[1] * m;
        const long c = p[2], sign = p[4], row0 = p[5], nrow = p[6], node0 = p[7], col0 = p[8];
        double *T = targets[p[3]];
        for (i = 0; i < nrow; i++) {
            const long node = node0 + i;
            const double e = cf[node] * sc[node];
            double *t = T + (row0 + i) * M + col0;
            if (c == 0) {
                if (sign > 0) t[node] = t[node] + e; else t[node] = t[node] - e;
            } else {
                const double *d = (c == 1 ? D1 : D2) + node * m;
                if (sign > 0) { for (j = 0; j < m; j++) t[j] = t[j] + e * d[j]; }
                else { for (j = 0; j < m; j++) t[j] = t[j] - e * d[j]; }
            }
        }
    }
}

/* out[i, j] = (P[i, j] * r[i]) * c[j] */
void cf_equilibrate(long M, const double *P, const double *r, const double *c, double *out)
{
    long i, j;
    for (i = 0; i < M; i++) {
        const double ri = r[i];
        const double *p = P + i * M;
        double *o = out + i * M;
        for (j = 0; j < M; j++) o[j] = (p[j] * ri) * c[j];
    }
}
"""


#: numpy's integer type of the C ``long`` the kernel reads its plan in.
C_LONG = np.dtype(f"i{ctypes.sizeof(ctypes.c_long)}")


class ScatterKernel(NamedTuple):
    scatter: ctypes._CFuncPtr  # type: ignore[name-defined]
    equilibrate: ctypes._CFuncPtr  # type: ignore[name-defined]


@functools.cache
def scatter_kernel() -> ScatterKernel | None:
    """The compiled scatter and equilibration (None: the numpy road)."""
    lib = cached_library("operator_scatter", "v1", lambda: _SOURCE, sources=(__name__,))
    if lib is None:
        return None
    vp, lg = ctypes.c_void_p, ctypes.c_long
    scatter, equilibrate = lib.cf_scatter, lib.cf_equilibrate
    scatter.argtypes = [lg, vp, vp, vp, vp, vp, lg, lg, vp]
    scatter.restype = None
    equilibrate.argtypes = [lg, vp, vp, vp, vp]
    equilibrate.restype = None
    return ScatterKernel(scatter, equilibrate)


class TermPlan(NamedTuple):
    """Where the terms of one operator layout go (:func:`term_plan`)."""

    equations: tuple[str, ...]  # distinct equations, in order of first use
    offsets: tuple[int, ...]  # first coefficient row of each equation
    n_coef: int  # coefficient rows in all
    uses: tuple[tuple[str, str], ...]  # (equation, scale kind) per scale row
    keys: tuple[tuple[int, int], ...]  # the pieces A_{b,d}, in order of first appearance
    entries: np.ndarray  # (terms, 9) int: see the C source
    k_rows: tuple[int, ...]  # rows holding |k| terms (the top conditions), sorted
    where: tuple  # per entry: (coefficient row, scale row, nodes, target, sign, index, order)


#: Scale kinds of a row equation: interior nodes (an array over the nodes), the floor row
#: (one number), the top row (1).
BULK, FLOOR, TOP = "bulk", "floor", "top"


@functools.lru_cache(maxsize=32)
def term_plan(n: int, fields: tuple[str, ...], rows_of: tuple[tuple, tuple]) -> TermPlan:
    """The scatter plan of the operator on N = ``n`` with ``fields``: for each term of each
    row equation, in the order the operator was always assembled in, its coefficient row,
    scale row, order, target (0 … len(keys) − 1 the pieces, then B, then K), sign and rows,
    nodes and columns. ``rows_of``: the (field, equation) pairs of the bulk rows and of the
    floor rows (:data:`chuteflow.stability.operator.BULK_OF`, ``FLOOR_OF``).

    Each field's block has its bulk equation on the interior nodes, α terms to
    B with a minus sign (residuals are N(X) − B ∂_t X); its floor row and its
    top row, the far-field condition (ν̂' = −(cos θ/T0) ν̂, f̂' = −|k| f̂ for the others, whose
    |k| terms go to K), without α terms. An undifferentiated term (c = 0) holds the field's
    own node only. Raises NotImplementedError where a term does not fit the pencil."""
    eqs = compiled_equations()
    bulk, floor = dict(rows_of[0]), dict(rows_of[1])
    m = n + 1
    three_d = "w" in fields
    col = {f: i * m for i, f in enumerate(fields)}
    equations: list[str] = []
    offsets: list[int] = []
    total = 0
    keys: list[tuple[int, int]] = [(0, 0)]
    raw: list[tuple] = []  # (coef row, scale row, c, target key, sign, row0, nrow, node0, col0)
    uses: list[tuple[str, str]] = []
    k_rows: set[int] = set()

    def add(name, kind, node0, nrow, row0, keep_alpha):
        nonlocal total
        if name not in equations:
            equations.append(name)
            offsets.append(total)
            total += len(eqs[name].terms)
        off = offsets[equations.index(name)]
        s_row = len(uses)
        uses.append((name, kind))
        for i, t in enumerate(eqs[name].terms):  # coefficient i of the compiled output
            if t.field not in col or (t.d and not three_d):
                continue
            target: object
            sign = 1
            if t.a:
                if (t.a, t.b, t.c, t.d, t.k) != (1, 0, 0, 0, 0):
                    raise NotImplementedError(f"α enters {name} as {t}: not a pencil")
                if not keep_alpha:
                    continue
                target, sign = "B", -1
            elif t.k:
                if (t.k, t.b, t.d) != (1, 0, 0):
                    raise NotImplementedError(f"|k| enters {name} as {t}: not linear")
                target = "K"
                k_rows.update(range(row0, row0 + nrow))
            else:
                target = (t.b, t.d)
                if target not in keys:
                    keys.append(target)
            raw.append((off + i, s_row, t.c, target, sign, row0, nrow, node0, col[t.field]))

    for i, f in enumerate(fields):
        r0 = i * m
        add(bulk[f], BULK, 1, m - 2, r0 + 1, True)
        add(floor[f], FLOOR, 0, 1, r0, False)
        add(TOP_OF[f], TOP, m - 1, 1, r0 + m - 1, False)
    index: dict[object, int] = {key: j for j, key in enumerate(keys)}
    index["B"], index["K"] = len(keys), len(keys) + 1
    entries = np.array([(*r[:3], index[r[3]], *r[4:]) for r in raw], dtype=C_LONG).reshape(-1, 9)
    entries.flags.writeable = False
    where = []  # the numpy road's view of the entries (stability.operator._scatter_numpy)
    for cr, sr, c, t, sign, row0, nrow, node0, col0 in entries.tolist():
        if c == 0:  # the field's own node: the diagonal of the block
            at: tuple = (np.arange(row0, row0 + nrow), col0 + np.arange(node0, node0 + nrow))
        else:
            at = (slice(row0, row0 + nrow), slice(col0, col0 + m))
        where.append((cr, sr, slice(node0, node0 + nrow), t, sign, at, c))
    return TermPlan(
        tuple(equations),
        tuple(offsets),
        total,
        tuple(uses),
        tuple(keys),
        entries,
        tuple(sorted(k_rows)),
        tuple(where),
    )

"""The compiled scatter of the stability operator's terms (chuteflow.stability._assembly).

Source: the numpy road of the same assembly (operator._scatter_numpy and the equilibration
_scaled without the kernel), which applies the terms of the plan one by one. The kernel performs the same
products and sums in the same order without floating-point contraction, so the two must
agree bit for bit (not merely to round-off: the solvers that
track a branch at the edge of the dilute top's continuum are sensitive to round-off, see
ChuteModel.evaluate), for every piece, B, K, the equilibrated copies, the row scales and the
residuals, in 2D and 3D, on the mapped and the plain grid. The plan itself (which term goes
where) is checked independently of both roads by tests/stability/test_operator.py
(test_pencil_solves_the_raw_linearised_equations: an eigenvector of the assembled pencil
satisfies each compiled equation, term by term, at every node).
"""

from __future__ import annotations

import importlib

import numpy as np
import pytest

from chuteflow import _ccode
from chuteflow.equations import TOP_OF
from chuteflow.stability._assembly import scatter_kernel, term_plan
from chuteflow.steady import solve_steady

operator = importlib.import_module("chuteflow.stability.operator")

pytestmark = pytest.mark.skipif(_ccode.compiler() is None, reason="no C compiler: only the numpy road")

_POINTS = [(16.0, 0.08), (14.0, 0.05), (17.5, 0.11)]


@pytest.fixture(scope="module")
def flows():
    return {p: solve_steady(*p) for p in _POINTS}


def _bits(a):
    a = np.ascontiguousarray(a, dtype=float)
    return a.shape, a.view(np.uint64).tobytes()


def _state(op):
    """Everything the assembly produces, as exact bit patterns."""
    out = {("row_scale",): _bits(op.row_scale), ("B",): _bits(op.B), ("B_eq",): _bits(op.B_eq)}
    out[("keys",)] = tuple(op.pieces)
    for key in op.pieces:
        out[("piece", key)] = _bits(op.pieces[key])
        out[("piece_eq", key)] = _bits(op._pieces_eq[key])
    K, Keq = op._K_sparse, op._K_eq
    out[("K", "rows")] = tuple(K[0].tolist())
    out[("K", "cols")] = tuple(K[1].tolist())
    out[("K", "vals")] = _bits(K[2])
    out[("K", "vals_eq")] = _bits(Keq[2])
    out[("residual names",)] = tuple(op.residuals)
    for name, r in op.residuals.items():
        out[("residual", name)] = _bits(r)
    return out


@pytest.mark.parametrize("point", _POINTS)
@pytest.mark.parametrize("n", [30, 48])
@pytest.mark.parametrize("kind", ["mapped", "plain", "3d"])
def test_compiled_scatter_equals_the_numpy_road_bit_for_bit(flows, monkeypatch, point, n, kind):
    assert scatter_kernel() is not None
    kw = {"mapped": {"mapped": True}, "plain": {"mapped": False}, "3d": {"three_d": True}}[kind]
    flow = flows[point]
    numpy_calls = []
    real = operator._scatter_numpy

    def spy(*a):
        numpy_calls.append(1)
        return real(*a)

    monkeypatch.setattr(operator, "_scatter_numpy", spy)
    fast = operator.StabilityOperator(flow, n, **kw)
    assert not numpy_calls  # the compiled road
    monkeypatch.setattr(operator, "scatter_kernel", lambda: None)
    slow = operator.StabilityOperator(flow, n, **kw)
    assert numpy_calls  # the numpy road
    a, b = _state(fast), _state(slow)
    assert a.keys() == b.keys()
    different = [k for k in a if a[k] != b[k]]
    assert not different


def test_plan_counts_every_term_once():
    """The plan holds each applicable term of each row equation once: 2D ν̂, û, v̂, T̂ blocks
    (bulk, floor and top rows), no k_z terms, and α terms only in the bulk rows."""
    eqs = operator.compiled_equations()
    fields = operator.FIELDS_2D
    plan = term_plan(40, fields, operator._ROWS_OF)
    expected = 0
    for f in fields:
        for name, bulk in (
            (operator.BULK_OF[f], True),
            (operator.FLOOR_OF[f], False),
            (TOP_OF[f], False),
        ):
            expected += sum(1 for t in eqs[name].terms if t.field in fields and not t.d and (bulk or not t.a))
    assert len(plan.entries) == expected
    assert plan.keys[0] == (0, 0)
    assert all(d == 0 for _b, d in plan.keys)
    # the top rows carry the |k| terms: the last row of every block but ν̂'s
    m = 41
    assert plan.k_rows == tuple(i * m + m - 1 for i in range(1, len(fields)))

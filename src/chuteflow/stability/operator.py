"""The linear stability operator on a Chebyshev grid (paper §4.1, Appendix A).

Perturbations ∝ exp(αt + i k_x x + i k_z z) (eq. (4.4); k_z = 0 in the paper) of a steady
flow satisfy A V = α B V. Every coefficient comes from the compiled linearisation of
:mod:`chuteflow.equations`; nothing of Appendix A is retyped here. A term (a, b, c, d) of an
equation, coefficient × α^a (ik_x)^b (ik_z)^d d^c/dy^c, goes to B (a = 1, with a minus sign:
residuals are N(X) − B∂_tX) or to the piece A_{b,d} of

    A(k_x, k_z) = Σ_{b,d} (ik_x)^b (ik_z)^d A_{b,d} + |k| K,

where K holds the |k| terms of the top decay conditions. The N + 1 collocation nodes per field
on [0, y_max] are Chebyshev–Lobatto nodes of a computational variable mapped by a sinh onto
y, clustered at the edge of the dense layer (:func:`layer_map`: ~2× fewer nodes
than the plain grid for the paper's 1e-7 at k ≤ 0.02; ``mapped=True``, what the solvers'
operator cache builds in 2D), or of the plain Chebyshev grid (the default). Rows:

- ν̂ block: the mass balance (eq. 2.1) at the interior nodes; the y-momentum balance at the
  floor y = 0 (an extra condition); ν̂' = −(cos θ/T0) ν̂ at the top y = y_max (extra);
- û block: the x-momentum balance; the floor condition eq. (2.9) (eq. A 5); û' = −k û;
- v̂ block: the y-momentum balance; v̂ = 0 at the floor (impermeable, docs/errata.md);
  v̂' = −k v̂;
- ŵ block (3D): the z-momentum balance; eq. (2.9), z component; ŵ' = −k ŵ;
- T̂ block: the energy balance (eq. 2.3); eq. (2.10) (eq. A 6); T̂' = −k T̂.

Momentum rows are divided by μ0(y) and energy rows by κ0(y), so that every row is O(D²)
from the floor to the dilute top; B is then diagonal with entries 1 (mass), ν0/μ0
(momentum) and 3ν0/(2κ0) (energy) on interior rows and 0 on boundary rows, whose
eigenvalues are infinite. The α term of the y-momentum row at the floor multiplies v̂(0),
which the impermeability row sets to zero, so dropping it changes nothing. The top rows are
the far-field conditions of :func:`chuteflow.equations.far_field_conditions`, compiled like
the bulk equations; a term with |k| (k = √(k_x² + k_z²)) goes to K.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from ..equations import Term, arguments, compiled_equations
from ..errors import ParameterError
from ..spectral import ChebyshevGrid, MappedChebyshevGrid, layer_edge_map
from ..steady import SteadyFlow
from ..steady.result import cached_per_flow
from ._assembly import BULK, FLOOR, scatter_kernel, term_plan

FIELDS_2D = ("nu", "u", "v", "T")
FIELDS_3D = ("nu", "u", "v", "w", "T")
#: Bulk equation of each field's row block.
BULK_OF = {"nu": "mass", "u": "xmom", "v": "ymom", "w": "zmom", "T": "energy"}
#: Floor row of each block (the ν̂ block carries the y-momentum balance at the floor).
FLOOR_OF = {"nu": "ymom", "u": "floor_x", "v": "floor_v", "w": "floor_z", "T": "floor_energy"}

#: The row equations of each block, as :func:`~chuteflow.stability._assembly.term_plan` takes them.
_ROWS_OF = (tuple(sorted(BULK_OF.items())), tuple(sorted(FLOOR_OF.items())))

N_RANGE = (8, 1000)

#: Weight β of the sinh part of the map, y = (1 − β) y_linear + β y_sinh.
MAP_BLEND = 1.0


@cached_per_flow  # every operator of a flow asks for it
def layer_map(flow: SteadyFlow) -> tuple[float, float] | None:
    """Centre y_c and width ε of the sinh map of the stability grid, or None (plain grid).

    The large resolutions the plain Chebyshev grid needs (N ~ 200–480 for the paper's 1e-7)
    come from an interior layer at the edge of the dense flow, y ≈ h (where ν0 has fallen
    to 1 % of its peak, ν0 ~ 1e-3), across which the transport coefficients change from
    their dense to their dilute form over a fraction of the density scale height
    T0/cos θ of the dilute top (ν0 ∝ exp(−y cos θ/T0) there). The map
    y = y_c + ε sinh(s), s linear in the Chebyshev variable, clusters the nodes there with

        y_c = h,    ε = :data:`~chuteflow.spectral.LAYER_MAP_WIDTH` × T0(h)/cos θ    (= 2 T0(h)/cos θ),

    the map of :func:`chuteflow.spectral.layer_edge_map`, which the steady grid uses too
    (:func:`chuteflow.steady.grid.layer_grid_map`, centred there at its sampled edge), and
    still reaches the floor and the top with Chebyshev clustering. The factor 2 is chosen
    from the resolution N at which the least-stable mode passes the paper's tests (drift and
    tail < 1e-7; ``benchmarks/probes/map_width.py``), N on the ladder 32, 40, 48, 56, 64, 80,
    100, 125, … for the plain grid and factors 0.45, 1, 2:

    ==========  =====  ====  ===  ===
    point, k    plain  0.45  1    2
    ==========  =====  ====  ===  ===
    P1, 0.005   80     64    56   48
    P4, 0.005   80     48    40   40
    P5, 0.005   100    80    80   64
    P1, 0.5     100    125   125  100
    P4, 0.5     40     56    48   40
    P1, 3       200    >256  256  256
    P4, 3       48     64    56   56
    ==========  =====  ====  ===  ===

    A narrow map (0.45, the optimum for a 1e-9 branch eigenvalue at small k) starves the
    dense layer of nodes at k ≳ 0.5; the factor 2 gains at small k and loses little beyond.
    The fallback rule is the shared one: None (the plain grid) where ε exceeds half of y_max
    (a broad layer without a sharp edge; at the paper's eight points ε/y_max = 0.085–0.11)
    or h is not inside (0, y_max).
    """
    T_h = float(flow.grid.interpolate(flow.T, np.array([float(flow.h)]))[0])
    return layer_edge_map(float(flow.h), T_h, flow.theta, float(flow.y_max))


def stability_grid(flow: SteadyFlow, n: int, mapped: bool = True) -> ChebyshevGrid:
    """The collocation grid of the stability problem of ``flow`` with N = ``n`` intervals on
    [0, y_max]: sinh-mapped around the layer's edge (:func:`layer_map`, default) or the
    plain Chebyshev grid (``mapped=False``, the paper's discretisation, kept for checks;
    also where :func:`layer_map` gives no map)."""
    edge_map = layer_map(flow) if mapped else None
    if edge_map is not None:
        yc, eps = edge_map
        return MappedChebyshevGrid(n, 0.0, flow.y_max, yc, eps, MAP_BLEND)
    return ChebyshevGrid(n, 0.0, flow.y_max)


def base_on_grid(flow: SteadyFlow, y: np.ndarray) -> dict[str, np.ndarray]:
    """Jets ν0, ν0', ν0'', u0, …, T0'' (keys of :data:`chuteflow.equations.BASE`) at ``y``.

    Derivatives are taken on the flow's own grid, where its Chebyshev series is converged,
    and then interpolated spectrally, so they are exact on any target grid. ν0 goes through
    ln ν0, which keeps relative accuracy where ν0 ~ 1e-9.
    """
    g = flow.grid
    d = flow.derivatives()
    ln = np.asarray(flow.log_nu)
    # one Clenshaw evaluation of all nine series at once
    stack = np.stack([ln, g.D @ ln, g.D2 @ ln, flow.u, d["u_y"], d["u_yy"], flow.T, d["T_y"], d["T_yy"]])
    vals = g.interpolate(stack, np.asarray(y))
    s, s1, s2 = vals[0], vals[1], vals[2]
    nu = np.exp(s)
    return {
        "nu": nu,
        "nu_y": nu * s1,
        "nu_yy": nu * (s2 + s1**2),
        "u": vals[3],
        "u_y": vals[4],
        "u_yy": vals[5],
        "T": vals[6],
        "T_y": vals[7],
        "T_yy": vals[8],
    }


def equation_terms(
    flow: SteadyFlow,
    name: str,
    fields: dict[str, np.ndarray],
    kx: float,
    kz: float = 0.0,
    alpha: complex = 0.0,
    *,
    grid: ChebyshevGrid | None = None,
) -> list[tuple[Term, np.ndarray]]:
    """Each term of one linearised equation, applied to a normal-mode perturbation.

    Parameters
    ----------
    flow : SteadyFlow
        The base state.
    name : str
        An equation of :func:`chuteflow.equations.compiled_equations` ("mass", "xmom", …).
    fields : dict
        Field name → complex nodal values f̂ on the N + 1 nodes of the grid (N = len − 1),
        e.g. :attr:`Mode.fields <chuteflow.stability.Mode>`. Terms acting on a field that is
        absent (ŵ of a 2D mode) are left out.
    kx, kz : float
        Wavevector of the mode exp(αt + i k_x x + i k_z z).
    alpha : complex
        Its eigenvalue α (used by the terms with ∂_t).
    grid : ChebyshevGrid, optional
        The grid the nodal values live on (:attr:`Mode.grid <chuteflow.stability.Mode>`);
        default the mapped stability grid :func:`stability_grid` of ``flow``.

    Returns
    -------
    list of (Term, ndarray)
        coefficient × α^a (ik_x)^b (ik_z)^d |k|^k d^c f̂/dy^c at every node, for every term
        of the equation; their sum is the equation's linearised residual, which vanishes at
        the interior nodes for an eigenmode of a bulk equation.
    """
    first = next(iter(fields.values()))
    g = stability_grid(flow, len(first) - 1) if grid is None else grid
    if len(g.y) != len(first):
        raise ParameterError(f"grid: {len(g.y)} nodes, but the fields have {len(first)} values")
    base = base_on_grid(flow, g.y)
    part = flow.model.evaluate(base["nu"], base["T"])
    th = math.radians(flow.theta)
    ce = compiled_equations()[name]
    _, coefs = ce.evaluate(base, part, math.sin(th), math.cos(th))
    dmat = (None, g.D, g.D2)
    k = math.hypot(kx, kz)
    out = []
    for t, cf in zip(ce.terms, coefs):
        if t.field not in fields:
            continue
        f = np.asarray(fields[t.field])
        df = f if t.c == 0 else dmat[t.c] @ f
        fac = alpha**t.a * (1j * kx) ** t.b * (1j * kz) ** t.d * k**t.k
        out.append((t, np.broadcast_to(cf, g.y.shape) * fac * df))
    return out


@dataclass(frozen=True, eq=False)
class Pencil:
    """A V = α B V at one wavevector, with what is needed to interpret V.

    Attributes
    ----------
    A : ndarray, complex, (M, M)
        Operator at (k_x, k_z); M = (N + 1) × number of fields. Built on first access.
    B : ndarray, real, (M, M)
        Diagonal mass matrix (zero on boundary rows).
    kx, kz : float
        Wavevector components; :attr:`k` = |k|.
    grid : ChebyshevGrid
        Collocation grid on [0, y_max] (a :class:`~chuteflow.spectral.MappedChebyshevGrid`
        by default).
    fields : tuple of str
        Order of the field blocks of V: ("nu", "u", "v", "T"), or with "w" in 3D.
    flow : SteadyFlow
        The base state.
    operator : StabilityOperator
        The operator this pencil was evaluated from.
    """

    kx: float
    kz: float
    operator: StabilityOperator = field(repr=False)

    @property
    def grid(self) -> ChebyshevGrid:
        return self.operator.grid

    @property
    def fields(self) -> tuple:
        return self.operator.fields

    @property
    def flow(self) -> SteadyFlow:
        return self.operator.flow

    @cached_property
    def A(self) -> np.ndarray:
        return self.operator.matrix(self.kx, self.kz)

    @property
    def B(self) -> np.ndarray:
        return self.operator.B

    @property
    def k(self) -> float:
        return math.hypot(self.kx, self.kz)

    @property
    def n(self) -> int:
        return self.grid.n

    @property
    def size(self) -> int:
        return self.operator.size

    def slices(self) -> dict[str, slice]:
        """Field name → slice of its block in V."""
        m = self.grid.n + 1
        return {f: slice(i * m, (i + 1) * m) for i, f in enumerate(self.fields)}

    def split(self, V: np.ndarray) -> dict[str, np.ndarray]:
        """Field name → nodal values, for a vector V (or the leading axis of an array)."""
        return {f: V[s] for f, s in self.slices().items()}

    @cached_property
    def _equilibrated(self):
        op = self.operator
        return op.matrix(self.kx, self.kz, equilibrated=True), op.B_eq

    def equilibrated(self) -> tuple[np.ndarray, np.ndarray]:
        """(R A C, R B C) with the operator's diagonal equilibration R, C.

        Same eigenvalues; an eigenvector W of the equilibrated pencil is V = C W here
        (:meth:`unscale`). All solvers of this package work on it.
        """
        return self._equilibrated

    def unscale(self, W: np.ndarray) -> np.ndarray:
        """Eigenvector(s) of the equilibrated pencil → of (A, B)."""
        return (self.operator.col_eq * W.T).T


def _scaled(kernel, P: np.ndarray, r: np.ndarray, c: np.ndarray) -> np.ndarray:
    """(P · r_i) · c_j (row and column scales): by the compiled kernel in one pass
    (:mod:`._assembly`), or without one (``kernel`` None) in numpy with one temporary instead
    of two; the same numbers."""
    if kernel is None:
        out = np.multiply(P, r[:, None])
        out *= c[None, :]
        return out
    out = np.empty_like(P)
    kernel.equilibrate(P.shape[0], P.ctypes.data, r.ctypes.data, c.ctypes.data, out.ctypes.data)
    return out


def _scatter_numpy(where, coef, scale, D1, D2, targets) -> None:
    """The compiled scatter's loop (:mod:`._assembly`) in numpy, term by term (the plan's
    :attr:`~chuteflow.stability._assembly.TermPlan.where`): e = coefficient × row scale at
    the term's nodes, added (subtracted for the α terms) at the field's own node (c = 0) or
    as e · D_c[node] across the field's columns."""
    for cr, sr, nodes, t, sign, at, c in where:
        e = coef[cr, nodes] * scale[sr, nodes]
        blk = e if c == 0 else e[:, None] * (D1 if c == 1 else D2)[nodes]
        if sign > 0:
            targets[t][at] += blk
        else:
            targets[t][at] -= blk


class StabilityOperator:
    """The linear operator of one steady flow on one collocation grid, for any wavevector.

    Built once (coefficients evaluated, rows assembled by pieces); :meth:`matrix` then
    costs a few matrix additions.

    Parameters
    ----------
    flow : SteadyFlow
        Base state.
    n : int
        Number of Chebyshev intervals N (N + 1 nodes per field).
    three_d : bool
        Include ŵ and the z-momentum balance (required for k_z ≠ 0).
    mapped : bool
        Collocate on the sinh-mapped grid clustered at the layer's edge (True; see
        :func:`layer_map`) or on the plain Chebyshev grid of the paper (False, the
        constructor's default, which the 3D code and its checks rely on). The solvers of
        :mod:`chuteflow.stability` get their operators from an
        :class:`~chuteflow.stability.OperatorCache`, which builds the two-dimensional ones
        mapped by default. Three-dimensional operators stay on the plain grid: the
        transverse long-wave coefficient α2z, a k → 0 quantity that feels the dilute top,
        converges ~5× slower on the mapped grid (relative change N = 80 → 100: 4e-5 against
        < 1e-5).

    Attributes
    ----------
    pieces : dict
        (b, d) → real matrix A_{b,d}, the coefficient of (ik_x)^b (ik_z)^d.
    K : ndarray
        Coefficient of |k| (the top conditions û' = −kû, v̂' = −kv̂, ŵ' = −kŵ, T̂' = −kT̂).
    B : ndarray
        Mass matrix, independent of k.
    row_scale : ndarray
        Factor each row of the raw linearised equations was multiplied by.
    base : dict
        The base-state jets on :attr:`grid`.
    residuals : dict
        Steady residual of each equation on the grid (how well the base state solves it).
    """

    def __init__(self, flow: SteadyFlow, n: int, *, three_d: bool = False, mapped: bool = False):
        if not isinstance(flow, SteadyFlow):
            raise ParameterError(f"flow: expected a SteadyFlow, got {type(flow).__name__}")
        n = validate_n(n)
        self.flow, self.n, self.three_d, self.mapped = flow, n, bool(three_d), bool(mapped)
        self.fields = FIELDS_3D if three_d else FIELDS_2D
        self.grid = stability_grid(flow, n, self.mapped)
        self._assemble()
        #: finite eigenvalues of this operator's pencils by (k, kz), from dense QZ
        #: (:func:`~chuteflow.stability.modes.spectrum`): on a ladder of resolutions the
        #: drift check at N' = 0.8 N is the rung below, whose eigenvalues are known
        self.qz_eigenvalues: dict[tuple[float, float], np.ndarray] = {}
        #: results that solvers memoise on this operator (deterministic functions of it:
        #: the k = 0 null vectors, the branch tracker's continuation steps from k = 0; see
        #: :class:`~chuteflow.stability.BranchTracker`), dropped with the operator
        self.memo: dict = {}

    def remember_eigenvalues(self, k: float, kz: float, w: np.ndarray) -> None:
        """Keep the finite eigenvalues ``w`` of the pencil at (k, kz) (the last 8 pairs)."""
        if len(self.qz_eigenvalues) >= 8:
            self.qz_eigenvalues.pop(next(iter(self.qz_eigenvalues)))
        self.qz_eigenvalues[(float(k), float(kz))] = w

    @property
    def size(self) -> int:
        return (self.n + 1) * len(self.fields)

    def _assemble(self):
        g, flow = self.grid, self.flow
        m, M = self.n + 1, self.size
        th = math.radians(flow.theta)
        sin, cos = math.sin(th), math.cos(th)
        base = base_on_grid(flow, g.y)
        part = flow.model.evaluate(base["nu"], base["T"])
        scale_all = np.ones(M)
        mu, kap = part["mu"][(0, 0)], part["kappa"][(0, 0)]
        # Rows divided by the diffusion coefficient stay O(D²) up to the dilute top. Dividing
        # by the inertia ν0 instead (B = I) multiplies the top rows by ~1e9 and, QZ and LU
        # being normwise backward stable, buries the dense layer's eigenvalues in round-off
        # (α(0) ~ 1e-4 instead of ~1e-12 at θ = 16°, ν0 = 0.05).
        bulk_scale = {
            "mass": np.ones(m),
            "xmom": 1.0 / mu,
            "ymom": 1.0 / mu,
            "zmom": 1.0 / mu,
            "energy": 1.0 / kap,
        }
        floor_scale = {
            "ymom": 1.0 / mu[0],
            "floor_x": 1.0 / mu[0],
            "floor_v": 1.0,
            "floor_z": 1.0 / mu[0],
            "floor_energy": 1.0 / kap[0],
        }
        self.residuals = {}
        kernel = scatter_kernel()
        pieces, B, K, k_rows = self._scatter(kernel, base, part, sin, cos, bulk_scale, floor_scale)
        inner = slice(1, m - 1)
        for i, f in enumerate(self.fields):
            r0 = i * m
            scale_all[r0 + 1 : r0 + m - 1] = bulk_scale[BULK_OF[f]][inner]
            scale_all[r0] = floor_scale[FLOOR_OF[f]]
        self.pieces, self.B = pieces, B
        self.row_scale, self.base = scale_all, base
        # Equilibration used by the solvers (an exact diagonal similarity, not part of the
        # public operator): mass rows divided by ν0 and ν̂ columns multiplied by ν0, i.e.
        # unknown ν̂/ν0. Without it the dilute top's mass rows, −(ν0 v̂)' ~ 1e-9 D v̂, are
        # numerically zero rows: A − σB is singular to round-off in several directions at
        # once and shift-invert fails near the continuum (and at k = 0).
        self.row_eq = np.ones(M)
        self.row_eq[1 : m - 1] = 1.0 / base["nu"][1 : m - 1]
        self.col_eq = np.ones(M)
        self.col_eq[:m] = base["nu"]
        r, c = self.row_eq, self.col_eq
        self._pieces_eq = {key: _scaled(kernel, P, r, c) for key, P in pieces.items()}
        self.B_eq = _scaled(kernel, B, r, c)
        # K has entries on a few rows only (the top conditions): kept as (rows, columns, values)
        tops = np.array(k_rows, dtype=int)  # sorted (the plan's)
        ti, kc = np.nonzero(K[tops])
        kr = tops[ti]
        kv = K[kr, kc]
        self._K_eq = (kr, kc, kv * self.row_eq[kr] * self.col_eq[kc])
        self._K_sparse = (kr, kc, kv)

    def _scatter(self, kernel, base, part, sin, cos, bulk_scale, floor_scale):
        """(pieces, B, K, rows of K, sorted): every term of the row equations put where the plan
        (:func:`~chuteflow.stability._assembly.term_plan`) says, by the compiled kernel or,
        without one (``kernel`` None), term by term in numpy (:func:`_scatter_numpy`), with
        the same products and sums in the same order."""
        g = self.grid
        m, M = self.n + 1, self.size
        plan = term_plan(self.n, self.fields, _ROWS_OF)
        eqs = compiled_equations()
        args = arguments(base, part, sin, cos)
        coef = np.empty((plan.n_coef, m))
        for name, off in zip(plan.equations, plan.offsets):
            res, coefs = eqs[name].evaluate_arguments(args)
            self.residuals[name] = np.broadcast_to(res, (m,)).copy()
            for i, c in enumerate(coefs):
                coef[off + i] = c
        scale = np.empty((len(plan.uses), m))
        for row, (name, kind) in enumerate(plan.uses):
            scale[row] = bulk_scale[name] if kind == BULK else floor_scale[name] if kind == FLOOR else 1.0
        targets = [np.zeros((M, M)) for _ in range(len(plan.keys) + 2)]
        D1, D2 = np.ascontiguousarray(g.D, dtype=float), np.ascontiguousarray(g.D2, dtype=float)
        if kernel is None:
            _scatter_numpy(plan.where, coef, scale, D1, D2, targets)
        else:
            ptrs = np.array([t.ctypes.data for t in targets], dtype=np.uintp)
            kernel.scatter(
                len(plan.entries),
                plan.entries.ctypes.data,
                coef.ctypes.data,
                scale.ctypes.data,
                D1.ctypes.data,
                D2.ctypes.data,
                m,
                M,
                ptrs.ctypes.data,
            )
        pieces = dict(zip(plan.keys, targets))
        return pieces, targets[-2], targets[-1], plan.k_rows

    @property
    def K(self) -> np.ndarray:
        """Coefficient of |k| (dense; the top conditions' entries, built on each access)."""
        rows, cols, vals = self._K_sparse
        K = np.zeros((self.size, self.size))
        K[rows, cols] = vals
        return K

    # -- evaluation ----------------------------------------------------------------------
    def matrix(self, kx: float, kz: float = 0.0, *, equilibrated: bool = False) -> np.ndarray:
        """A(k_x, k_z), complex (of the equilibrated pencil R A C if ``equilibrated``)."""
        kx, kz = validate_k(kx, "k"), validate_k(kz, "kz", signed=True)
        if kz and not self.three_d:
            raise ParameterError("kz != 0 needs the three-dimensional operator (three_d=True)")
        pieces, K = (self._pieces_eq, self._K_eq) if equilibrated else (self.pieces, self._K_sparse)
        A = np.empty(pieces[(0, 0)].shape, dtype=complex)
        # (ik)^b is real for even b, imaginary for odd: fill real and imaginary parts apart
        re, im = pieces[(0, 0)].copy(), None
        for (b, d), P in pieces.items():
            if not (b or d):
                continue
            fac = (1j * kx) ** b * (1j * kz) ** d
            if fac == 0:
                continue
            if fac.imag == 0:
                re += fac.real * P
            elif fac.real == 0:
                im = fac.imag * P if im is None else im + fac.imag * P
            else:  # pragma: no cover - (ik)^b (ik)^d is always real or imaginary
                raise AssertionError(fac)
        k = math.hypot(kx, kz)
        rows, cols, vals = K
        re[rows, cols] += k * vals
        A.real = re
        A.imag = 0.0 if im is None else im
        return A

    def pencil(self, kx: float, kz: float = 0.0) -> Pencil:
        """The pencil (A, B) at wavevector (k_x, k_z)."""
        kx, kz = validate_k(kx, "k"), validate_k(kz, "kz", signed=True)
        if kz and not self.three_d:
            raise ParameterError("kz != 0 needs the three-dimensional operator (three_d=True)")
        return Pencil(kx, kz, self)

    def series(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(A0, A1, A2) with A(k) = A0 + (ik) A1 + (ik)² A2 for k_z = 0, k ≥ 0 (eq. 4.4).

        The top conditions' |k| = k = −i(ik) are folded into A1. This is the expansion that
        perturbation theory in k uses (Appendix B); A0 is real and, with B, gives the k = 0
        problem whose null vector is ∂X0/∂β (see :func:`null_vectors`).
        """
        z = np.zeros((self.size, self.size))
        A0 = self.pieces[(0, 0)].copy()
        A1 = self.pieces.get((1, 0), z).astype(complex)
        rows, cols, vals = self._K_sparse
        A1[rows, cols] -= 1j * vals  # − i K, on K's entries only
        A2 = self.pieces.get((2, 0), z).astype(complex)
        return A0, A1, A2

    def series_products(self):
        """(A0, P1, P2) of the expansion A(s) = A0 + s P1 + s² P2 along k_x = s, without
        dense complex copies: A0 the real k = 0 matrix itself (read it, do not modify it),
        P1 = i A1 and P2 = −A2 of :meth:`series` as functions x ↦ P x. P1 = i R1 + K with
        R1 the real coefficient of (ik) and K the |k| entries, P2 = −R2 with R2 that of
        (ik)²: real matrix products and the few entries of K (the perturbation theory of
        :mod:`chuteflow.longwave.theory` needs three products per grid, and :meth:`series`
        costs four complex copies of the matrix)."""
        M = self.size
        R1, R2 = self.pieces.get((1, 0)), self.pieces.get((2, 0))
        rows, cols, vals = self._K_sparse

        def real_times(R, x):
            x = np.asarray(x)
            if R is None:
                return np.zeros(M, dtype=complex)
            if np.iscomplexobj(x):
                return (R @ x.real) + 1j * (R @ x.imag)
            return (R @ x).astype(complex)

        def p1(x):
            y = 1j * real_times(R1, x)
            np.add.at(y, rows, vals * np.asarray(x)[cols])
            return y

        def p2(x):
            return -real_times(R2, x)

        return self.pieces[(0, 0)], p1, p2


def validate_n(n) -> int:
    """``n`` as an int, or a :class:`~chuteflow.errors.ParameterError` if outside ``N_RANGE``."""
    try:
        n = int(n)
    except (TypeError, ValueError):
        raise ParameterError(f"n = {n!r}: expected an integer number of intervals") from None
    lo, hi = N_RANGE
    if not lo <= n <= hi:
        raise ParameterError(
            f"n = {n} is outside [{lo}, {hi}]: the number of Chebyshev "
            "intervals must resolve the layer and the dense solve must fit "
            "in memory"
        )
    return n


def validate_k(k, name, signed=False) -> float:
    """The wavenumber ``k`` (parameter ``name``) as a float: finite, and ≥ 0 unless ``signed``."""
    try:
        k = float(k)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} = {k!r}: expected a number") from None
    if not math.isfinite(k) or (k < 0 and not signed):
        raise ParameterError(
            f"{name} = {k!r} is outside [0, inf): the wavenumber of the "
            "perturbation exp(ikx) is taken non-negative (α(−k) = conj α(k))"
        )
    return k

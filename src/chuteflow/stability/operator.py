"""The linear stability operator on a Chebyshev grid (paper §4.1, Appendix A).

Perturbations ∝ exp(αt + i k_x x + i k_z z) (eq. (4.4); k_z = 0 in the paper) of a steady
flow satisfy A V = α B V. Every coefficient comes from the compiled linearisation of
:mod:`chuteflow.equations`; nothing of Appendix A is retyped here. A term (a, b, c, d) of an
equation, coefficient × α^a (ik_x)^b (ik_z)^d d^c/dy^c, goes to B (a = 1, with a minus sign:
residuals are N(X) − B∂_tX) or to the piece A_{b,d} of

    A(k_x, k_z) = Σ_{b,d} (ik_x)^b (ik_z)^d A_{b,d} + |k| K,

where K holds the |k| terms of the top decay conditions. Rows, for N + 1 Chebyshev–Lobatto
nodes per field on [0, y_max]:

========  =================  ===========================  =================================
block     interior nodes     floor (y = 0)                top (y = y_max)
========  =================  ===========================  =================================
ν̂         mass (eq. 2.1)      y-momentum at y = 0 (extra)  ν̂' = −(cos θ/T0) ν̂ (extra)
û         x-momentum         eq. (2.9) (eq. A 5)             û' = −k û
v̂         y-momentum         v̂ = 0 (impermeable, docs/errata.md)  v̂' = −k v̂
ŵ (3D)    z-momentum         eq. (2.9), z component          ŵ' = −k ŵ
T̂         energy (eq. 2.3)   eq. (2.10) (eq. A 6)             T̂' = −k T̂
========  =================  ===========================  =================================

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

from ..equations import TOP_OF, Term, compiled_equations
from ..errors import ParameterError
from ..spectral import ChebyshevGrid
from ..steady import SteadyFlow

FIELDS_2D = ("nu", "u", "v", "T")
FIELDS_3D = ("nu", "u", "v", "w", "T")
#: Bulk equation of each field's row block.
BULK_OF = {"nu": "mass", "u": "xmom", "v": "ymom", "w": "zmom", "T": "energy"}
#: Floor row of each block (the ν̂ block carries the y-momentum balance at the floor).
FLOOR_OF = {"nu": "ymom", "u": "floor_x", "v": "floor_v", "w": "floor_z", "T": "floor_energy"}

N_RANGE = (8, 1000)


def base_on_grid(flow: SteadyFlow, y: np.ndarray) -> dict[str, np.ndarray]:
    """Jets ν0, ν0', ν0'', u0, …, T0'' (keys of :data:`chuteflow.equations.BASE`) at ``y``.

    Derivatives are taken on the flow's own grid, where its Chebyshev series is converged,
    and then interpolated spectrally, so they are exact on any target grid. ν0 goes through
    ln ν0, which keeps relative accuracy where ν0 ~ 1e-9.
    """
    g = flow.grid
    d = flow.derivatives()
    s = g.interpolate(flow.log_nu, y)
    nu = np.exp(s)
    s1, s2 = g.interpolate(g.D @ flow.log_nu, y), g.interpolate(g.D2 @ flow.log_nu, y)
    return {
        "nu": nu,
        "nu_y": nu * s1,
        "nu_yy": nu * (s2 + s1**2),
        "u": g.interpolate(flow.u, y),
        "u_y": g.interpolate(d["u_y"], y),
        "u_yy": g.interpolate(d["u_yy"], y),
        "T": g.interpolate(flow.T, y),
        "T_y": g.interpolate(d["T_y"], y),
        "T_yy": g.interpolate(d["T_yy"], y),
    }


def equation_terms(
    flow: SteadyFlow,
    name: str,
    fields: dict[str, np.ndarray],
    kx: float,
    kz: float = 0.0,
    alpha: complex = 0.0,
) -> list[tuple[Term, np.ndarray]]:
    """Each term of one linearised equation, applied to a normal-mode perturbation.

    Parameters
    ----------
    flow : SteadyFlow
        The base state.
    name : str
        An equation of :func:`chuteflow.equations.compiled_equations` ("mass", "xmom", …).
    fields : dict
        Field name → complex nodal values f̂ on the N + 1 Chebyshev nodes of [0, y_max]
        (N = len − 1), e.g. :attr:`Mode.fields <chuteflow.stability.Mode>`. Terms acting on
        a field that is absent (ŵ of a 2D mode) are left out.
    kx, kz : float
        Wavevector of the mode exp(αt + i k_x x + i k_z z).
    alpha : complex
        Its eigenvalue α (used by the terms with ∂_t).

    Returns
    -------
    list of (Term, ndarray)
        coefficient × α^a (ik_x)^b (ik_z)^d |k|^k d^c f̂/dy^c at every node, for every term
        of the equation; their sum is the equation's linearised residual, which vanishes at
        the interior nodes for an eigenmode of a bulk equation.
    """
    first = next(iter(fields.values()))
    g = ChebyshevGrid(len(first) - 1, 0.0, flow.y_max)
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
        Collocation grid on [0, y_max].
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


class StabilityOperator:
    """The linear operator of one steady flow on one Chebyshev grid, for any wavevector.

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

    def __init__(self, flow: SteadyFlow, n: int, *, three_d: bool = False):
        if not isinstance(flow, SteadyFlow):
            raise ParameterError(f"flow: expected a SteadyFlow, got {type(flow).__name__}")
        n = validate_n(n)
        self.flow, self.n, self.three_d = flow, n, bool(three_d)
        self.fields = FIELDS_3D if three_d else FIELDS_2D
        self.grid = ChebyshevGrid(n, 0.0, flow.y_max)
        self._assemble()

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
        eqs = compiled_equations()
        dmat = (np.eye(m), g.D, g.D2)
        col = {f: slice(i * m, (i + 1) * m) for i, f in enumerate(self.fields)}
        pieces: dict[tuple[int, int], np.ndarray] = {(0, 0): np.zeros((M, M))}
        B = np.zeros((M, M))
        K = np.zeros((M, M))
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
        cache = {}

        def coefficients(name):
            if name not in cache:
                res, coefs = eqs[name].evaluate(base, part, sin, cos)
                self.residuals[name] = np.broadcast_to(res, (m,)).copy()
                cache[name] = [np.broadcast_to(np.asarray(c, dtype=float), (m,)) for c in coefs]
            return cache[name]

        def add(name, nodes, scale, rows, keep_alpha):
            for t, cf in zip(eqs[name].terms, coefficients(name)):
                if t.field not in col or (t.d and not self.three_d):
                    continue
                blk = (cf[nodes] * scale)[:, None] * dmat[t.c][nodes]
                if t.a:
                    if (t.a, t.b, t.c, t.d, t.k) != (1, 0, 0, 0, 0):
                        raise NotImplementedError(f"α enters {name} as {t}: not a pencil")
                    if keep_alpha:
                        B[rows, col[t.field]] -= blk
                    continue
                if t.k:
                    if (t.k, t.b, t.d) != (1, 0, 0):
                        raise NotImplementedError(f"|k| enters {name} as {t}: not linear")
                    K[rows, col[t.field]] += blk
                    continue
                pieces.setdefault((t.b, t.d), np.zeros((M, M)))[rows, col[t.field]] += blk

        inner = slice(1, m - 1)
        for i, f in enumerate(self.fields):
            r0 = i * m
            name = BULK_OF[f]
            add(name, inner, bulk_scale[name][inner], slice(r0 + 1, r0 + m - 1), True)
            scale_all[r0 + 1 : r0 + m - 1] = bulk_scale[name][inner]
            name = FLOOR_OF[f]
            add(name, slice(0, 1), floor_scale[name], slice(r0, r0 + 1), False)
            scale_all[r0] = floor_scale[name]
            # far field: ν̂' = −(cos θ/T0) ν̂ (ν̂ ∝ ν0), f̂' = −|k| f̂ for û, v̂, ŵ, T̂
            add(TOP_OF[f], slice(m - 1, m), 1.0, slice(r0 + m - 1, r0 + m), False)
        self.pieces, self.K, self.B = pieces, K, B
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
        r, c = self.row_eq[:, None], self.col_eq[None, :]
        self._pieces_eq = {key: P * r * c for key, P in pieces.items()}
        self.B_eq = B * r * c
        nz = np.nonzero(K)
        self._K_eq = (nz[0], nz[1], (K * r * c)[nz])
        self._K_sparse = (nz[0], nz[1], K[nz])

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
        A1 = self.pieces.get((1, 0), z) - 1j * self.K
        A2 = self.pieces.get((2, 0), z).astype(complex)
        return A0, A1, A2


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

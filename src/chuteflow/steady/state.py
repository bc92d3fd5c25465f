"""The Newton unknowns of a steady flow (paper §3): :class:`NewtonState` on the nodes of
:func:`~chuteflow.steady.grid.reference_grid`, moved between grids (:func:`resample`) and
converted from and to a :class:`~chuteflow.steady.result.SteadyFlow`.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..spectral import ChebyshevGrid, barycentric, reference_nodes
from .grid import reference_grid
from .result import SteadyFlow, derived_quantities, steady_grid


@dataclass
class NewtonState:
    """Nodal unknowns: s = ln ν0 (keeps relative accuracy over nine decades), u0, T0, y_max,
    on the nodes ξ_j y_max of :func:`~chuteflow.steady.grid.reference_grid` (n, ``grid_map``)."""

    n: int
    s: np.ndarray
    u: np.ndarray
    T: np.ndarray
    L: float
    grid_map: tuple[float, float] | None = None
    #: Set by Newton (:meth:`~chuteflow.steady.newton.SteadyNewton.solve` with ``tangents``) on
    #: the state it returns: (dX/dβ, relative size of the last Newton step), the family tangent
    #: (β = ν0(0)) solved with the last Jacobian, which was taken at the state before that step.
    tangents: tuple | None = field(default=None, repr=False, compare=False)
    #: Set by Newton with chord steps (:attr:`~chuteflow.steady.newton.SteadyNewton.chord`) on
    #: the state it returns: J⁻¹ B from the last LU it used
    #: (:meth:`~chuteflow.steady.newton.SteadyNewton.factored_step`), for the chord steps of a
    #: neighbour's solve at the same n (:attr:`~chuteflow.steady.newton.SteadyNewton.inherit`).
    lu: Any = field(default=None, repr=False, compare=False)

    @property
    def nu(self):
        return np.exp(self.s)

    @property
    def ref(self) -> ChebyshevGrid:
        """The grid of the nodes in ξ = y/y_max."""
        return reference_grid(self.n, self.grid_map)

    def pack(self):
        return np.concatenate([self.s, self.u, self.T, [self.L]])

    @classmethod
    def unpack(cls, n, X, grid_map=None):
        m = n + 1
        return cls(n, X[:m].copy(), X[m : 2 * m].copy(), X[2 * m : 3 * m].copy(), float(X[-1]), grid_map)


_SAME: Any = object()


def resample(st: NewtonState, n: int, grid_map: Any = _SAME) -> NewtonState:
    """Interpolate a state to n + 1 nodes on the same [0, y_max] (log ν for positivity), on
    the grid ``grid_map`` (default: the state's own)."""
    gm = st.grid_map if grid_map is _SAME else grid_map
    if st.n == n and gm == st.grid_map:
        return NewtonState(n, st.s.copy(), st.u.copy(), st.T.copy(), st.L, gm)
    if gm == st.grid_map:
        # the same map: the new nodes are the Chebyshev nodes of n in the computational
        # variable, whatever the map (one cached interpolation matrix per pair of n)
        v = np.stack([st.s, st.u, st.T]) @ _node_interpolation(st.n, n)
    else:
        v = st.ref.interpolate(np.stack([st.s, st.u, st.T]), reference_grid(n, gm).y)
    return NewtonState(n, v[0].copy(), v[1].copy(), v[2].copy(), st.L, gm)


@functools.lru_cache(maxsize=16)
def _node_interpolation(n_old: int, n_new: int) -> np.ndarray:
    """M with f(x_new) = f(x_old) @ M: the interpolant on the n_old + 1 Chebyshev nodes at
    the n_new + 1 ones (barycentric formula; read-only)."""
    M = barycentric(np.eye(n_old + 1), n_old, reference_nodes(n_new)[0])
    M.flags.writeable = False
    return M


def state_of(flow: SteadyFlow) -> NewtonState:
    """The Newton unknowns of a converged flow (on its own grid)."""
    return NewtonState(
        flow.n, np.asarray(flow.log_nu), np.asarray(flow.u), np.asarray(flow.T), flow.y_max, flow.grid_map
    )


def quantities(theta, st: NewtonState, model):
    """The grid of ``st`` on [0, y_max] and the scalar results of the flow it holds (paper §3.2:
    :func:`~chuteflow.steady.result.derived_quantities`, with u0(0), T0(0) and y_max)."""
    g = steady_grid(st.n, st.L, st.grid_map)
    q = derived_quantities(theta, g, st.s, st.u, st.T, model)
    q.update(u_floor=float(st.u[0]), T_floor=float(st.T[0]), y_max=st.L)
    return g, q

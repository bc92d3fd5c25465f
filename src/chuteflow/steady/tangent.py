"""The family tangent dX/dβ (β = ν0(0)) and dX/dθ of a steady flow: the k = 0 null vector
∂X0/∂β of Appendix B, and dQ0/dρ̄0 (eq. (B 6)).
"""

from __future__ import annotations

import weakref

import numpy as np

from .newton import SteadyNewton
from .result import SteadyFlow, cached_per_flow
from .state import NewtonState, quantities, state_of

#: Largest relative Newton step after the Jacobian whose LU gave a flow's dX/dβ for
#: :func:`steady_tangent` to use it (otherwise it factorises the Jacobian at the flow).
#: The tangent's error is of the order of that step (measured: tests/steady/test_solver.py).
TANGENT_STEP = 1e-10


class _PerObject:
    """Values by object identity while the object lives (a weak reference: never keeps it
    alive). Unlike a ``WeakKeyDictionary``, flows equal in value do not share an entry, so
    one flow dying does not take the entry of another equal one."""

    def __init__(self):
        self._items: dict[int, tuple] = {}

    def put(self, obj, value) -> None:
        key = id(obj)

        def drop(_ref, key=key, items=self._items):
            items.pop(key, None)

        self._items[key] = (weakref.ref(obj, drop), value)

    def get(self, obj):
        """The value stored for ``obj``, or None."""
        item = self._items.get(id(obj))
        return None if item is None or item[0]() is not obj else item[1]

    def take(self, obj):
        """The value stored for ``obj``, removed; None if there is none."""
        value = self.get(obj)
        if value is not None:
            self._items.pop(id(obj), None)
        return value


#: dX/dβ from Newton's last LU (solve_point), by flow object, while the flow lives.
_BETA_TANGENTS = _PerObject()


def newton_tangent(st: NewtonState) -> np.ndarray | None:
    """dX/dβ of a converged state from Newton's last LU
    (:attr:`~chuteflow.steady.state.NewtonState.tangents`) if
    that Jacobian was taken within :data:`TANGENT_STEP` of the state (accurate to about that
    step, as an output); None otherwise (factorise at the state instead)."""
    if st.tangents is not None and st.tangents[1] <= TANGENT_STEP:
        return st.tangents[0]
    return None


def steady_tangent(flow: SteadyFlow) -> dict:
    """Derivative of a steady flow along its family at fixed θ, with respect to β = ν0(0).

    Differentiating the discrete steady equations R(X; β) = 0 gives J dX/dβ = −∂R/∂β with the
    same exact Jacobian J that Newton used; β enters only through ln ν0(0) = ln β. This is the
    k = 0 null vector ∂X0/∂β of Appendix B. Scalar quantities are differentiated along that
    tangent (central difference on the exact tangent direction, step 1e-6 relative: error
    O(1e-12)). The result is cached per flow while the flow lives; its arrays are
    read-only.

    Returns
    -------
    dict
        ``log_nu``, ``u``, ``T`` (nodal arrays), ``y_max`` (d/dβ at fixed ξ = y/y_max), and
        d/dβ of ``rho_bar``, ``Q``, ``T_mean``, ``h``, ``nu_mean``, ``u_floor``, ``T_floor``,
        plus ``dQ_drho`` = dQ0/dρ̄0 (eq. (B 6)).
    """
    return dict(_cached_tangent(flow))


@cached_per_flow
def _cached_tangent(flow: SteadyFlow) -> dict:
    """The tangent of one flow, computed once while the flow lives: several sweep metrics of
    the same point (``kinematic``, the 1D criterion, the long-wave theory) need it. Its
    arrays are made read-only so that no caller can alter the cached copy.

    Newton's dX/dβ is kept by flow object (:data:`_BETA_TANGENTS`), not by value as the
    cache is: two flows equal in value (a marked point on the grid, solved from the same
    cold start by two tasks in the threads of one Dask worker) each find their own, so the
    tangent does not depend on which of them dies or asks first (with one entry for both,
    the second factorised instead, and its dQ0/dρ̄0 differed by ~TANGENT_STEP: 2e-10 in
    tests/sweep/test_dask.py, in one run of three)."""
    dX = _BETA_TANGENTS.take(flow)
    out = tangent_from(flow, dX if dX is not None else tangent_vectors(flow, theta=False)[0])
    for v in out.values():
        if isinstance(v, np.ndarray):
            v.flags.writeable = False
    return out


def tangent_from(flow: SteadyFlow, dX: np.ndarray) -> dict:
    """steady_tangent's dict from the packed tangent dX/dβ."""
    st = state_of(flow)
    m = flow.n + 1
    out = {"log_nu": dX[:m], "u": dX[m : 2 * m], "T": dX[2 * m : 3 * m], "y_max": dX[-1]}
    X = st.pack()
    eps = 1e-6 * flow.nu0
    qp = quantities(flow.theta, NewtonState.unpack(flow.n, X + eps * dX, flow.grid_map), flow.model)[1]
    qm = quantities(flow.theta, NewtonState.unpack(flow.n, X - eps * dX, flow.grid_map), flow.model)[1]
    for k in ("rho_bar", "Q", "T_mean", "h", "nu_mean", "u_floor", "T_floor"):
        out["d" + k] = (qp[k] - qm[k]) / (2 * eps)
    out["dQ_drho"] = out["dQ"] / out["drho_bar"]
    return out


def tangent_vectors(flow: SteadyFlow, theta: bool = True):
    """Packed dX/dβ (β = ν0(0)) and, if ``theta``, dX/dθ (per degree), from one LU of the
    exact Jacobian. θ enters the residual only through sin θ and cos θ, linearly, so a
    central difference of R in θ (step 1e-3°) is exact up to round-off (~1e-12)."""
    st = state_of(flow)
    return state_tangent_vectors(flow.theta, flow.nu0, flow.model, flow.nu_top, st, theta=theta)


def state_tangent_vectors(theta_deg, nu0, model, nu_top, st: NewtonState, theta: bool = True):
    """:func:`tangent_vectors` at a solution given as a
    :class:`~chuteflow.steady.state.NewtonState` (any n)."""
    newton = SteadyNewton(st.n, theta_deg, nu0, model, nu_top, grid_map=st.grid_map)
    rhs = np.zeros((st.pack().size, 2 if theta else 1))
    rhs[0, 0] = -1.0 / nu0
    if theta:
        eps = 1e-3
        Rp = SteadyNewton(st.n, theta_deg + eps, nu0, model, nu_top, grid_map=st.grid_map).evaluate(
            st, jac=False
        )[0]
        Rm = SteadyNewton(st.n, theta_deg - eps, nu0, model, nu_top, grid_map=st.grid_map).evaluate(
            st, jac=False
        )[0]
        rhs[:, 1] = (Rp - Rm) / (2 * eps)
    # Newton's own solve: the exact Jacobian at st, with u0' eliminated where the equations
    # allow (SteadyNewton.step: a third of the dense LU's work)
    sol = -newton.step(st, rhs)
    return sol[:, 0], (sol[:, 1] if theta else None)

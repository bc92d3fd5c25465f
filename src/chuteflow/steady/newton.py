"""Damped Newton with chord steps on the steady system (paper §3)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..errors import ConvergenceError, NoSteadyFlowError
from .linear import eliminated_step
from .state import NewtonState
from .system import SteadySystem

#: Steps in a row accepted at the two smallest step lengths after which Newton gives up
#: (:meth:`SteadyNewton._solve`).
_CRAWL = 3


#: A chord step (:attr:`SteadyNewton.chord`) is kept when it lowers the residual at least
#: this much (relative); otherwise Newton factorises the Jacobian where it stands.
_CHORD_RATIO = 0.1


class _NewtonFailure(Exception):
    def __init__(self, state, history):
        super().__init__("Newton did not converge")
        self.state, self.history = state, history


class SteadyNewton(SteadySystem):
    """Damped Newton on the steady system of :class:`~chuteflow.steady.system.SteadySystem`."""

    def __init__(self, n, theta_deg, nu0, model, nu_top, integrated=True, grid_map=None):
        super().__init__(n, theta_deg, nu0, model, nu_top, integrated, grid_map)
        #: Newton also solves for dX/dβ (β = ν0(0)) with each LU (see _solve)
        self.tangents = False
        #: Newton reuses its last LU for chord steps while they contract fast (see _solve)
        self.chord = False
        #: with chord: a neighbour's LU at this n
        #: (:attr:`~chuteflow.steady.state.NewtonState.lu`), for chord steps from the start
        #: (continuation: the Jacobian of a nearby flow)
        self.inherit = None
        self._latest = None  # the last LU a chord solve used (see solve)

    def step(self, st: NewtonState, B: np.ndarray) -> np.ndarray:
        """J⁻¹ B for the exact Jacobian J at ``st`` (columns of B: right-hand sides).

        Where the equations allow (:attr:`eliminate`: u0 enters every row only through u0',
        except the floor rows, which may also hold u0(0); the integrated x-momentum eq. (3.7) μ
        u0' = tanθ p is the first such row), the unknowns u0(ξ_j) are replaced by (u0(0), w_j =
        u0'(ξ_j), j = 1…n), u0 = M⁻¹ (u0(0), w) with M = [e_0; D1 rows 1…n]
        (:func:`~chuteflow.steady.linear._u_basis`). The x-momentum rows then hold w_j at their
        own node only (a diagonal block), and so do the energy rows; eliminating w leaves a
        dense system of 2(n + 1) + 1 instead of 3(n + 1) + 1 unknowns (a third of the LU's
        work), whose Schur complement costs O(n²). Otherwise, a dense LU of J."""
        return self._step(st, B, keep=False)[0]

    def factored_step(self, st: NewtonState, B: np.ndarray) -> tuple[np.ndarray, Any]:
        """(J⁻¹ B, solve) as :meth:`step`, with ``solve(B2)`` = J⁻¹ B2 for the same J from
        its kept LU factors (O(n²) a right-hand side: Newton's chord steps, :meth:`solve`
        with :attr:`chord`). Uses scipy's LU (``lu_factor``, imported here)."""
        return self._step(st, B, keep=True)

    def _step(self, st: NewtonState, B: np.ndarray, keep: bool) -> tuple[np.ndarray, Any]:
        return eliminated_step(self, st, B, keep)

    def solve(self, st: NewtonState, tol=1e-10, maxiter=60, y_cap=1e5, lam_min=1e-6, min_iter=0):
        """Damped Newton from ``st``: (state, corrections, residual, history); raises
        :class:`_NewtonFailure` (see :meth:`_solve`)."""
        out = self._solve(st, tol, maxiter, y_cap, lam_min, min_iter)
        out[0].lu = self._latest  # the last LU used (with chord), for a neighbour's solve
        return out

    def trial_residual(self, st: NewtonState) -> np.ndarray:
        """The scaled residual at a trial state (a start, a chord or a line-search step).

        A trial may leave the closures' domain (ν0 > ν_m, T0 ≤ 0 between the nodes, overflow
        of e^s): its residual is then NaN or ±inf, which the line search rejects (a shorter
        step) — an expected, handled outcome, so numpy's floating-point warnings are
        silenced here, and only here (the Jacobian and the linear solves are taken at
        accepted states, with a finite residual)."""
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            return self.evaluate(st, jac=False)[0]

    def _solve(self, st, tol, maxiter, y_cap, lam_min, min_iter):
        """Damped Newton. Converged when the scaled residual is below ``tol``, or when the
        relative Newton step falls below 1e-11 with the residual at its round-off floor.
        Fails when the backtracking step would fall below ``lam_min`` (a continuation
        guess that needs heavy damping is on the wrong side of a fold: fail fast), or when
        :data:`_CRAWL` steps in a row were accepted only at the two smallest step lengths
        allowed (λ < 4 ``lam_min``): each of them lowers the residual by less than
        0.1 λ, a crawl that does not reach Newton's quadratic phase within the iterations
        of a continuation attempt. On the 60 × 60 paper steady map and the diagram's
        steady rows no solve that converged had more than two such steps in a row, while
        ~120 failing continuation attempts crawled on to ``maxiter``.

        The round-off floor of the residual grows like n⁴ (second derivatives near the ends),
        so ``tol`` is raised accordingly above n = 64; the accuracy of a result is checked
        independently by the change between two resolutions (:func:`~chuteflow.steady.solve.solve_steady`)."""
        tol = max(tol, 1e-11 * (self.n / 64.0) ** 4)
        hist = []
        crawl = 0  # steps in a row accepted at λ < 4 lam_min
        steps = 0  # corrections taken (Newton and chord)
        # with chord: J⁻¹ B from the last LU (after a full step only, or a neighbour's);
        # the relative distance from the state of that Jacobian, and its dX/dβ
        again = self._latest = self.inherit if self.chord else None
        walked, tangent = math.inf, None
        R = self.trial_residual(st)
        res = np.abs(R).max()
        for _ in range(maxiter):
            hist.append(res)
            if not np.isfinite(res):
                break
            if res < tol and steps >= min_iter:
                return st, steps, res, hist
            while again is not None:
                # chord step: the last LU (its Jacobian a Newton step or a few back), kept
                # while it lowers the residual at least 1/_CHORD_RATIO times, down to
                # _CHORD_RATIO tol (a full Newton step ends well below tol; stopping just
                # below it would leave Newton's error larger than before) or to the
                # round-off floor (a step below tol that no longer contracts)
                X0 = st.pack()
                dX = -again(R[:, None])[:, 0]
                trial = NewtonState.unpack(self.n, X0 + dX, self.grid_map)
                rt = math.inf
                kept = self._last  # st's residual pieces, for its Jacobian if this step fails
                if (trial.T > 0).all() and 0 < trial.L < y_cap:
                    Rt = self.trial_residual(trial)
                    rt = np.abs(Rt).max()
                # (a correction that keeps the residual below tol counts for min_iter: the
                # finer rung of a ladder from a neighbour's LU)
                contracts = rt < _CHORD_RATIO * res
                if not (contracts or (steps < min_iter and rt < tol)):
                    again, self._last = None, kept
                    break
                walked += np.abs(dX).max() / max(np.abs(X0).max(), 1.0)
                if self.tangents:
                    if tangent is None:  # a neighbour's LU: its dX/dβ here (approximate)
                        Bb = np.zeros((len(R), 1))
                        Bb[0, 0] = 1.0 / self.nu0
                        tangent = again(Bb)[:, 0]
                    trial.tangents = (tangent, walked)
                st, R, res = trial, Rt, rt
                steps += 1
                hist.append(res)
                if res < tol and steps >= min_iter and (res < _CHORD_RATIO * tol or not contracts):
                    return st, steps, res, hist
            if res < tol and steps >= min_iter:
                return st, steps, res, hist
            # with ``tangents``, dX/dβ as a second right-hand side of the same LU (O(n²)):
            # J dX/dβ = −∂R/∂β, and β = ν0(0) enters only through R[0] = ln ν(0) − ln β
            if self.tangents:
                B = np.zeros((len(R), 2))
                B[:, 0], B[0, 1] = R, 1.0 / self.nu0
            else:
                B = R[:, None].copy()
            try:
                # the Jacobian only now that a step is needed (the residual's pieces of this
                # state are kept by evaluate)
                if self.chord:
                    sol, again = self.factored_step(st, B)
                    self._latest = again
                else:
                    sol = self.step(st, B)
            except (ValueError, np.linalg.LinAlgError):
                break
            dX = -sol[:, 0]
            X0 = st.pack()
            step = np.abs(dX).max() / max(np.abs(X0).max(), 1.0)
            # at large n the residual floor grows like eps·n⁴ (D2 near the ends): accept a
            # stalled residual when the Newton step is at noise level too; the accuracy of
            # the result is checked independently by the change between two resolutions
            stalled = len(hist) > 2 and res > 0.5 * hist[-2] and (res < 1e-7 or (step < 1e-7 and res < 1e-4))
            if ((step < 1e-11 and res < 1e-6) or stalled) and steps >= min_iter:
                if self.tangents:  # this Jacobian was taken at st itself
                    st.tangents = (sol[:, 1].copy(), 0.0)
                return st, steps, res, hist
            lam = 1.0
            while lam >= lam_min:
                trial = NewtonState.unpack(self.n, X0 + lam * dX, self.grid_map)
                if (trial.T > 0).all() and 0 < trial.L < y_cap:
                    Rt = self.trial_residual(trial)
                    rt = np.abs(Rt).max()
                    better = rt < (1 - 0.1 * lam) * res or (lam == 1.0 and rt < 1e-6)
                    if np.isfinite(rt) and better:
                        if self.tangents:
                            tangent = sol[:, 1].copy()
                            trial.tangents = (tangent, lam * step)
                        st, R, res = trial, Rt, rt
                        steps += 1
                        break
                lam *= 0.5
            else:
                break
            walked = lam * step
            if lam < 1.0:
                again = None  # damped: not yet in Newton's quadratic phase
            crawl = crawl + 1 if lam < 4.0 * lam_min else 0
            if crawl >= _CRAWL:
                break
        else:
            if res < 1e-7 and len(hist) >= min_iter:
                # iterations used up at the round-off floor (residual still creeping down)
                return st, steps, res, hist
        hist.append(res)
        raise _NewtonFailure(st, hist)


def _diagnose(theta, nu0, model, fail):
    """Turn a failed Newton solve into an error that says which case it is."""
    st = fail.state
    where = (
        f"theta = {theta:g} deg, nu0 = {nu0:g}, roughness = {model.roughness:g}, "
        f"wall_loss = {model.wall_loss:g}"
    )
    if st.L > 2e3:
        return NoSteadyFlowError(
            f"no steady flow at {where}: the density decay length diverges (y_max grew past "
            f"{st.L:.3g} diameters) — the angle is too large for this roughness"
        )
    if st.L < 2.0 or st.T.min() < 1e-3:
        how = (
            f"decay length {st.L:.2g} diameters, below one particle diameter"
            if st.L < 2.0
            else f"the temperature falls to {st.T.min():.2g}: the layer freezes"
        )
        return NoSteadyFlowError(
            f"no steady flow at {where}: the layer collapses ({how}) — the angle is too "
            "small for this roughness, or the floor density too low"
        )
    return ConvergenceError(
        f"steady solver did not converge at {where}: Newton stalled with residual "
        f"{fail.history[-1]:.2e} after {len(fail.history)} iterations"
    )

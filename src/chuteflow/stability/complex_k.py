"""The stability operator at complex wavenumber, and the eigenvalue α(k) as an analytic function.

The operator of :mod:`.operator` is a polynomial in ik plus the top decay conditions'
|k| term (k_z = 0):

    A(k) = A_0 + (ik) A_1 + (ik)² A_2 + κ(k) K,    κ(k) = √(k²), Re κ > 0.

For real k ≥ 0, κ = k = |k|: the far-field condition f' + |k| f = 0 of
:func:`chuteflow.equations.far_field_conditions` says that û, v̂, T̂ decay as exp(−|k| y)
above the layer. Its analytic continuation to complex k is f' + κ f = 0 with the principal
root κ = √(k²), the root with Re κ > 0, so that the continued perturbation still decays
into the dilute top. κ(k) = k in the right half-plane Re k > 0 and κ(k) = −k in the left
one; the branch cut is the imaginary axis Re k = 0, where k² ≤ 0, κ is imaginary and the
far field neither decays nor grows. A spatial branch k(ω) (:mod:`chuteflow.spatial`) is
continued inside Re k > 0 (waves of positive frequency travel down the slope with Re k > 0);
one that reaches the cut cannot be continued analytically on this sheet and is returned
flagged. Across the cut, the root continued analytically from Re k > 0 is κ = k itself
(``sheet="continued"``, :data:`SHEETS`): A(k) is then a polynomial in k, analytic in the whole
plane, and the perturbation grows into the top where Re k < 0. It is the sheet on which the
lab-frame saddle of :mod:`chuteflow.spatial.absolute` is sought.

α(k) is computed by Newton's method on the bordered system

    (A(k) − α B) v = 0,    cᴴ v = 1,

(unknowns v, α; c the start vector), started from a nearby eigenpair (the tracked temporal
mode at real k, or the previous point of a continuation). Its Jacobian
J = [[A − αB, −Bv], [cᴴ, 0]] at the solution also gives the derivatives exactly:
J (v', α') = (−A'(k) v, 0) and J (v'', α'') = (−A''v − 2(A' − α'B) v', 0), with
A' = i A_1 − 2k A_2 + κ'(k) K and A'' = −2 A_2 (κ' = ±1 off the cut). Everything is done on
the operator's equilibrated pencil (:meth:`~chuteflow.stability.Pencil.equilibrated`),
whose eigenvalues are the same.
"""

from __future__ import annotations

import cmath
import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from ..errors import ConvergenceError, ParameterError
from .operator import StabilityOperator

__all__ = ["SHEETS", "far_field_decay", "complex_matrices", "ComplexEigenpair", "eigenpair_at"]

#: The two sheets of κ(k): ``"principal"`` κ = √(k²), Re κ > 0 (the perturbation decays into
#: the dilute top); ``"continued"`` κ = k, the root continued analytically from Re k > 0 across
#: the cut (it grows into the top where Re k < 0). They agree on Re k > 0.
SHEETS = ("principal", "continued")

#: Newton on the bordered system also stops where its step on α stops shrinking (by 4×) at a
#: size below this fraction of max(1, |α|): the round-off floor, above ``tol`` near a multiple
#: eigenvalue (the residual test then decides).
STAGNATION_RTOL = 1e-10

#: α' and α'' are solved with the last Newton iteration's LU factors where that iteration's
#: step was below this fraction of the solution (relative errors of that order, below the
#: saddle and root tolerances of :mod:`chuteflow.spatial`); else J is factorised anew.
REUSE_RTOL = 1e-11


def _check_sheet(sheet: str) -> str:
    if sheet not in SHEETS:
        raise ParameterError(f"sheet = {sheet!r}: expected one of {', '.join(SHEETS)}")
    return sheet


def far_field_decay(k: complex, sheet: str = "principal") -> complex:
    """κ = √(k²) with Re κ > 0: the decay rate of the far-field condition f' + κ f = 0 at complex
    k (κ = |k| for real k). Raises :class:`~chuteflow.errors.ParameterError` on the branch cut
    Re k = 0 (k ≠ 0), where the continued perturbation does not decay into the dilute top.
    ``sheet="continued"``: κ = k at every k (:data:`SHEETS`; no cut, A(k) is a polynomial)."""
    k = complex(k)
    if _check_sheet(sheet) == "continued":
        return k
    if k.real == 0.0 and k.imag != 0.0:
        raise ParameterError(
            f"k = {k:.6g} lies on the branch cut Re k = 0 of the far-field decay rate √(k²): "
            "the perturbation would not decay into the dilute top"
        )
    return k if k.real >= 0 else -k


def complex_matrices(op: StabilityOperator, k: complex, *, derivatives: int = 0, sheet: str = "principal"):
    """The equilibrated A(k) at complex k (k_z = 0) and, with ``derivatives`` ≥ 1 (2), its
    first (and second) derivative in k; a tuple of 1 to 3 complex arrays (module docstring).
    ``sheet``: the root κ(k) of the far-field condition (:data:`SHEETS`)."""
    if op.three_d:
        raise ParameterError("complex k is implemented for the two-dimensional operator (k_z = 0)")
    k = complex(k)
    kappa = far_field_decay(k, sheet)
    dkappa = 1.0 if (sheet == "continued" or k.real >= 0) else -1.0
    pieces = op._pieces_eq
    rows, cols, vals = op._K_eq
    ik = 1j * k
    A = np.array(pieces[(0, 0)], dtype=complex)
    dA = np.zeros_like(A) if derivatives >= 1 else None
    d2A = np.zeros_like(A) if derivatives >= 2 else None
    for (b, d), P in pieces.items():
        if d != 0 or b == 0:
            continue
        A += ik**b * P
        if dA is not None:
            dA += (b * 1j * ik ** (b - 1)) * P
        if d2A is not None and b >= 2:
            d2A += (b * (b - 1) * (1j) ** 2 * ik ** (b - 2)) * P
    A[rows, cols] += kappa * vals
    if dA is not None:
        dA[rows, cols] += dkappa * vals
    out = [A]
    if dA is not None:
        out.append(dA)
    if d2A is not None:
        out.append(d2A)
    return tuple(out)


@dataclass(frozen=True, eq=False)
class ComplexEigenpair:
    """An eigenpair of the pencil at complex k (equilibrated), with α'(k) and α''(k).

    Attributes
    ----------
    k : complex
        The wavenumber.
    alpha : complex
        The eigenvalue α(k).
    dalpha, d2alpha : complex
        dα/dk and d²α/dk² of the branch through (k, α) (NaN if not asked for).
    w : ndarray
        The eigenvector of the equilibrated pencil (cᴴ w = 1 with c the start vector).
    residual : float
        ‖(A − αB) w‖ / (‖A‖ ‖w‖) (max norms).
    iterations : int
        Newton steps taken.
    """

    k: complex
    alpha: complex
    dalpha: complex
    d2alpha: complex
    w: np.ndarray
    residual: float
    iterations: int


def eigenpair_at(
    op: StabilityOperator,
    k: complex,
    alpha0: complex,
    w0: np.ndarray,
    *,
    derivatives: int = 1,
    tol: float = 1e-13,
    maxiter: int = 30,
    sheet: str = "principal",
) -> ComplexEigenpair:
    """Newton on the bordered system (module docstring) at complex ``k`` from (``alpha0``,
    ``w0``), an eigenpair estimate on the equilibrated pencil; with ``derivatives`` 1 or 2
    also α'(k) (and α''(k)). Raises :class:`~chuteflow.errors.ConvergenceError` when Newton
    does not settle (the start is too far from an eigenpair). ``sheet``: the root κ(k) of the
    far-field condition (:data:`SHEETS`; ``"continued"`` crosses the cut Re k = 0)."""
    mats = complex_matrices(op, k, derivatives=derivatives, sheet=sheet)
    A = mats[0]
    bd = np.diag(op.B_eq).astype(complex)
    M = A.shape[0]
    c = np.asarray(w0, dtype=complex)
    c = c / np.vdot(c, c).real ** 0.5
    v = c / np.vdot(c, c)
    alpha = complex(alpha0)
    J = np.zeros((M + 1, M + 1), dtype=complex)
    J[M, :M] = c.conj()
    scale = float(np.abs(A).max())
    lu = None
    it = 0
    prev = math.inf
    for it in range(1, maxiter + 1):
        J[:M, :M] = A
        J[np.arange(M), np.arange(M)] -= alpha * bd
        J[:M, M] = -bd * v
        r = np.concatenate([A @ v - alpha * bd * v, [np.vdot(c, v) - 1.0]])
        lu = sla.lu_factor(J, check_finite=False)
        dx = sla.lu_solve(lu, -r, check_finite=False)
        v = v + dx[:M]
        alpha = alpha + dx[M]
        if not (np.isfinite(alpha) and np.all(np.isfinite(dx))):
            break
        step = abs(dx[M])
        if step <= tol * max(1.0, abs(alpha)) and np.abs(dx[:M]).max() <= 1e-9 * np.abs(v).max():
            break
        # stagnation at the round-off floor (a near-multiple eigenvalue raises it above tol):
        # the step no longer shrinks, at a size that is noise next to the eigenvalue
        if it >= 6 and step <= STAGNATION_RTOL * max(1.0, abs(alpha)) and step >= 0.25 * prev:
            break
        prev = step
    res = float(np.abs(A @ v - alpha * bd * v).max() / (scale * np.abs(v).max()))
    if not (cmath.isfinite(alpha) and res < 1e-9):
        raise ConvergenceError(
            f"no eigenvalue near {complex(alpha0):.6g} at k = {complex(k):.6g}: Newton on the "
            f"pencil did not settle (relative residual {res:.1e})"
        )
    # the Jacobian at the solution: the last iteration's factorisation where its Newton step
    # was below REUSE_RTOL (the Jacobians then differ by that fraction), else refactored
    last_v = float(np.abs(dx[:M]).max()) if lu is not None else math.inf
    if derivatives >= 1 and (
        lu is None
        or last_v > REUSE_RTOL * float(np.abs(v).max())
        or abs(dx[M]) > REUSE_RTOL * max(1.0, abs(alpha))
    ):
        J[:M, :M] = A
        J[np.arange(M), np.arange(M)] -= alpha * bd
        J[:M, M] = -bd * v
        lu = sla.lu_factor(J, check_finite=False)
    da = d2a = complex(math.nan, math.nan)
    if derivatives >= 1:
        dA = mats[1]
        x = sla.lu_solve(lu, np.concatenate([-(dA @ v), [0.0]]), check_finite=False)
        dv, da = x[:M], complex(x[M])
        if derivatives >= 2:
            d2A = mats[2]
            rhs = -(d2A @ v) - 2.0 * (dA @ dv - da * bd * dv)
            x2 = sla.lu_solve(lu, np.concatenate([rhs, [0.0]]), check_finite=False)
            d2a = complex(x2[M])
    return ComplexEigenpair(complex(k), complex(alpha), da, d2a, v, res, it)

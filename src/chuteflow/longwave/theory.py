"""Long-wave expansion of the least-stable branch, α(k) = α1 k + α2 k² + O(k³) (§5.1.1, App. B).

At k = 0 the mass-conservation mode has α = 0 and eigenvector V0 = ∂X0/∂β, the derivative of
the steady flow along its family at fixed θ (Appendix B, eq. (B 18)), which the steady solver
gives exactly (:func:`chuteflow.steady.steady_tangent`). Writing the discrete operator as
A(k) = A0 + k P1 + k² P2 (P1 = i A1, P2 = −A2 of :meth:`StabilityOperator.series`) and
expanding A V = α B V with V = V0 + k V1 + k² V2,

    A0 V1 − α1 B V0 = −P1 V0,
    A0 V2 − α2 B V0 = α1 B V1 − P1 V1 − P2 V0,

each solved for (V_j, α_j) together as one *bordered* system [[A0, −B V0], [c, 0]] with the
normalisation c·V_j = ∫ ν̂_j dy = 0. Bordering replaces the solvability condition with the
adjoint vector, which is ill-conditioned here: a continuum of slowly settling density modes of
the dilute top (docs/errata.md, numerical notes) sits within ~1e-8 of α = 0. Rows and columns are
equilibrated before the LU for the same reason.

Checks: α1 = −i dQ0/dρ̄0 (Appendix B, eq. (B 2)) and α2 = lim Re α/k² + i Im … of the eigenvalues
at k ≲ 1e-6. Re α2 converges only algebraically in N (≈ N⁻⁴), hence the default N = 200 and the
reported convergence. Re α2 > 0 means long-wave instability; never decide stability at finite k
from α2 alone (the k² regime ends near k ~ 1e-5 … 1e-4 for P1).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla

from ..closures import ChuteModel
from ..conventions import long_wave_phase_velocity
from ..errors import ConvergenceError
from ..stability.dispersion import BranchTracker, after_lost_branch
from ..stability.modes import (
    OperatorCache,
    check_n,
    interp_vector,
    nearest_eigenpair,
    stability_operator,
    tail,
)
from ..stability.operator import StabilityOperator
from ..stability.policy import DEFAULT_POLICY, RejectionPolicy
from ..steady import SteadyFlow, steady_tangent

#: Wavenumbers of the eigenvalue-based k² coefficient Re α/k² (the range over which the
#: dispersion relation follows it, docs/errata.md "the k² regime is narrow").
EIG_KS = (1e-6, 1e-5, 1e-4)
#: The one that decides the long-wave sign: at 1e-6 the eigenvalue's round-off (~1e-12
#: absolute near the continuum) is 1e-4 of Re α; at 1e-5 Re α/k² converges to ~1e-6 by N ≈ 100
#: (P1, P2) and stays within a few per cent of its k → 0 limit.
K_EIG = 1e-5


def eigen_coefficient(
    flow: SteadyFlow,
    *,
    n: int = 100,
    n_max: int = 256,
    rtol: float = 1e-4,
    ks=EIG_KS,
    cache: OperatorCache | None = None,
):
    """Re α(k)/k² of the α(0) = 0 branch at the wavenumbers ``ks`` (from eigenvalues).

    Each eigenvalue is one shift-invert solve from the perturbative prediction
    (:func:`branch_point`); where that does not land on the branch (tested by distance and
    eigenvector tail), the branch is followed from k = 0 by
    :class:`~chuteflow.stability.BranchTracker` instead. Both at N and at 4N/5; N grows by
    25 % until Re α/k² at :data:`K_EIG` changes by less than ``rtol`` (relative) or N
    reaches ``n_max``.

    Returns
    -------
    (values, convergence, n)
        ``values`` (tuple of float, one per k; NaN where the branch was not reached), the
        relative change at :data:`K_EIG` and the resolution N.
    """
    ks = tuple(sorted(float(k) for k in ks))
    tangent = steady_tangent(flow)

    def at(nn):
        op = stability_operator(flow, nn, cache=cache)
        vals: list[float] = []
        tr = None
        for kk in ks:
            bp = branch_point(op, tangent, kk) if tr is None else None
            if bp is not None and math.isfinite(bp.coefficient):
                vals.append(bp.coefficient)
                continue
            if tr is None:
                tr = BranchTracker(flow, nn, n_max=nn, cache=cache)
            try:
                a, _ = tr.advance(kk)
                vals.append(float(a.real / kk**2))
            except ConvergenceError:
                vals.extend([math.nan] * (len(ks) - len(vals)))
                break
        return vals

    j = ks.index(K_EIG) if K_EIG in ks else len(ks) // 2
    ladder = RejectionPolicy(n_start=int(n), n_max=int(n_max))
    n2 = max(24, (4 * int(n)) // 5)
    prev = at(n2)
    nn = int(n)
    while True:
        cur = at(nn)
        conv = abs(cur[j] - prev[j]) / max(abs(cur[j]), 1e-300)
        if not math.isfinite(conv):
            conv = math.inf
        if conv <= rtol or nn >= ladder.n_max:
            return tuple(cur), float(conv), nn
        prev, nn = cur, ladder.next_n(nn)


@dataclass(frozen=True)
class EigenSign:
    """The long-wave coefficient from eigenvalues, resolved for its sign (sweeps).

    Attributes
    ----------
    theta, nu0 : float
        The steady flow.
    alpha1 : complex
        α1 = −i dQ0/dρ̄0 (Appendix B, eq. (B 2)) with dQ0/dρ̄0 from the exact steady tangent
        (:func:`chuteflow.steady.steady_tangent`): as accurate as the steady flow (measured
        ≤ 1e-9 relative at P1–P5 between steady N = 96 … 324). Perturbation theory on the
        stability grid converges to it only algebraically (≈ N⁻⁴, the dilute top: 6.8e-4 at
        P1, N = 48 mapped), so it is kept apart as :attr:`alpha1_taylor`.
    coefficient : float
        Re α(k)/k² of the branch's eigenvalue at k = :attr:`k` and N: the k² coefficient the
        dispersion relation follows (> 0: long-wave unstable).
    convergence : float
        |coefficient(N) − coefficient(N')| / |coefficient(N)|, N' = round(0.8 N).
    alpha2_taylor : complex
        The strict Taylor α2 at N (dominated by the dilute top's continuum on coarse grids;
        reported, not used for the sign).
    k : float
        Wavenumber of the eigenvalue (:data:`K_EIG`).
    n : int
        Resolution N.
    converged : bool
        ``convergence`` met the requested tolerance by ``n_max``.
    alpha1_taylor : complex
        α1 of bordered perturbation theory on the stability grid at N (the operator's own
        k → 0 limit; its relative distance from :attr:`alpha1` measures the grid's error
        there).
    """

    theta: float
    nu0: float
    alpha1: complex
    coefficient: float
    convergence: float
    alpha2_taylor: complex
    k: float
    n: int
    converged: bool
    alpha1_taylor: complex = complex("nan")

    @property
    def unstable(self) -> bool:
        """Long-wave unstable: Re α(k)/k² > 0 (same rule as :attr:`LongWave.unstable`)."""
        return bool(self.coefficient > 0)


def eigen_sign(
    flow: SteadyFlow,
    *,
    n: int = 48,
    n_max: int = 160,
    rtol: float = 0.05,
    k: float = K_EIG,
    cache: OperatorCache | None = None,
    taylor: bool = True,
) -> EigenSign:
    """Re α(k)/k² at k = :data:`K_EIG` with its convergence, cheaply (one flow of a sweep).

    :func:`branch_point` at N and N' = round(0.8 N) on the (sinh-mapped) stability grid,
    N raised along the ladder N → round(1.25 N) (each rung's N' is the previous rung, so it
    is reused; the first N' is solved from the eigenpair at N, without the Taylor
    coefficients that only N reports) until the two agree to ``rtol`` relative — with the
    default 0.05 the sign is decided with a margin of 20 — or N reaches ``n_max``. Measured
    N at the paper's points: 48–75 (``benchmarks/bench_longwave.py``). Where the
    perturbative solve misses the branch (k = 1e-5 beyond the k² regime, e.g. ν0(0) ≲
    0.02), the shift is the branch on another rung, or the eigenvalue comes from
    :class:`~chuteflow.stability.BranchTracker`.

    ``taylor`` (default True): the finer rung also computes the strict Taylor α1, α2 by
    bordered perturbation theory (:attr:`EigenSign.alpha2_taylor`, ``alpha1_taylor``; a
    sixth of the work) and starts its eigenvalue solve from them; with False they are NaN
    and the solve starts from the exact α1 k and the null vector V0 (:func:`branch_point`).
    """
    tangent = steady_tangent(flow)
    ladder = RejectionPolicy(n_start=int(n), n_max=int(n_max))
    memo: dict[int, BranchPoint] = {}

    def at(nn: int, ref: BranchPoint | None = None) -> BranchPoint:
        if nn not in memo and ref is not None and ref.vector is not None:
            # the check rung N' of the finer ref: started from ref's eigenpair, without the
            # Taylor coefficients (only the finer rung's are reported)
            op = stability_operator(flow, nn, cache=cache)
            v0 = interp_vector(ref.vector, len(op.fields), ref.n, nn)
            bp = branch_point(op, tangent, k, guess=ref.alpha, v0=v0, taylor=False)
            if math.isfinite(bp.coefficient):
                memo[nn] = bp
        if nn not in memo:
            op = stability_operator(flow, nn, cache=cache)
            bp = branch_point(op, tangent, k, taylor=taylor)
            unresolved = bp.tail > DEFAULT_POLICY.track_tail_tol and nn < ladder.n_max
            if not math.isfinite(bp.coefficient) and not unresolved:
                # beyond the k² regime at k (dilute flows): from the branch on another rung,
                # else by continuation from k = 0 once (an unresolved rung is passed by)
                done = [(q, q.vector) for q in memo.values() if q.vector is not None]
                if done:
                    q, vec = done[-1]
                    assert vec is not None
                    v0 = interp_vector(vec, len(op.fields), q.n, nn)
                    # (the Taylor coefficients, if asked for, are those of the first solve)
                    again = branch_point(op, tangent, k, guess=q.alpha, v0=v0, taylor=False)
                    bp = dataclasses.replace(again, alpha1=bp.alpha1, alpha2=bp.alpha2)
                if not math.isfinite(bp.coefficient):
                    try:
                        try:
                            a, w = BranchTracker(flow, nn, n_max=nn, cache=cache).advance(k)
                        except ConvergenceError:
                            # through k/10 first: where the k² regime ends below k the first
                            # step from k = 0 must stay inside it (θ = 20.14°, φ = 0.1, ν0(0) =
                            # 3.1e-4, h = 84: Re α/k² = 2.3e6 at k = 1e-6, −6508 at 1e-5; to k
                            # directly the predictor misses by 1.2 of any step)
                            tr = BranchTracker(flow, nn, n_max=nn, cache=cache)
                            tr.advance(k / 10)
                            a, w = tr.advance(k)
                        bp = dataclasses.replace(bp, alpha=complex(a), vector=w)
                    except ConvergenceError:
                        # lost near the continuum: as least_stable answers there
                        # (after_lost_branch; at these k, the relaxed tail threshold)
                        m = after_lost_branch(flow, k, n=nn, cache=cache)
                        if m is not None:
                            bp = dataclasses.replace(bp, alpha=m.alpha, vector=None)
            memo[nn] = bp
        return memo[nn]

    nn = ladder.n_start
    while True:
        cur = at(nn)
        prev = at(check_n(nn), cur)
        conv = abs(cur.coefficient - prev.coefficient) / max(abs(cur.coefficient), 1e-300)
        if not math.isfinite(conv):
            conv = math.inf
        if conv <= rtol or nn >= ladder.n_max:
            break
        nn = ladder.next_n(nn)
    return EigenSign(
        flow.theta,
        flow.nu0,
        complex(0.0, -float(tangent["dQ_drho"])),
        cur.coefficient,
        float(conv),
        cur.alpha2,
        float(k),
        nn,
        bool(conv <= rtol),
        cur.alpha1,
    )


@dataclass(frozen=True)
class LongWave:
    """Long-wave coefficients of the least-stable branch of one steady flow.

    Attributes
    ----------
    theta, nu0 : float
        The steady flow (degrees, floor density).
    alpha1, alpha2 : complex
        α(k) = α1 k + α2 k² + O(k³) for perturbations ∝ exp(αt + ikx) (eq. 4.4).
    dQ_drho : float
        dQ0/dρ̄0 along the family at fixed θ (eq. B 6); Appendix B: α1 = −i dQ0/dρ̄0.
    n : int
        Chebyshev intervals of the finer resolution.
    convergence_alpha1, convergence_alpha2 : float
        Relative change of α1 and α2 between n and 4n/5.
    k_check, alpha_check : float, complex
        A small wavenumber and the eigenvalue there (see :attr:`alpha2_from_eigenvalue`).
    model : ChuteModel or None
        Parameters and closures of the steady flow the coefficients were computed for.
    converged : bool
        The Taylor coefficients met ``rtol`` by ``n_max`` (else they are the estimate at
        ``n``, with :attr:`convergence_alpha2` saying how far they are from it).
    eig_k : tuple of float
        Wavenumbers of the eigenvalue-based coefficient (default 1e-6, 1e-5, 1e-4).
    eig_alpha2 : tuple of float
        Re α(k)/k² of the tracked branch at ``eig_k``: the k² coefficient the dispersion
        relation follows there (docs/errata.md: the strict Taylor α2 feels the dilute-top continuum
        within ~1e-8 of α = 0, which eigenvalues at k ≳ 1e-6 do not).
    eig_convergence : float
        Relative change of Re α(k)/k² at k = :data:`K_EIG` between N_eig and 4N_eig/5.
    eig_n : int
        Resolution of the eigenvalue-based coefficient.
    """

    theta: float
    nu0: float
    alpha1: complex
    alpha2: complex
    dQ_drho: float
    n: int
    convergence_alpha1: float
    convergence_alpha2: float
    k_check: float = float("nan")
    alpha_check: complex = complex("nan")
    model: ChuteModel | None = None
    converged: bool = True
    eig_k: tuple = ()
    eig_alpha2: tuple = ()
    eig_convergence: float = float("nan")
    eig_n: int = 0

    @property
    def alpha2_eig(self) -> float:
        """Re α/k² of the eigenvalue at k = :data:`K_EIG` (1e-5): the robust long-wave
        coefficient (NaN when not computed)."""
        for kk, v in zip(self.eig_k, self.eig_alpha2):
            if kk == K_EIG:
                return float(v)
        return float("nan")

    @property
    def sign_consistent(self) -> bool:
        """The Taylor Re α2 and the eigenvalue-based Re α/k² agree in sign (True when the
        latter was not computed)."""
        e = self.alpha2_eig
        return not math.isfinite(e) or (e > 0) == (self.alpha2.real > 0)

    @property
    def alpha2_from_eigenvalue(self) -> complex:
        """(α(k) − α1 k)/k² from the eigenvalue at ``k_check``: the k² coefficient as the
        eigenvalues see it, for comparison with the perturbative α2."""
        return (self.alpha_check - self.alpha1 * self.k_check) / self.k_check**2

    @property
    def phase_velocity(self) -> float:
        """Long-wave phase velocity c = −Im α1 = dQ0/dρ̄0, positive down the slope (the
        convention of :mod:`chuteflow.conventions`)."""
        return long_wave_phase_velocity(self.alpha1)

    @property
    def unstable(self) -> bool:
        """Long-wave unstable: Re α/k² > 0 from the eigenvalue at k = 1e-5
        (:attr:`alpha2_eig`, converged to ~1e-6 at N ≈ 100), else Re α2 > 0 (Taylor)."""
        e = self.alpha2_eig
        return bool(e > 0) if math.isfinite(e) else bool(self.alpha2.real > 0)

    def summary(self) -> dict:
        return {
            "theta": self.theta,
            "nu0": self.nu0,
            "alpha1_re": self.alpha1.real,
            "alpha1_im": self.alpha1.imag,
            "alpha2_re": self.alpha2.real,
            "alpha2_im": self.alpha2.imag,
            "dQ_drho": self.dQ_drho,
            "n": self.n,
            "convergence_alpha1": self.convergence_alpha1,
            "convergence_alpha2": self.convergence_alpha2,
            "k_check": self.k_check,
            "alpha2_from_eigenvalue_re": self.alpha2_from_eigenvalue.real,
            "alpha2_from_eigenvalue_im": self.alpha2_from_eigenvalue.imag,
            "long_wave_unstable": bool(self.unstable),
            "converged": bool(self.converged),
            "alpha2_eig_re": self.alpha2_eig,
            "eig_k": list(self.eig_k),
            "eig_alpha2_re": list(self.eig_alpha2),
            "eig_convergence": self.eig_convergence,
            "eig_n": self.eig_n,
            "sign_consistent": bool(self.sign_consistent),
            **(self.model.to_dict() if self.model is not None else {}),
        }


def null_vector(op: StabilityOperator, tangent: dict) -> np.ndarray:
    """V0 = ∂X0/∂β at fixed height y on the operator's grid (v̂ = ŵ = 0).

    The tangent is taken at fixed ξ = y/y_max; at fixed y, ∂f/∂β|_y = ∂f/∂β|_ξ − (y/y_max)
    (dy_max/dβ) f'(y).
    """
    y = op.grid.y
    fixed_y = fixed_height_tangent(op.flow, tangent, y)
    parts = [fixed_y[f] if f in fixed_y else np.zeros_like(y) for f in op.fields]
    return np.concatenate(parts)


def fixed_height_tangent(flow, tangent: dict, y: np.ndarray) -> dict[str, np.ndarray]:
    """∂ν0/∂β, ∂u0/∂β, ∂T0/∂β at fixed height, at the heights ``y`` (keys "nu", "u", "T";
    the non-zero fields of :func:`null_vector`)."""
    g, L, dL = flow.grid, flow.y_max, tangent["y_max"]
    shift = (g.y / L) * dL
    fixed_y = {
        "nu": flow.nu * tangent["log_nu"] - shift * (g.D @ flow.nu),
        "u": tangent["u"] - shift * (g.D @ flow.u),
        "T": tangent["T"] - shift * (g.D @ flow.T),
    }
    # one Clenshaw evaluation of the three series (the same numbers as one at a time)
    vals = g.interpolate(np.stack(list(fixed_y.values())), y)
    return dict(zip(fixed_y, vals))


def coefficients(op: StabilityOperator, tangent: dict) -> tuple[complex, complex]:
    """(α1, α2) of one discretised operator by bordered perturbation theory."""
    return bordered_coefficients(op, tangent, *op.series_products())


def bordered_coefficients(
    op: StabilityOperator, tangent: dict, A0: np.ndarray, P1, P2
) -> tuple[complex, complex]:
    """(α1, α2) of A(s) = A0 + s P1 + s² P2 + … (A(s)V = αBV, α = α1 s + α2 s² + …).

    P1 and P2 are matrices or functions x ↦ P x
    (:meth:`~chuteflow.stability.operator.StabilityOperator.series_products`).

    Bordered perturbation theory at s = 0: the null vector V0 = ∂X0/∂β normalised by
    ∫ ν̂ dy = 1, one LU of the bordered (equilibrated) matrix [A0, −BV0; c, 0] and two
    solves give (V1, α1) and α2.
    """
    a1, a2, _, _ = _bordered(op, tangent, A0, P1, P2)
    return a1, a2


def _bordered(op, tangent, A0, P1, P2):
    """(α1, α2, V0, V1) of :func:`bordered_coefficients` (V0, V1 of (A, B), not equilibrated)."""
    B = np.asarray(op.B, dtype=float)
    M = A0.shape[0]
    V0 = null_vector(op, tangent)
    c = np.zeros(M)
    i = op.fields.index("nu") * (op.n + 1)
    c[i : i + op.n + 1] = op.grid.weights  # c·V = ∫ ν̂ dy
    V0 = V0 / (c @ V0)
    bord = np.zeros((M + 1, M + 1))
    bord[:M, :M] = A0
    bord[:M, M] = -(B @ V0)
    bord[M, :M] = c
    rs = 1.0 / np.abs(bord).max(axis=1)
    bord *= rs[:, None]
    cs = 1.0 / np.abs(bord).max(axis=0)
    bord *= cs[None, :]
    lu = sla.lu_factor(bord, overwrite_a=True, check_finite=False)

    def solve(rhs):
        r = np.concatenate([rhs, [0.0]]) * rs
        x = sla.lu_solve(lu, r.real, check_finite=False) + 1j * sla.lu_solve(lu, r.imag, check_finite=False)
        x *= cs
        return x[:M], x[M]

    def times(P, x):  # P a matrix or a function x ↦ P x (StabilityOperator.series_products)
        return P(x) if callable(P) else P @ x

    V1, a1 = solve(-times(P1, V0))
    _, a2 = solve(a1 * (B @ V1) - times(P1, V1) - times(P2, V0))
    return complex(a1), complex(a2), V0, V1


@dataclass(frozen=True)
class BranchPoint:
    """The α(0) = 0 branch at one small k on one grid, from perturbation theory and one
    eigenvalue solve (:func:`branch_point`).

    Attributes
    ----------
    alpha1, alpha2 : complex
        Taylor coefficients (bordered perturbation theory at k = 0) on this grid.
    k : float
        The wavenumber of the eigenvalue.
    alpha : complex
        The eigenvalue of the branch at k (NaN when the solve did not land on the branch).
    tail : float
        Chebyshev tail of its eigenvector (the paper's statistic).
    n : int
        Resolution N.
    vector : ndarray or None
        The eigenvector (of the equilibrated pencil; None when ``alpha`` is NaN).
    """

    alpha1: complex
    alpha2: complex
    k: float
    alpha: complex
    tail: float
    n: int
    vector: np.ndarray | None = field(default=None, repr=False)

    @property
    def coefficient(self) -> float:
        """Re α(k)/k² (NaN when the eigenvalue is missing)."""
        return float(self.alpha.real / self.k**2)


def branch_point(
    op: StabilityOperator,
    tangent: dict,
    k: float = 1e-5,
    *,
    guess: complex | None = None,
    v0=None,
    taylor: bool = True,
) -> BranchPoint:
    """α1, α2 and the branch's eigenvalue α(k) at a small k on the grid of ``op``.

    The eigenvalue is the one nearest α1 k by shift-invert on the equilibrated pencil,
    started from the perturbative eigenvector V0 + k V1: one more LU than the Taylor
    coefficients, and no continuation from k = 0 (the same first step as
    :class:`~chuteflow.stability.BranchTracker`). α2 k² is not used in the shift: on coarse
    grids the Taylor α2 is dominated by the dilute top's continuum within ~1e-8 of α = 0
    (at P1, N = 48: 2.6e6 against Re α/k² ≈ 1.2e4). The answer is kept only when it lies
    within a quarter of |α1 k| of the prediction in Im α (Re α is what is measured) and its
    eigenvector is resolved (tail below :attr:`RejectionPolicy.track_tail_tol`, which the
    continuum of the dilute top fails); otherwise ``alpha`` is NaN. With ``guess`` and
    ``v0`` (the branch at k on another grid, ``v0`` on this one), the shift is ``guess``
    and the answer must lie within 5 % of it. ``taylor=False`` skips the Taylor coefficients
    (``alpha1``, ``alpha2`` NaN: the bordered matrix's LU and solves less); without
    ``guess`` the shift is then the exact α1 k, α1 = −i dQ0/dρ̄0 of the steady tangent
    (eq. (B 2)), and the start the null vector V0 (:func:`null_vector`), which differs from
    the eigenvector at k by O(k): the same eigenpair, to the solve's round-off.
    """
    a1 = a2 = complex("nan")
    if taylor:
        a1, a2, V0, V1 = _bordered(op, tangent, *op.series_products())
        pred, start = a1 * k, (V0 + k * V1) / op.col_eq
    elif guess is None:
        # without perturbation theory: the exact slope α1 = −i dQ0/dρ̄0 (eq. (B 2)) and the
        # k = 0 null vector V0 (the eigenvector at k differs from it by O(k))
        pred, start = complex(0.0, -float(tangent["dQ_drho"])) * k, null_vector(op, tangent) / op.col_eq
    if guess is not None:
        pred, start = complex(guess), v0
    pencil = op.pencil(k)
    alpha, t, vec = complex("nan"), math.inf, None
    try:
        a, w = nearest_eigenpair(pencil, pred, v0=start)
        t = tail(pencil.unscale(w), len(op.fields))
        near = (
            abs(a.imag - pred.imag) <= 0.25 * abs(pred)
            if guess is None
            else abs(a - pred) <= 0.05 * abs(pred)
        )
        if near and t <= DEFAULT_POLICY.track_tail_tol:
            alpha, vec = complex(a), w
    except ConvergenceError:
        pass
    return BranchPoint(a1, a2, float(k), alpha, float(t), op.n, vec)


def longwave(
    flow: SteadyFlow,
    n: int = 200,
    *,
    rtol: float = 1e-2,
    n_max: int = 480,
    k_check: float | None = 1e-6,
    strict: bool = True,
    eig_ks=EIG_KS,
) -> LongWave:
    """Long-wave coefficients α1, α2 of the least-stable branch (perturbation theory at k = 0).

    Parameters
    ----------
    flow : SteadyFlow
        The base state.
    n : int
        Starting number of Chebyshev intervals per field. α1, α2 are computed at 4n/5 and n,
        and n is raised by 25 % until α2 changes by less than ``rtol`` (α1 by less than
        ``rtol``/100).
    rtol : float
        Accepted relative change of α2 between resolutions. Re α2 converges only
        algebraically (≈ N⁻⁴) when the domain reaches far into the dilute layer
        (``flow.nu_top`` = 1e-9 needs N ≈ 300–400 for 1 %); for a sign only, 0.2 suffices.
    n_max : int
        Largest resolution tried.
    k_check : float or None
        Wavenumber of the eigenvalue cross-check; None skips it (sign-only sweeps).
    strict : bool
        True (default): raise when ``rtol`` is not met by ``n_max``. False: return the
        estimate at ``n_max`` flagged ``converged = False`` (its relative change in
        :attr:`LongWave.convergence_alpha2`).
    eig_ks : tuple of float or None
        Wavenumbers of the eigenvalue-based coefficient Re α/k² (:func:`eigen_coefficient`,
        default 1e-6, 1e-5, 1e-4); it decides :attr:`LongWave.unstable`. Empty or None
        skips it.

    Raises
    ------
    ConvergenceError
        With ``strict=True``, if the target is not reached by ``n_max``.

    Notes
    -----
    The eigenvalue at ``k_check`` (default 1e-6) is computed too, by shift-invert from
    α1 k + α2 k² on the equilibrated pencil, and kept in the result
    (``alpha2_from_eigenvalue``). The two differ by a few per cent for ν_top = 1e-9: at
    k → 0 the branch interacts with the near-neutral continuum of the dilute top (gap
    ~1e-8), which the strict k² coefficient includes and eigenvalues at k ≳ 1e-7 do not
    (at P2 the Taylor Re α2 is −91 at N = 480, +841 at N = 100, while Re α/k² at
    k = 1e-5 is −39.996 from N = 100 on). :attr:`LongWave.unstable` is therefore decided
    by the eigenvalue-based coefficient (:func:`eigen_coefficient`).
    """
    tangent = steady_tangent(flow)
    n = int(n)
    # the stability solvers' resolution ladder (N → round(1.25 N)), from n up to n_max
    ladder = RejectionPolicy(n_start=n, n_max=int(n_max))
    n2 = max(24, (4 * n) // 5)
    # the Taylor α2 on the plain Chebyshev grid: it converges there faster than on the
    # sinh-mapped grid, which takes nodes from the dilute top whose continuum it feels (P2,
    # N = 100: Re α2 = 846 plain, 1.2e4 mapped; both → −91 … −40 only algebraically)
    plain = OperatorCache(2, mapped=False)
    b1, b2 = coefficients(stability_operator(flow, n2, cache=plain), tangent)
    while True:
        op = stability_operator(flow, n, cache=plain)
        a1, a2 = coefficients(op, tangent)
        c1 = abs(a1 - b1) / max(abs(a1), 1e-300)
        c2 = abs(a2 - b2) / max(abs(a2), 1e-300)
        ok = math.isfinite(c1) and math.isfinite(c2) and c2 <= rtol and c1 <= rtol / 100
        if ok or n >= n_max:
            break
        b1, b2, n2, n = a1, a2, n, ladder.next_n(n)
    if not ok and strict:
        raise ConvergenceError(
            f"long-wave coefficients at theta = {flow.theta:g}, nu0 = {flow.nu0:g} did not "
            f"converge: relative change of alpha1 {c1:.1e}, alpha2 {c2:.1e} between n = {n2} "
            f"and n = {n} (rtol = {rtol:g}); raise n_max or rtol"
        )
    check = complex("nan")
    if k_check:
        try:
            check, _ = nearest_eigenpair(op.pencil(k_check), a1 * k_check + a2 * k_check**2)
        except ConvergenceError:
            if strict:
                raise
    eig_k: tuple[float, ...] = ()
    eig_vals: tuple = ()
    eig_conv, eig_n = float("nan"), 0
    if eig_ks:
        eig_k = tuple(sorted(float(k) for k in eig_ks))
        eig_vals, eig_conv, eig_n = eigen_coefficient(flow, ks=eig_k)
    return LongWave(
        flow.theta,
        flow.nu0,
        a1,
        a2,
        float(tangent["dQ_drho"]),
        n,
        float(c1),
        float(c2),
        float(k_check or float("nan")),
        check,
        model=flow.model,
        converged=bool(ok),
        eig_k=eig_k,
        eig_alpha2=eig_vals,
        eig_convergence=eig_conv,
        eig_n=eig_n,
    )

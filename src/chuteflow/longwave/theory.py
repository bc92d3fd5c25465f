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

The α2 reported to users (:attr:`LongWave.alpha2`) is not this Taylor coefficient but the
dispersion relation's: (α(k) − α1 k)/k² from the branch's eigenvalue at k = 1e-5 with the
exact α1 = −i dQ0/dρ̄0 (Appendix B, eq. (B 2)), so Re α2 = Re α(k)/k², which converges
spectrally. The strict Taylor α2 (:attr:`LongWave.alpha2_taylor`) feels the dilute top's
continuum and converges only algebraically in N (≈ N⁻⁴): at P4 its real part is about half
of the dispersion relation's (docs/errata.md, note 4). Re α2 > 0 means long-wave
instability; never decide stability at finite k from α2 alone (the k² regime ends near
k ~ 1e-5 … 1e-4 for P1).
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
from ..stability.lost import after_lost_branch
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
from ..stability.tracking import BranchTracker
from ..steady import SteadyFlow, steady_tangent

#: Wavenumbers of the eigenvalue-based k² coefficient Re α/k² (the range over which the
#: dispersion relation follows it, docs/errata.md "the k² regime is narrow").
EIG_KS = (1e-6, 1e-5, 1e-4)
#: The one that decides the long-wave sign: at 1e-6 the eigenvalue's round-off (~1e-12
#: absolute near the continuum) is 1e-4 of Re α; at 1e-5 Re α/k² converges to ~1e-6 by N ≈ 100
#: (P1, P2) and stays within a few per cent of its k → 0 limit.
K_EIG = 1e-5
#: Largest relative change of Re α2 between its two finest rungs with which
#: :attr:`LongWave.converged` holds: the sign of α2 (long-wave stability) is then decided.
ALPHA2_SIGN_RTOL = 0.2


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
    cur, _, conv, nn = branch_eigenvalues(flow, n=n, n_max=n_max, rtol=rtol, ks=ks, cache=cache)
    return tuple(float(a.real / kk**2) for a, kk in zip(cur, ks)), conv, nn


def branch_eigenvalues(
    flow: SteadyFlow,
    *,
    n: int = 100,
    n_max: int = 256,
    rtol: float = 1e-4,
    ks=EIG_KS,
    cache: OperatorCache | None = None,
) -> tuple[tuple[complex, ...], tuple[complex, ...], float, int]:
    """The eigenvalues α(k) of the α(0) = 0 branch behind :func:`eigen_coefficient`.

    Same ladder and stopping rule (relative change of Re α/k² at :data:`K_EIG`).

    Returns
    -------
    (alphas, alphas_check, convergence, n)
        The eigenvalues at the sorted ``ks`` at the final N and at the rung below it (NaN
        where the branch was not reached), the relative change of Re α/k² at
        :data:`K_EIG` between them, and N.
    """
    ks = tuple(sorted(float(k) for k in ks))
    tangent = steady_tangent(flow)

    def at(nn) -> list[complex]:
        op = stability_operator(flow, nn, cache=cache)
        vals: list[complex] = []
        tr = None
        for kk in ks:
            bp = branch_point(op, tangent, kk) if tr is None else None
            if bp is not None and math.isfinite(bp.coefficient):
                vals.append(complex(bp.alpha))
                continue
            if tr is None:
                tr = BranchTracker(flow, nn, n_max=nn, cache=cache)
            try:
                a, _ = tr.advance(kk)
                vals.append(complex(a))
            except ConvergenceError:
                vals.extend([complex("nan")] * (len(ks) - len(vals)))
                break
        return vals

    j = ks.index(K_EIG) if K_EIG in ks else len(ks) // 2
    ladder = RejectionPolicy(n_start=int(n), n_max=int(n_max))
    n2 = max(24, (4 * int(n)) // 5)
    prev = at(n2)
    nn = int(n)
    while True:
        cur = at(nn)
        conv = abs(cur[j].real - prev[j].real) / max(abs(cur[j].real), 1e-300)
        if not math.isfinite(conv):
            conv = math.inf
        if conv <= rtol or nn >= ladder.n_max:
            return tuple(cur), tuple(prev), float(conv), nn
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

    α(k) = α1 k + α2 k² + O(k³) for perturbations ∝ exp(αt + ikx) (eq. 4.4). :attr:`alpha2`
    is the k² coefficient of the dispersion relation, from the branch's eigenvalue at
    k = :attr:`alpha2_k` (default :data:`K_EIG` = 1e-5); the strict Taylor coefficient of
    perturbation theory at k = 0 is the diagnostic :attr:`alpha2_taylor`.

    Attributes
    ----------
    theta, nu0 : float
        The steady flow (degrees, floor density).
    alpha1 : complex
        α1 by bordered perturbation theory at k = 0 (plain grid, N = :attr:`n`); Appendix B:
        α1 = −i dQ0/dρ̄0.
    alpha2 : complex
        α2 = (α(k) − α1 k)/k² at k = :attr:`alpha2_k` (1e-5), α(k) the eigenvalue of the
        α(0) = 0 branch (:func:`branch_eigenvalues`, sinh-mapped grid, N = :attr:`eig_n`)
        and α1 = −i dQ0/dρ̄0 exactly (steady tangent), so Re α2 = Re α(k)/k²: the
        coefficient the dispersion relation follows, whose sign decides long-wave stability
        (:attr:`unstable`). The exact α1 keeps the grid's O(N⁻⁴) error of α1, which 1/k
        would amplify, out of Im α2. NaN when the eigenvalues were not computed.
    alpha2_convergence, alpha2_im_convergence : float
        Relative change of Re α2 and of Im α2 between N = :attr:`eig_n` and the rung below
        it (4N/5 … N/1.25): the estimate of their relative error.
    alpha2_k : float
        The wavenumber of :attr:`alpha2`.
    dQ_drho : float
        dQ0/dρ̄0 along the family at fixed θ (eq. B 6); Appendix B: α1 = −i dQ0/dρ̄0.
    n : int
        Chebyshev intervals of the finer resolution of α1 and the Taylor α2.
    convergence_alpha1 : float
        Relative change of α1 between n and 4n/5.
    alpha2_taylor : complex
        The strict Taylor coefficient α2 by bordered perturbation theory at k = 0 (plain
        grid, N = :attr:`n`; the paper's Appendix B). A diagnostic: it feels the near-neutral
        continuum of the dilute top within ~1e-8 of α = 0, which the eigenvalues at
        k ≳ 1e-6 do not, and converges only algebraically in N (docs/errata.md, note 4;
        at P4 Re α2 is 44.2 while the Taylor value at N = 390 is 22.9).
    alpha2_taylor_convergence : float
        Relative change of the Taylor α2 between n and 4n/5.
    taylor_converged : bool
        The Taylor coefficients met ``rtol`` by ``n_max`` (else they are the estimate at
        ``n``, with :attr:`alpha2_taylor_convergence` saying how far they are from it).
    k_check, alpha_check : float, complex
        A second small wavenumber (default 1e-6) and the eigenvalue there on the Taylor
        coefficients' grid (see :attr:`alpha2_check`).
    model : ChuteModel or None
        Parameters and closures of the steady flow the coefficients were computed for.
    eig_k : tuple of float
        Wavenumbers of the eigenvalues (default 1e-6, 1e-5, 1e-4).
    eig_alpha2 : tuple of float
        Re α(k)/k² of the tracked branch at ``eig_k``: how far the k² regime extends
        (docs/errata.md, note 4); the entry at :attr:`alpha2_k` is Re :attr:`alpha2`.
    eig_n : int
        Resolution of the eigenvalues.
    """

    theta: float
    nu0: float
    alpha1: complex
    alpha2: complex
    dQ_drho: float
    n: int
    convergence_alpha1: float
    alpha2_taylor: complex = complex("nan")
    alpha2_taylor_convergence: float = float("nan")
    alpha2_convergence: float = float("nan")
    alpha2_im_convergence: float = float("nan")
    alpha2_k: float = float("nan")
    k_check: float = float("nan")
    alpha_check: complex = complex("nan")
    model: ChuteModel | None = None
    taylor_converged: bool = True
    eig_k: tuple = ()
    eig_alpha2: tuple = ()
    eig_n: int = 0

    @property
    def converged(self) -> bool:
        """:attr:`alpha2`, the coefficient that decides long-wave stability, was reached and
        its real part changed by at most :data:`ALPHA2_SIGN_RTOL` (20 %) between its two
        finest rungs, so its sign is decided. The Taylor coefficients are a diagnostic
        (:attr:`taylor_converged`); :attr:`note` says what is not converged."""
        return bool(math.isfinite(self.alpha2.real) and self.alpha2_convergence <= ALPHA2_SIGN_RTOL)

    @property
    def note(self) -> str:
        """Empty when :attr:`converged` and the Taylor diagnostic converged too; else why not."""
        parts = []
        if not math.isfinite(self.alpha2.real):
            parts.append(
                f"the branch's eigenvalue at k = {self.alpha2_k:g} was not reached: alpha2 is "
                "unknown and the sign is that of the Taylor alpha2"
            )
        elif not self.alpha2_convergence <= ALPHA2_SIGN_RTOL:
            parts.append(
                f"Re alpha2 changed by {self.alpha2_convergence:.1e} (relative) between N = "
                f"{self.eig_n} and the rung below"
            )
        if not self.taylor_converged:
            parts.append(
                "the Taylor coefficients (a diagnostic) changed by "
                f"{self.alpha2_taylor_convergence:.1e} at N = {self.n}"
            )
        return "; ".join(parts)

    @property
    def sign_consistent(self) -> bool:
        """The Taylor Re α2 and Re :attr:`alpha2` agree in sign (True when the latter was not
        computed)."""
        e = self.alpha2.real
        return not math.isfinite(e) or (e > 0) == (self.alpha2_taylor.real > 0)

    @property
    def alpha2_check(self) -> complex:
        """(α(k) − α1 k)/k² from the eigenvalue at ``k_check`` (1e-6) on the Taylor
        coefficients' grid, α1 the Taylor one: a check of :attr:`alpha2` and
        :attr:`alpha2_taylor`. At 1e-6 the eigenvalue's round-off (~1e-12 near the
        continuum) is ~1 in α2 (P4: 12 … 55 with round-off-level changes of the flow)."""
        return (self.alpha_check - self.alpha1 * self.k_check) / self.k_check**2

    @property
    def phase_velocity(self) -> float:
        """Long-wave phase velocity c = −Im α1 = dQ0/dρ̄0, positive down the slope (the
        convention of :mod:`chuteflow.conventions`)."""
        return long_wave_phase_velocity(self.alpha1)

    @property
    def unstable(self) -> bool:
        """Long-wave unstable: Re :attr:`alpha2` > 0 (Re α/k² from the eigenvalue at
        k = 1e-5), else, where that was not computed, the Taylor Re α2 > 0."""
        e = self.alpha2.real
        return bool(e > 0) if math.isfinite(e) else bool(self.alpha2_taylor.real > 0)

    def to_dict(self) -> dict:
        """JSON-ready dict (the keys of ``chuteflow longwave --json``, docs/cli.md)."""
        check = self.alpha2_check
        return {
            "theta": self.theta,
            "nu0": self.nu0,
            "alpha1_re": self.alpha1.real,
            "alpha1_im": self.alpha1.imag,
            "alpha2_re": self.alpha2.real,
            "alpha2_im": self.alpha2.imag,
            "alpha2_convergence": self.alpha2_convergence,
            "alpha2_im_convergence": self.alpha2_im_convergence,
            "alpha2_k": self.alpha2_k,
            "dQ_drho": self.dQ_drho,
            "n": self.n,
            "convergence_alpha1": self.convergence_alpha1,
            "alpha2_taylor_re": self.alpha2_taylor.real,
            "alpha2_taylor_im": self.alpha2_taylor.imag,
            "alpha2_taylor_convergence": self.alpha2_taylor_convergence,
            "taylor_converged": bool(self.taylor_converged),
            "converged": self.converged,
            "note": self.note,
            "k_check": self.k_check,
            "alpha2_check_re": check.real,
            "alpha2_check_im": check.imag,
            "long_wave_unstable": bool(self.unstable),
            "eig_k": list(self.eig_k),
            "eig_alpha2_re": list(self.eig_alpha2),
            "eig_n": self.eig_n,
            "sign_consistent": bool(self.sign_consistent),
            **(self.model.to_dict() if self.model is not None else {}),
        }


def tangent_vector(op: StabilityOperator, tangent: dict) -> np.ndarray:
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
    the non-zero fields of :func:`tangent_vector`)."""
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


def taylor_coefficients(op: StabilityOperator, tangent: dict) -> tuple[complex, complex]:
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
    V0 = tangent_vector(op, tangent)
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
    (eq. (B 2)), and the start the null vector V0 (:func:`tangent_vector`), which differs from
    the eigenvector at k by O(k): the same eigenpair, to the solve's round-off.
    """
    a1 = a2 = complex("nan")
    if taylor:
        a1, a2, V0, V1 = _bordered(op, tangent, *op.series_products())
        pred, start = a1 * k, (V0 + k * V1) / op.col_eq
    elif guess is None:
        # without perturbation theory: the exact slope α1 = −i dQ0/dρ̄0 (eq. (B 2)) and the
        # k = 0 null vector V0 (the eigenvector at k differs from it by O(k))
        pred, start = complex(0.0, -float(tangent["dQ_drho"])) * k, tangent_vector(op, tangent) / op.col_eq
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
    strict: bool = False,
    eig_ks=EIG_KS,
) -> LongWave:
    """Long-wave coefficients α1, α2 of the least-stable branch, α = α1 k + α2 k² + O(k³).

    α2 (:attr:`LongWave.alpha2`) is the dispersion relation's k² coefficient, from the
    branch's eigenvalue at k = 1e-5; α1 and the strict Taylor α2
    (:attr:`LongWave.alpha2_taylor`, a diagnostic) come from bordered perturbation theory at
    k = 0.

    Parameters
    ----------
    flow : SteadyFlow
        The base state.
    n : int
        Starting number of Chebyshev intervals per field of the perturbation theory. α1 and
        the Taylor α2 are computed at 4n/5 and n, and n is raised by 25 % until the Taylor
        α2 changes by less than ``rtol`` (α1 by less than ``rtol``/100).
    rtol : float
        Accepted relative change of the Taylor α2 between resolutions. It converges only
        algebraically (≈ N⁻⁴) when the domain reaches far into the dilute layer
        (``flow.nu_top`` = 1e-9 needs N ≈ 300–400 for 1 %); 0.2 is enough where only α1 and
        :attr:`LongWave.alpha2` are wanted.
    n_max : int
        Largest resolution tried for the perturbation theory.
    k_check : float or None
        Wavenumber of the eigenvalue cross-check (:attr:`LongWave.alpha2_check`); None
        skips it.
    strict : bool
        False (default, the package's convention): return the estimate at ``n_max``
        flagged ``taylor_converged = False`` (its relative change in
        :attr:`LongWave.alpha2_taylor_convergence`). True: raise when ``rtol`` is not met
        by ``n_max``.
    eig_ks : tuple of float or None
        Wavenumbers of the branch's eigenvalues (:func:`branch_eigenvalues`, default 1e-6,
        1e-5, 1e-4); :attr:`LongWave.alpha2` is taken at :data:`K_EIG` (1e-5; the middle
        one if absent) and decides :attr:`LongWave.unstable`. Empty or None skips them
        (``alpha2`` is then NaN and the Taylor sign decides).

    Raises
    ------
    ConvergenceError
        With ``strict=True``, if the Taylor coefficients do not reach ``rtol`` by ``n_max``.

    Notes
    -----
    α2 = (α(k) − α1 k)/k² at k = 1e-5 with the exact α1 = −i dQ0/dρ̄0: Re α2 = Re α(k)/k²
    converges to ~1e-6 by N ≈ 100 at P1, P2 (at P4, where Re α(1e-5) ≈ 4e-9 lies next to the
    continuum, to ~1e-2: round-off), Im α2 to ~1e-5 … 1e-3. The strict Taylor α2 differs:
    at k → 0 the branch interacts with the near-neutral continuum of the dilute top (gap
    ~1e-8), which the strict k² coefficient includes and eigenvalues at k ≳ 1e-7 do not (at
    P2 the Taylor Re α2 is −91 at N = 480, +841 at N = 100, while Re α/k² at k = 1e-5 is
    −39.996 from N = 100 on). Never decide stability at finite k from α2 alone: the k²
    regime ends near k ~ 1e-5 … 1e-4 (:attr:`LongWave.eig_alpha2`).

    The eigenvalue at ``k_check`` (default 1e-6) on the Taylor coefficients' grid is
    computed by shift-invert from α1 k + α2 k² (Taylor) and kept in the result
    (:attr:`LongWave.alpha2_check`).
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
    b1, b2 = taylor_coefficients(stability_operator(flow, n2, cache=plain), tangent)
    while True:
        op = stability_operator(flow, n, cache=plain)
        a1, a2 = taylor_coefficients(op, tangent)
        c1 = abs(a1 - b1) / max(abs(a1), 1e-300)
        c2 = abs(a2 - b2) / max(abs(a2), 1e-300)
        ok = math.isfinite(c1) and math.isfinite(c2) and c2 <= rtol and c1 <= rtol / 100
        if ok or n >= n_max:
            break
        b1, b2, n2, n = a1, a2, n, ladder.next_n(n)
    if not ok and strict:
        raise ConvergenceError(
            f"long-wave Taylor coefficients at theta = {flow.theta:g}, nu0 = {flow.nu0:g} did "
            f"not converge: relative change of alpha1 {c1:.1e}, alpha2 (Taylor) {c2:.1e} "
            f"between n = {n2} and n = {n} (rtol = {rtol:g}); raise n_max or rtol"
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
    eig_n = 0
    alpha2, conv_re, conv_im, k2 = complex("nan"), float("nan"), float("nan"), float("nan")
    if eig_ks:
        eig_k = tuple(sorted(float(k) for k in eig_ks))
        alphas, coarse, conv_re, eig_n = branch_eigenvalues(flow, ks=eig_k)
        eig_vals = tuple(float(a.real / kk**2) for a, kk in zip(alphas, eig_k))
        j = eig_k.index(K_EIG) if K_EIG in eig_k else len(eig_k) // 2
        k2 = eig_k[j]
        # the exact α1 (eq. (B 2)): Re α1 = 0, so Re α2 = Re α(k)/k²; the grid's α1 would
        # carry its O(N⁻⁴) error, amplified by 1/k, into Im α2
        exact1 = complex(0.0, -float(tangent["dQ_drho"]))
        alpha2 = (alphas[j] - exact1 * k2) / k2**2
        im_coarse = ((coarse[j] - exact1 * k2) / k2**2).imag
        conv_im = abs(alpha2.imag - im_coarse) / max(abs(alpha2.imag), 1e-300)
        if not math.isfinite(conv_im):
            conv_im = math.inf
    return LongWave(
        flow.theta,
        flow.nu0,
        a1,
        alpha2,
        float(tangent["dQ_drho"]),
        n,
        float(c1),
        alpha2_taylor=a2,
        alpha2_taylor_convergence=float(c2),
        alpha2_convergence=float(conv_re),
        alpha2_im_convergence=float(conv_im),
        alpha2_k=float(k2),
        k_check=float(k_check or float("nan")),
        alpha_check=check,
        model=flow.model,
        taylor_converged=bool(ok),
        eig_k=eig_k,
        eig_alpha2=eig_vals,
        eig_n=eig_n,
    )

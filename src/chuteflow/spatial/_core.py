"""Shared machinery of the spatial analysis: the evaluator of α(k) on the tracked branch at
complex k, its convergence measures, and the policy of the Newton iterations."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ConvergenceError, ParameterError
from ..stability import DEFAULT_POLICY, RejectionPolicy, least_stable, stability_operator
from ..stability.complex_k import ComplexEigenpair, eigenpair_at
from ..stability.modes import check_n, interp_vector, tail
from ..steady import SteadyFlow


@dataclass(frozen=True)
class SpatialPolicy:
    """The tuning knobs of the spatial solvers (:mod:`chuteflow.spatial`).

    Attributes
    ----------
    k_rtol : float
        Newton on k stops when the step is below ``k_rtol`` |k| (1e-11).
    saddle_rtol : float
        Newton on a saddle point stops when the step is below ``saddle_rtol`` |k| (1e-8: α'
        carries round-off ~1e-10 |α'|, divided by α'' ~ 1e2 at the paper's points; α + ikV
        is stationary there, so its error is of second order in the step).
    maxiter : int
        Newton steps on k before the point is flagged (40).
    rejection : RejectionPolicy
        The drift and tail thresholds and the resolution ladder of the temporal modes; a
        spatial point is judged by the same tests (drift |α(k; N) − α(k; N')| at the found k).
    ray_step : float
        First step of the continuation of the saddle point in the frame speed V, relative to
        the group velocity at the temporal peak (0.1).
    pinch_margin : float
        The Briggs collapse check raises Re α from the saddle's to the temporal peak's growth
        times (1 + ``pinch_margin``) (0.5).
    coarse : float
        The saddle family's continuation in V, the collapse checks and the lab-frame steps run
        at N = ``coarse`` × N (0.6; 1 turns it off); the edges, the kinematic-wave speed, the
        lab-frame saddle and the temporal tests are then refined at N itself.
    """

    k_rtol: float = 1e-11
    saddle_rtol: float = 1e-8
    maxiter: int = 40
    rejection: RejectionPolicy = DEFAULT_POLICY
    ray_step: float = 0.1
    pinch_margin: float = 0.5
    coarse: float = 0.6

    def __post_init__(self):
        if not (0 < self.k_rtol < 1e-3):
            raise ParameterError(
                f"k_rtol = {self.k_rtol!r} is outside (0, 1e-3): Newton's stopping rule on k"
            )
        if not (0 < self.saddle_rtol < 1e-3):
            raise ParameterError(
                f"saddle_rtol = {self.saddle_rtol!r} is outside (0, 1e-3): Newton's stopping rule"
            )
        if not (isinstance(self.maxiter, int) and self.maxiter >= 3):
            raise ParameterError(f"maxiter = {self.maxiter!r}: at least 3 Newton steps")
        if not (0 < self.ray_step <= 0.5):
            raise ParameterError(f"ray_step = {self.ray_step!r} is outside (0, 0.5]: relative step in V")
        if not (0 < self.pinch_margin <= 10):
            raise ParameterError(f"pinch_margin = {self.pinch_margin!r} is outside (0, 10]")
        if not (0.3 <= self.coarse <= 1):
            raise ParameterError(f"coarse = {self.coarse!r} is outside [0.3, 1]: a fraction of N")


DEFAULT_SPATIAL_POLICY = SpatialPolicy()


def check_flow(flow) -> SteadyFlow:
    if not isinstance(flow, SteadyFlow):
        raise ParameterError(f"flow: expected a SteadyFlow, got {type(flow).__name__}")
    return flow


class Branch:
    """α(k) of the tracked α(0) = 0 branch, continued to complex k at resolution N.

    Started from the temporal resolver's mode at a real k (:func:`~chuteflow.stability.
    least_stable`); every later evaluation is Newton from the nearest previous eigenpair
    (:func:`~chuteflow.stability.complex_k.eigenpair_at`)."""

    def __init__(self, flow: SteadyFlow, k_real: float, policy: SpatialPolicy, cache=None):
        self.flow, self.policy, self.cache = flow, policy, cache
        mode = least_stable(flow, k_real, policy=policy.rejection, cache=cache)
        self.seed_mode = mode
        self.n = int(mode.n)
        self.op = stability_operator(flow, self.n, cache=cache)
        V = np.concatenate([mode.fields[f] for f in self.op.fields])
        self.last = eigenpair_at(self.op, complex(k_real), mode.alpha, V / self.op.col_eq, derivatives=2)

    def transfer(self, e: ComplexEigenpair, other: Branch, sheet: str = "principal") -> ComplexEigenpair:
        """The eigenpair ``e`` of ``other`` (another resolution of the same flow) refined at this
        branch's N: its eigenvector interpolated, Newton at the same k."""
        if other.n == self.n:
            return e
        nf = len(self.op.fields)
        w = interp_vector(e.w * other.op.col_eq, nf, other.n, self.n) / self.op.col_eq
        out = eigenpair_at(self.op, e.k, e.alpha, w, derivatives=2, sheet=sheet)
        self.last = out
        return out

    def coarsened(self, factor: float) -> Branch:
        """The same branch at N = round(``factor`` N) (at least 16), started from the seed's
        eigenpair interpolated there: the cheaper evaluator of :class:`SpatialPolicy`'s
        ``coarse`` steps."""
        b = object.__new__(Branch)
        b.flow, b.policy, b.cache, b.seed_mode = self.flow, self.policy, self.cache, self.seed_mode
        b.n = max(16, int(round(factor * self.n)))
        b.op = stability_operator(self.flow, b.n, cache=self.cache)
        b.last = self.last
        b.last = b.transfer(self.last, self)
        return b

    def at(
        self,
        k: complex,
        *,
        start: ComplexEigenpair | None = None,
        derivatives: int = 2,
        sheet: str = "principal",
    ) -> ComplexEigenpair:
        """The eigenpair at ``k`` (from ``start``, default the last one evaluated), with α' and α''.
        ``sheet``: the root κ(k) of the far-field condition (:data:`~chuteflow.stability.
        complex_k.SHEETS`); on ``"principal"`` the cut Re k = 0 stops the branch."""
        s = self.last if start is None else start
        guess = s.alpha + s.dalpha * (complex(k) - s.k)
        if sheet == "principal" and not (complex(k).real > 0):
            raise ConvergenceError(
                f"k = {complex(k):.6g} reached the branch cut Re k = 0 of the far-field decay "
                "rate: the branch cannot be continued there"
            )
        e = eigenpair_at(self.op, k, guess, s.w, derivatives=derivatives, sheet=sheet)
        self.last = e
        return e

    def convergence(self, e: ComplexEigenpair, sheet: str = "principal") -> tuple[float, float, int]:
        """(drift, tail, N') of the eigenpair: |α(k; N) − α(k; N')| with N' = 0.8 N and the
        Chebyshev tail of its eigenvector, the temporal modes' two tests."""
        n2 = check_n(self.n)
        op2 = stability_operator(self.flow, n2, cache=self.cache)
        nf = len(self.op.fields)
        w2 = interp_vector(e.w * self.op.col_eq, nf, self.n, n2) / op2.col_eq
        try:
            e2 = eigenpair_at(op2, e.k, e.alpha, w2, derivatives=0, sheet=sheet)
            drift = abs(e2.alpha - e.alpha)
        except ConvergenceError:
            drift = math.inf
        V = e.w * self.op.col_eq
        V = V / V[int(np.argmax(np.abs(V)))]
        return float(drift), float(tail(V, nf, self.policy.rejection.tail_terms)), n2


def newton_k(
    branch: Branch,
    k0: complex,
    target: complex,
    policy: SpatialPolicy,
    start=None,
    V: float = 0.0,
    sheet: str = "principal",
    max_step: float = math.inf,
) -> ComplexEigenpair:
    """The root k of α(k) + ikV = ``target`` near ``k0`` by Newton (k ← k − (α + ikV − target)/(α' + iV));
    V = 0: the spatial branch α(k) = target. ``sheet`` and ``max_step`` as in :func:`newton_saddle`."""
    k = complex(k0)
    e = branch.at(k, start=start, sheet=sheet)
    for _ in range(policy.maxiter):
        d = e.dalpha + 1j * V
        if d == 0 or not np.isfinite(d):
            break
        dk = -(e.alpha + 1j * k * V - target) / d
        if abs(dk) > max_step:
            break
        k = k + dk
        e = branch.at(k, start=e, sheet=sheet)
        res = abs(e.alpha + 1j * k * V - target)
        # the step, or the residual at the round-off of the eigenvalue (~1e-15 of rates ~1e-3)
        if abs(dk) <= policy.k_rtol * max(abs(k), 1e-12) or res <= 5e-14:
            return e
    raise ConvergenceError(
        f"Newton on α(k) + ikV = {target:.6g} (V = {V:g}) did not settle from k = {complex(k0):.6g} "
        f"(last k = {k:.6g}, |residual| = {abs(e.alpha + 1j * e.k * V - target):.1e})"
    )


def newton_saddle(
    branch: Branch,
    k0: complex,
    V: float,
    policy: SpatialPolicy,
    start=None,
    sheet: str = "principal",
    max_step: float = math.inf,
) -> ComplexEigenpair:
    """The saddle point of α(k) + ikV near ``k0``: α'(k) = −iV, by Newton (k ← k − (α' + iV)/α'').
    ``sheet`` as in :meth:`Branch.at`; a Newton step longer than ``max_step`` gives up (the
    start is too far from a saddle)."""
    k = complex(k0)
    e = branch.at(k, start=start, sheet=sheet)
    for _ in range(policy.maxiter):
        if e.d2alpha == 0 or not np.isfinite(e.d2alpha):
            break
        dk = -(e.dalpha + 1j * V) / e.d2alpha
        if abs(dk) > max_step:
            break
        k = k + dk
        e = branch.at(k, start=e, sheet=sheet)
        if abs(dk) <= policy.saddle_rtol * max(abs(k), 1e-12):
            return e
    raise ConvergenceError(
        f"Newton on the saddle dα/dk = {-1j * V:.6g} did not settle from k = {complex(k0):.6g} "
        f"(last k = {k:.6g})"
    )

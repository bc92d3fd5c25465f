"""When a computed eigenpair is accepted: one rejection policy for every solver (paper §4.1).

A :class:`RejectionPolicy` holds the paper's two tests of a physical mode — the *drift* of
the eigenvalue between the resolutions N and N' = round(0.8 N), and the *tail* of its
eigenvector (the highest ``tail_terms`` Chebyshev coefficients) — with their thresholds, and
the ladder of resolutions N tried until a mode passes them. Every function of
:mod:`chuteflow.stability` that judges modes takes it as ``policy=`` (default
:data:`DEFAULT_POLICY`, the paper's values).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from ..errors import ParameterError
from .operator import validate_n

__all__ = ["DEFAULT_POLICY", "RejectionPolicy"]


@dataclass(frozen=True)
class RejectionPolicy:
    """Thresholds of the physical-mode tests and the resolution ladder (paper §4.1).

    Parameters
    ----------
    drift_tol : float
        Largest accepted |α(N) − α(N')| (paper: 1e-7).
    tail_tol : float
        Largest accepted coefficient among the highest ``tail_terms`` Chebyshev
        coefficients of the normalised eigenvector (paper: 1e-7).
    tail_terms : int
        Number of highest Chebyshev coefficients of the tail test (paper: 10).
    track_tail_tol : float
        Largest tail of an eigenvector accepted as a continuation step of the branch
        α(0) = 0 (looser than ``tail_tol``; the near-neutral continuum of the dilute top
        has tails ~1e-4).
    n_start : int
        First resolution N of the adaptive choice (80; on the sinh-mapped grid the paper's
        1e-7 is reached at N = 40–64 for k ≤ 0.02 at the paper's points, against 56–160 on
        the plain grid, ``benchmarks/probes/n_table.py``, so the sweep metrics start at 48;
        the default stays 80 for the 3D solvers on the plain grid and for the k → 0 limits,
        which converge more slowly on the mapped grid).
    n_max : int
        Largest resolution N tried.
    n_growth : float
        Each rung of the ladder is round(``n_growth`` × the one before) (at most ``n_max``).
    relaxed_k_max : float
        Largest |k| at which a flagged value of the branch followed with the relaxed tail
        threshold (``method = "branch (relaxed)"``) always outranks a direct solve's mode
        (:meth:`direct_outranks_relaxed`). Below it the relaxed branch is the branch (at
        θ = 16.5°, ν0(0) = 0.13, φ = 0.08, Φ = 0.30, k = 0.005 its drift falls from 2.3e-4
        at N = 80 to 3.3e-6 at N = 244, where QZ finds the same eigenvalue). Above it the
        branch lies in a band of critical-layer eigenvalues (phase velocity inside the range
        of u0), the continuation may land on a neighbour in the band (P4, k = 0.5, N = 200:
        −0.0279 − 0.8199i mapped, −0.0350 − 0.8188i plain, against the branch's
        −0.0300 − 0.8171i), and a resolved direct mode competes with it
        (``benchmarks/probes/relaxed_branch.py``).
    """

    drift_tol: float = 1e-7
    tail_tol: float = 1e-7
    tail_terms: int = 10
    track_tail_tol: float = 1e-5
    n_start: int = 80
    n_max: int = 256
    n_growth: float = 1.25
    relaxed_k_max: float = 0.1

    def __post_init__(self):
        if isinstance(self.relaxed_k_max, bool) or not (
            isinstance(self.relaxed_k_max, (int, float)) and self.relaxed_k_max >= 0
        ):
            raise ParameterError(
                f"relaxed_k_max = {self.relaxed_k_max!r}: need a wavenumber >= 0 (where the "
                "relaxed branch stops outranking a direct solve)"
            )
        object.__setattr__(self, "relaxed_k_max", float(self.relaxed_k_max))
        for name in ("drift_tol", "tail_tol", "track_tail_tol"):
            v = getattr(self, name)
            if isinstance(v, bool) or not (isinstance(v, (int, float)) and 0 < v < 1):
                raise ParameterError(
                    f"{name} = {v!r} is outside (0, 1): it is a threshold on "
                    "an eigenvalue change or a normalised Chebyshev "
                    "coefficient"
                )
            object.__setattr__(self, name, float(v))
        if isinstance(self.tail_terms, bool) or not (
            isinstance(self.tail_terms, int) and self.tail_terms >= 1
        ):
            raise ParameterError(f"tail_terms = {self.tail_terms!r}: need an integer >= 1")
        for name in ("n_start", "n_max"):
            try:
                object.__setattr__(self, name, validate_n(getattr(self, name)))
            except ParameterError as exc:
                raise ParameterError(f"{name}: {exc}") from None
        if not (isinstance(self.n_growth, (int, float)) and self.n_growth > 1):
            raise ParameterError(f"n_growth = {self.n_growth!r}: the ladder must grow (> 1)")

    def replace(self, **changes) -> RejectionPolicy:
        """A copy with the given fields changed; ``None`` values leave a field as it is."""
        changes = {k: v for k, v in changes.items() if v is not None}
        return dataclasses.replace(self, **changes) if changes else self

    def accepts(self, drift: float, tail: float) -> bool:
        """Both tests pass: drift < ``drift_tol`` and tail < ``tail_tol``."""
        return bool(drift < self.drift_tol and tail < self.tail_tol)

    def direct_outranks_relaxed(
        self,
        k: float,
        direct_re: float,
        direct_drift: float,
        direct_tail: float,
        relaxed_re: float,
        relaxed_drift: float,
    ) -> bool:
        """Whether a direct solve's mode (dense QZ at k; growth rate ``direct_re``) replaces a
        flagged value of the branch followed with the relaxed tail threshold (growth rate
        ``relaxed_re``) as the answer at wavenumber |k| = ``k``.

        Only beyond :attr:`relaxed_k_max` (where the branch has reached the continuum), and
        only when the direct mode is resolved (tail below :attr:`track_tail_tol`), agrees
        between the resolutions N and N' better than the relaxed value (``direct_drift <
        relaxed_drift``) and is at least as unstable (``direct_re >= relaxed_re``): a
        resolved but more damped mode never hides a less damped one that N does not yet
        resolve (P4, k = 0.5: the branch at −0.0300 − 0.8172i, drift 6.4e-4 at N = 200,
        against a resolved mode at −2.51 − 0.87i).

        Below :attr:`relaxed_k_max` the branch value wins unless the direct mode passes both
        of the paper's tests (:meth:`accepts`) and is less damped: the least-stable physical
        mode is then that mode, and the relaxed value, which the tests reject, is not (θ =
        17.5°, ν0(0) = 0.11, φ = 0.075, Φ = 0.35, k = 0.005: the relaxed branch wanders
        between −0.00530 and −0.00614 with drifts ≥ 1.8e-4 up to N = 256, while −0.00522663 −
        0.0310785i passes both tests from N = 125, drift 1.3e-11 at N = 256).
        """
        if k <= self.relaxed_k_max:
            return bool(self.accepts(direct_drift, direct_tail) and direct_re > relaxed_re)
        return bool(
            direct_tail < self.track_tail_tol and direct_drift < relaxed_drift and direct_re >= relaxed_re
        )

    def next_n(self, n: int) -> int:
        """The rung after N: min(``n_max``, round(``n_growth`` N))."""
        return min(self.n_max, round(n * self.n_growth))

    def ladder(self, start: int | None = None) -> list[int]:
        """Resolutions tried in turn: ``start`` (default ``n_start``, at most ``n_max``),
        then :meth:`next_n` until ``n_max`` (80, 100, 125, 156, 195, 244, 256 by default)."""
        out = [min(self.n_start if start is None else start, self.n_max)]
        while out[-1] < self.n_max:
            out.append(self.next_n(out[-1]))
        return out


#: The paper's thresholds (§4.1) and the default ladder 80 … 256.
DEFAULT_POLICY = RejectionPolicy()

"""One scan of the α(0) = 0 branch and the one rule for its k_c, peak and cut-off (§4.2,
figures 7–9).

The paper calls a flow unstable "for 0 < k ≤ k_c" (P1: k_c ≈ 0.007, figure 7(a)): k_c is the
upper edge of the long-wave unstable band, where Re α of the tracked α(0) = 0 branch turns
from positive to negative. Every caller that reports k_c, the largest growth rate or the
edge of an unstable band decides it from sampled values of Re α with the functions here:

- **sign change** (:func:`sign_changes`): between two adjacent samples of the scan, both
  finite, when the first is nonzero and the second has another sign (a sample exactly 0
  closes the bracket that ends there). Across an unreached sample (NaN) no sign change is
  decided.
- **k_c** (:func:`critical_index`): the *first* sign change of the scan, when Re α goes
  from + to − there, i.e. the flow is long-wave unstable on the scan (Re α > 0 at the
  smallest sampled k) and k_c ends that band. Where the first sign change goes from − to +
  — a long-wave stable flow (P2, P3, figure 7(b, c)) whose branch turns unstable at finite
  k — or there is none, k_c is None: there is no band 0 < k < k_c. The crossings of such a
  branch are still listed (:attr:`BranchScan.crossings`) and the upper edge of its last
  unstable band is :meth:`BranchScan.cutoff`.
- **cut-off** (:func:`cutoff_index`): the largest k of the scan with Re α > 0, i.e. the
  *last* sign change when it goes from + to −; None where Re α ≤ 0 at every sample, or > 0
  at the last one reached (the band goes on past the scan). For a long-wave unstable
  branch with one band, the cut-off is k_c.
- **peak** (:func:`peak_index`): the largest finite Re α over k > 0 (the first of equal
  values), refined between its two neighbours (:meth:`BranchScan.peak`).

:func:`branch_scan` tracks the branch (:class:`~chuteflow.stability.BranchTracker`) on a
grid, refines every sign change by Brent's method and the peak by a bounded search, both on
the eigenvalue nearest the interpolated branch, and returns a :class:`BranchScan`.
:func:`critical_k` is ``branch_scan(...).k_c``; :func:`crossings` the refined sign changes
with the scan's convergence (:class:`Crossings`). Cheaper callers that sample the branch
themselves (the sweep's ``growth`` metric, the transverse peaks) apply the same
:func:`critical_index`, :func:`cutoff_index` and :func:`peak_index` to their samples.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from ..conventions import RATE_UNITS, WAVENUMBER_UNITS
from ..errors import ConvergenceError, ParameterError
from ..steady import SteadyFlow
from .modes import OperatorCache, check_hydrodynamic_k, interp_vector, nearest_eigenpair, stability_operator
from .operator import validate_k
from .policy import RejectionPolicy
from .tracking import BranchTracker

__all__ = [
    "BranchScan",
    "Crossings",
    "Peak",
    "branch_scan",
    "critical_index",
    "critical_k",
    "crossings",
    "cutoff_index",
    "linear_crossing",
    "peak_index",
    "sign_changes",
]


# -- the rule, on sampled values -------------------------------------------------------------
def sign_changes(values) -> list[int]:
    """Indices i where Re α changes sign between the samples i and i + 1 (module docstring):
    both finite, ``values[i]`` ≠ 0 and of another sign than ``values[i + 1]``."""
    v = np.asarray(values, dtype=float)
    out = []
    for i in range(len(v) - 1):
        a, b = v[i], v[i + 1]
        if math.isfinite(a) and math.isfinite(b) and a != 0 and np.sign(a) != np.sign(b):
            out.append(i)
    return out


def critical_index(values) -> int | None:
    """The bracket [i, i + 1] of k_c: the first sign change of the samples if Re α goes from
    + to − there (the upper edge of the long-wave unstable band), else None (module
    docstring; paper §4.2, figures 7–9)."""
    v = np.asarray(values, dtype=float)
    ch = sign_changes(v)
    return ch[0] if ch and v[ch[0]] > 0 else None


def cutoff_index(values) -> int | None:
    """The bracket [i, i + 1] of the cut-off (the largest k with Re α > 0): the last sign
    change of the samples if Re α goes from + to − there, else None."""
    v = np.asarray(values, dtype=float)
    ch = sign_changes(v)
    return ch[-1] if ch and v[ch[-1]] > 0 else None


def peak_index(values, k=None) -> int | None:
    """Index of the largest finite Re α (over k > 0 when ``k`` is given; the first of equal
    values), None if there is none."""
    v = np.asarray(values, dtype=float)
    ok = np.isfinite(v)
    if k is not None:
        ok &= np.asarray(k, dtype=float) > 0
    if not ok.any():
        return None
    return int(np.argmax(np.where(ok, v, -np.inf)))


def linear_crossing(k, values, i: int) -> float:
    """The zero of the straight line through (k[i], values[i]) and (k[i+1], values[i+1])."""
    ka, kb, a, b = float(k[i]), float(k[i + 1]), float(values[i]), float(values[i + 1])
    return ka - a * (kb - ka) / (b - a)


def _parabola_peak(k, values, i: int) -> tuple[float, float] | None:
    """Vertex (k, value) of the parabola through the samples i − 1, i, i + 1 (a maximum
    inside their bracket), or None."""
    if i <= 0 or i >= len(values) - 1:
        return None
    x = np.asarray(k[i - 1 : i + 2], dtype=float)
    y = np.asarray(values[i - 1 : i + 2], dtype=float)
    if not np.all(np.isfinite(y)):
        return None
    # divided differences: y = y0 + d1 (x − x0) + d2 (x − x0)(x − x1)
    d01 = (y[1] - y[0]) / (x[1] - x[0])
    d12 = (y[2] - y[1]) / (x[2] - x[1])
    d2 = (d12 - d01) / (x[2] - x[0])
    if not d2 < 0:
        return None
    xv = 0.5 * (x[0] + x[1]) - d01 / (2 * d2)
    if not x[0] <= xv <= x[2]:
        return None
    return float(xv), float(y[0] + d01 * (xv - x[0]) + d2 * (xv - x[0]) * (xv - x[1]))


# -- the result --------------------------------------------------------------------------------
@dataclass(frozen=True)
class Crossings:
    """The wavenumbers where Re α of the tracked branch changes sign, in increasing order,
    with the convergence of the scan that found them (:meth:`BranchScan.to_crossings`).

    Iterating, ``len`` and indexing go over the wavenumbers ``ks``.

    Attributes
    ----------
    ks : tuple of float
        The sign changes of Re α.
    converged : bool
        Every grid point of the scan passed the drift and tail tests, the branch was
        followed up to ``k_max`` and every crossing was refined on the branch.
    max_drift, max_tail : float
        Largest drift and tail over the scanned points.
    n : int
        Largest resolution N used.
    k_reached : float
        Largest k of the scan (< ``k_max`` when the branch was lost).
    note : str
        Empty when converged; else what was not reached.
    """

    ks: tuple[float, ...] = ()
    converged: bool = True
    max_drift: float = 0.0
    max_tail: float = 0.0
    n: int = 0
    k_reached: float = math.nan
    note: str = ""

    def __iter__(self) -> Iterator[float]:
        return iter(self.ks)

    def __len__(self) -> int:
        return len(self.ks)

    def __getitem__(self, i):
        return self.ks[i]

    def to_dict(self) -> dict:
        """JSON-ready dict of the fields (``ks`` as a list)."""
        d = dataclasses.asdict(self)
        d["ks"] = [float(k) for k in self.ks]
        return d


class Peak(NamedTuple):
    """The largest growth rate of a scan (:meth:`BranchScan.peak`).

    ``k``, ``growth``: where and how large (NaN where no point was reached); ``refined``:
    moved off the grid (on the branch by :func:`branch_scan`, else the parabola through the
    sample and its neighbours); ``at_edge``: the largest sample is the first or the last
    one reached, so the maximum may lie outside the scan."""

    k: float
    growth: float
    refined: bool
    at_edge: bool


@dataclass(frozen=True, eq=False)
class BranchScan:
    """Re α of the α(0) = 0 branch sampled on a k grid, with the paper's k_c, peak and cut-off
    decided by one rule (module docstring; §4.2, figures 7–9).

    Attributes
    ----------
    k : ndarray
        The grid, increasing, k > 0.
    alpha : ndarray (complex)
        α on the branch; NaN from where the branch was lost.
    drift, tail : ndarray
        |α(N) − α(N')| and the Chebyshev tail per point (NaN where not reached).
    n : ndarray (int)
        Resolution N per point (0 where not reached).
    physical : ndarray (bool)
        The point passed the drift and tail tests.
    crossings : tuple of float
        Every sign change of Re α (:func:`sign_changes`), refined: by Brent's method on the
        branch (:func:`branch_scan`) or linearly between the bracketing samples
        (:meth:`from_samples`; also where the refinement left the branch, noted).
    peak_k, peak_growth : float
        The refined maximum (NaN: use the sampled one, :meth:`peak`).
    k_max : float
        The scan's intended end (the last grid point).
    theta, nu0 : float
        The flow's parameters (NaN when not known).
    note : str
        Empty when converged; else what was not reached.
    """

    k: np.ndarray
    alpha: np.ndarray
    drift: np.ndarray
    tail: np.ndarray
    n: np.ndarray
    physical: np.ndarray
    crossings: tuple[float, ...]
    peak_k: float = math.nan
    peak_growth: float = math.nan
    k_max: float = math.nan
    theta: float = math.nan
    nu0: float = math.nan
    note: str = ""

    @classmethod
    def from_samples(
        cls,
        k,
        alpha,
        *,
        drift=None,
        tail=None,
        n=None,
        physical=None,
        theta: float = math.nan,
        nu0: float = math.nan,
        note: str = "",
    ) -> BranchScan:
        """A scan from sampled values alone (a synthetic or an already computed α(k)):
        crossings by linear interpolation, the peak by the parabola through the largest
        sample and its neighbours. Missing convergence data count as converged."""
        k = np.asarray(k, dtype=float)
        alpha = np.asarray(alpha, dtype=complex)
        if k.ndim != 1 or k.shape != alpha.shape or len(k) < 2 or not np.all(np.diff(k) > 0):
            raise ParameterError("BranchScan: need increasing k and alpha of the same length ≥ 2")
        reached = np.isfinite(alpha)
        re = alpha.real
        roots = tuple(linear_crossing(k, re, i) for i in sign_changes(re))
        j = peak_index(re, k)
        vertex = _parabola_peak(k, re, j) if j is not None else None
        return cls(
            k=k,
            alpha=alpha,
            drift=np.zeros(len(k)) if drift is None else np.asarray(drift, dtype=float),
            tail=np.zeros(len(k)) if tail is None else np.asarray(tail, dtype=float),
            n=np.zeros(len(k), dtype=int) if n is None else np.asarray(n, dtype=int),
            physical=reached.copy() if physical is None else np.asarray(physical, dtype=bool),
            crossings=roots,
            peak_k=vertex[0] if vertex else math.nan,
            peak_growth=vertex[1] if vertex else math.nan,
            k_max=float(k[-1]),
            theta=theta,
            nu0=nu0,
            note=note,
        )

    # -- the rule ---------------------------------------------------------------------------
    @property
    def growth(self) -> np.ndarray:
        """Re α per point (NaN where not reached)."""
        return self.alpha.real

    def _root(self, i: int | None) -> float | None:
        if i is None:
            return None
        return float(self.crossings[sign_changes(self.growth).index(i)])

    @property
    def k_c(self) -> float | None:
        """The critical wavenumber: the first sign change of Re α when it goes from + to −
        (the upper edge of the long-wave unstable band 0 < k < k_c, paper §4.2); None where
        the flow is long-wave stable on the scan (the first change goes from − to +) or Re α
        keeps its sign on the scan (:func:`critical_index`)."""
        return self._root(critical_index(self.growth))

    def cutoff(self) -> float | None:
        """The largest k with Re α > 0: the last sign change when it goes from + to −; None
        where Re α ≤ 0 everywhere or > 0 at the last point reached (:func:`cutoff_index`)."""
        return self._root(cutoff_index(self.growth))

    def peak(self) -> Peak:
        """The largest Re α over the scan and its k, refined between the grid neighbours of
        the largest sample (:func:`peak_index`); ``at_edge`` where that sample is the first
        or last point reached."""
        re = self.growth
        j = peak_index(re, self.k)
        if j is None:
            return Peak(math.nan, math.nan, False, False)
        last = int(np.flatnonzero(np.isfinite(re))[-1])
        at_edge = j == 0 or j == last
        if math.isfinite(self.peak_growth) and self.peak_growth >= re[j]:
            return Peak(float(self.peak_k), float(self.peak_growth), True, at_edge)
        return Peak(float(self.k[j]), float(re[j]), False, at_edge)

    # -- convergence --------------------------------------------------------------------------
    @property
    def reached(self) -> np.ndarray:
        """The points where the branch was reached."""
        return np.isfinite(self.alpha)

    @property
    def k_reached(self) -> float:
        """Largest k where the branch was reached (0 where none)."""
        r = self.reached
        return float(self.k[r][-1]) if r.any() else 0.0

    @property
    def converged(self) -> bool:
        """Every point reached and passing the paper's drift and tail tests, and every
        crossing refined on the branch (``note`` empty)."""
        return bool(not self.note and self.reached.all() and self.physical.all())

    @property
    def max_drift(self) -> float:
        return float(np.nanmax(self.drift)) if self.reached.any() else 0.0

    @property
    def max_tail(self) -> float:
        return float(np.nanmax(self.tail)) if self.reached.any() else 0.0

    def to_crossings(self) -> Crossings:
        """The crossings with the scan's convergence (:func:`crossings`)."""
        return Crossings(
            tuple(self.crossings),
            converged=self.converged,
            max_drift=self.max_drift,
            max_tail=self.max_tail,
            n=int(self.n.max()) if len(self.n) else 0,
            k_reached=self.k_reached,
            note=self.note,
        )

    def to_dict(self) -> dict:
        """JSON-ready summary: k_c, the cut-off, the peak, the crossings and the
        convergence (the per-point arrays are in :meth:`to_xarray`)."""
        pk = self.peak()
        return {
            "theta": self.theta,
            "nu0": self.nu0,
            "k_max": self.k_max,
            "k_c": self.k_c,
            "cutoff": self.cutoff(),
            "crossings": [float(k) for k in self.crossings],
            "peak_k": pk.k,
            "peak_growth": pk.growth,
            "peak_refined": bool(pk.refined),
            "peak_at_edge": bool(pk.at_edge),
            "k_reached": self.k_reached,
            "n_max": int(self.n.max()) if len(self.n) else 0,
            "max_drift": self.max_drift,
            "max_tail": self.max_tail,
            "converged": self.converged,
            "note": self.note,
        }

    def to_xarray(self):
        """:class:`xarray.Dataset` over k (alpha_re, alpha_im, drift, tail, n, physical),
        with k_c, the crossings, the peak and the cut-off as attributes (absent where None;
        flags as 0/1, NetCDF-ready)."""
        import xarray as xr

        u = RATE_UNITS
        pk = self.peak()
        attrs: dict = {
            "long_name": "scan of the alpha(0) = 0 branch",
            "source": "Mitarai & Nakanishi §4.2, figures 7-9",
            "theta": self.theta,
            "nu0": self.nu0,
            "k_max": self.k_max,
            "crossings": np.asarray(self.crossings, dtype=float),
            "peak_k": pk.k,
            "peak_growth": pk.growth,
            "peak_refined": int(pk.refined),
            "peak_at_edge": int(pk.at_edge),
            "converged": int(self.converged),
            "note": self.note,
        }
        optional = (("k_c", self.k_c), ("cutoff", self.cutoff()))
        attrs.update({name: value for name, value in optional if value is not None})
        return xr.Dataset(
            {
                "alpha_re": ("k", self.alpha.real, {"long_name": "growth rate Re alpha", "units": u}),
                "alpha_im": ("k", self.alpha.imag, {"long_name": "Im alpha", "units": u}),
                "drift": ("k", self.drift, {"long_name": "|alpha(N) - alpha(N')|", "units": u}),
                "tail": ("k", self.tail, {"long_name": "largest of the highest Chebyshev coefficients"}),
                "n": ("k", self.n, {"long_name": "Chebyshev intervals N"}),
                "physical": ("k", self.physical, {"long_name": "passes drift and tail tests"}),
            },
            coords={"k": ("k", self.k, {"long_name": "wavenumber", "units": WAVENUMBER_UNITS})},
            attrs=attrs,
        )


# -- the scan on the tracked branch ------------------------------------------------------------
def scan_grid(k_max: float, num: int) -> np.ndarray:
    """The default grid of :func:`branch_scan`: ``num // 3`` points geometric from 1e-5 (the
    narrow k² regime) and the rest uniform on (0, k_max]."""
    return np.unique(
        np.concatenate([np.geomspace(1e-5, k_max, num // 3), np.linspace(0, k_max, num - num // 3 + 1)[1:]])
    )


#: Relative tolerance in k of the refined peak (the growth rate is flat there: Re α moves by
#: ~1e-6 of itself).
PEAK_XTOL = 1e-3
#: A refined point is on the branch when within this fraction of |α| of the interpolation.
PEAK_ON_BRANCH = 0.05


def branch_scan(
    flow: SteadyFlow,
    *,
    k_max: float = 0.05,
    num: int = 40,
    ks=None,
    n: int | None = None,
    n_max: int | None = None,
    xtol: float = 1e-10,
    policy: RejectionPolicy | None = None,
    cache: OperatorCache | None = None,
    strict: bool = False,
    refine_peak: bool = True,
) -> BranchScan:
    """Track the α(0) = 0 branch over (0, k_max] and decide k_c, the peak and the cut-off
    (module docstring; paper §4.2, figures 7–9).

    Parameters
    ----------
    flow : SteadyFlow
        Base state.
    k_max, num : float, int
        The grid :func:`scan_grid` (``num`` ≥ 3), unless ``ks`` is given (increasing, > 0).
    n, n_max, policy, cache
        Starting resolution, largest resolution, rejection policy and operator cache of
        the :class:`~chuteflow.stability.BranchTracker` (each point judged by ``policy``).
    xtol : float
        Brent's tolerance on each crossing, relative to the bracket's upper k.
    strict : bool
        False (default): points that miss the paper's thresholds by N = ``n_max`` are kept
        with their best estimate, a lost branch ends the scan at the last point reached
        (NaN beyond), and a crossing whose refinement leaves the branch keeps the bracket's
        linear estimate; ``note`` says which. True: :class:`ConvergenceError` instead.
    refine_peak : bool
        Refine the largest sample by a bounded search between its neighbours on the branch.
    """
    from .._memory import brentq  # scipy's, without a reference cycle that keeps the operators

    if ks is None:
        k_max = validate_k(k_max, "k_max")
        if k_max == 0 or num < 3:
            raise ParameterError("k_max must be > 0 and num ≥ 3")
        ks = scan_grid(k_max, num)
    else:
        ks = np.asarray(ks, dtype=float)
        if ks.ndim != 1 or len(ks) < 2 or not (ks[0] > 0 and np.all(np.diff(ks) > 0)):
            raise ParameterError("ks: need at least 2 increasing wavenumbers > 0")
        k_max = float(ks[-1])
    check_hydrodynamic_k(k_max)
    tr = BranchTracker(flow, n or None, policy=policy, n_max=n_max, cache=cache)
    m = len(ks)
    alpha = np.full(m, np.nan, dtype=complex)
    drift, tails = np.full(m, np.nan), np.full(m, np.nan)
    nres, phys = np.zeros(m, dtype=int), np.zeros(m, dtype=bool)
    vecs: list = []  # eigenvector of the equilibrated pencil per point reached
    messages: list[str] = []
    for i, kk in enumerate(ks):
        try:
            mode = tr.mode(float(kk))
        except ConvergenceError as exc:
            if strict:
                raise
            last = ks[i - 1] if i else 0.0
            messages.append(f"branch lost near k = {kk:g} ({exc}); scanned up to k = {last:g}")
            break
        if not mode.physical:
            msg = (
                f"the branch at k = {kk:g} is not converged at N = {mode.n} (drift "
                f"{mode.drift:.1e}, tail {mode.tail:.1e})"
            )
            if strict:
                raise ConvergenceError(
                    f"branch scan at theta = {flow.theta:g}, nu0 = {flow.nu0:g}: {msg}; lower "
                    "k_max or raise n_max"
                )
            if not any(s.startswith("the branch at") for s in messages):
                messages.append(msg)
        alpha[i], drift[i], tails[i] = mode.alpha, mode.drift, mode.tail
        nres[i], phys[i] = tr.n, mode.physical
        vecs.append(tr.history[-1][2])

    def solver(i_lo: int, i_hi: int):
        """α(k) nearest the linear interpolation between samples i_lo and i_hi, at the finer
        of their resolutions, started from the eigenvector of i_lo."""
        nb = int(max(nres[i_lo], nres[i_hi]))
        op = stability_operator(flow, nb, cache=cache)
        na = int(nres[i_lo])
        start = vecs[i_lo] if na == nb else interp_vector(vecs[i_lo], len(op.fields), na, nb)
        ka, kb, aa, ab = float(ks[i_lo]), float(ks[i_hi]), alpha[i_lo], alpha[i_hi]

        def at(kk: float) -> tuple[complex, complex]:
            pred = aa + (ab - aa) * (kk - ka) / (kb - ka)
            return complex(nearest_eigenpair(op.pencil(kk), pred, v0=start)[0]), pred

        return at

    re = alpha.real
    roots = []
    for i in sign_changes(re):
        at = solver(i, i + 1)

        def growth(kk: float, at=at) -> float:
            return at(kk)[0].real

        try:
            roots.append(float(brentq(growth, ks[i], ks[i + 1], xtol=xtol * ks[i + 1], rtol=1e-12)))
        except (ConvergenceError, ValueError) as exc:
            if strict:
                raise
            # the refinement left the branch: keep the bracket's linear estimate
            roots.append(linear_crossing(ks, re, i))
            messages.append(f"crossing in [{ks[i]:g}, {ks[i + 1]:g}] from linear interpolation ({exc})")
    peak_k = peak_growth = math.nan
    j = peak_index(re, ks)
    if refine_peak and j is not None and 0 < j < len(vecs) - 1:
        peak_k, peak_growth = _refine_peak(ks, alpha, j, solver)
    return BranchScan(
        k=np.asarray(ks, dtype=float),
        alpha=alpha,
        drift=drift,
        tail=tails,
        n=nres,
        physical=phys,
        crossings=tuple(roots),
        peak_k=peak_k,
        peak_growth=peak_growth,
        k_max=float(k_max),
        theta=float(flow.theta),
        nu0=float(flow.nu0),
        note="; ".join(messages),
    )


def _refine_peak(ks, alpha, j: int, solver) -> tuple[float, float]:
    """The maximum of Re α between the samples j − 1 and j + 1 by a bounded search on the
    eigenvalue nearest the branch's linear interpolation (each half bracket its own
    interpolation); (NaN, NaN) where no evaluation beats the sample j."""
    from scipy.optimize import minimize_scalar

    halves = {j - 1: solver(j - 1, j), j: solver(j, j + 1)}
    seen: dict[float, float] = {}

    def minus(kk: float) -> float:
        i = j - 1 if kk <= ks[j] else j
        try:
            a, pred = halves[i](float(kk))
        except ConvergenceError:
            return math.inf
        if abs(a - pred) > PEAK_ON_BRANCH * abs(pred):
            return math.inf  # a neighbour of the continuum, not the branch
        seen[float(kk)] = a.real
        return -a.real

    minimize_scalar(
        minus,
        bounds=(float(ks[j - 1]), float(ks[j + 1])),
        method="bounded",
        options={"xatol": PEAK_XTOL * float(ks[j]), "maxiter": 30},
    )
    halves.clear()
    if not seen:
        return math.nan, math.nan
    kb, gb = max(seen.items(), key=lambda t: t[1])
    return (kb, gb) if gb > alpha[j].real else (math.nan, math.nan)


# -- the short forms ---------------------------------------------------------------------------
def critical_k(
    flow: SteadyFlow,
    *,
    k_max: float = 0.05,
    num: int = 40,
    n: int | None = None,
    n_max: int | None = None,
    xtol: float = 1e-10,
    policy: RejectionPolicy | None = None,
    cache: OperatorCache | None = None,
    strict: bool = False,
) -> float | None:
    """Critical wavenumber k_c: the upper edge of the long-wave unstable band 0 < k < k_c of
    the α(0) = 0 branch (paper §4.2, figures 7–9), ``branch_scan(...).k_c``.

    The branch is tracked on :func:`scan_grid` (``num`` points up to ``k_max``, denser at
    small k) and each sign change of Re α refined by Brent's method on the branch.

    Returns
    -------
    float or None
        The first sign change of Re α when Re α goes from + to − there; None where the flow
        is long-wave stable on the scan (Re α < 0 up to its first sign change) or Re α does
        not change sign in (0, k_max]. All crossings, with the convergence of the scan, are
        in :func:`crossings` (``strict``: see :func:`branch_scan`).
    """
    return branch_scan(
        flow,
        k_max=k_max,
        num=num,
        n=n,
        n_max=n_max,
        xtol=xtol,
        policy=policy,
        cache=cache,
        strict=strict,
        refine_peak=False,
    ).k_c


def crossings(
    flow: SteadyFlow,
    *,
    k_max: float = 0.05,
    num: int = 40,
    n: int | None = None,
    n_max: int | None = None,
    xtol: float = 1e-10,
    policy: RejectionPolicy | None = None,
    cache: OperatorCache | None = None,
    strict: bool = False,
) -> Crossings:
    """All wavenumbers in (0, k_max] where Re α of the tracked branch changes sign (each
    grid point judged by ``policy``; ``n_max`` overrides its largest N): the crossings of
    :func:`branch_scan`, whose :attr:`BranchScan.k_c` says which of them is k_c.

    Returns a :class:`Crossings` (a tuple of floats with the scan's convergence). With
    ``strict=False`` (default) points that miss the paper's thresholds by N = ``n_max`` are
    used with their best estimate, and a lost branch ends the scan at the last point
    reached; ``.converged`` is then False and ``.note`` says why. ``strict=True`` raises
    :class:`ConvergenceError` instead.
    """
    return branch_scan(
        flow,
        k_max=k_max,
        num=num,
        n=n,
        n_max=n_max,
        xtol=xtol,
        policy=policy,
        cache=cache,
        strict=strict,
        refine_peak=False,
    ).to_crossings()

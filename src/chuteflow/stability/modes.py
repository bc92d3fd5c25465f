"""Eigenmodes with their convergence estimates, and spurious-mode rejection (paper §4.1).

A computed eigenpair is *physical* when both of the paper's tests pass:

* **drift** — the eigenvalue changes by less than ``drift_tol`` (1e-7) between the
  resolution N and the coarser N' = round(0.8 N) (modes paired by nearest eigenvalue);
* **tail** — with the eigenvector normalised so that |Re| + |Im| of its largest component
  is 1 (we divide by that component, which also fixes the phase), the highest ten
  Chebyshev coefficients of every field are below ``tail_tol`` (1e-7).

Drift alone is not enough: the dilute top carries a continuum of near-neutral modes
α ≈ −ik u0(y) − 1e-8 that barely move with N but whose eigenvectors are not resolved
(tails ~1e-4; ERRATA). Every :class:`Mode` carries both numbers.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np

from ..conventions import phase_velocity
from ..errors import ConvergenceError, ParameterError
from ..spectral import ChebyshevGrid, coefficients
from ..steady import SteadyFlow
from .eigen import ShiftInvert, qz
from .operator import Pencil, StabilityOperator, _check_k, _check_n

DRIFT_TOL = 1e-7
TAIL_TOL = 1e-7
TAIL_TERMS = 10
#: Default and largest resolution of the adaptive choice of N.
N_DEFAULT = 80
N_MAX = 256


def check_n(n: int) -> int:
    """The comparison resolution N' = round(0.8 N) (at most N − 8).

    The coarser of the two resolutions is the check: |α(N) − α(N')| then bounds the error
    of α(N') and, the discretisation converging spectrally, over-estimates that of α(N),
    which is what is returned. It also costs half a factorisation at N rather than two.
    """
    return max(min(int(round(0.8 * n)), n - 8), 8)


# -- operator cache ----------------------------------------------------------------------
_CACHE: list = []
_CACHE_SIZE = 6  # an operator at N = 256 holds ~60 MB


def stability_operator(flow: SteadyFlow, n: int, three_d: bool = False) -> StabilityOperator:
    """A :class:`StabilityOperator`, cached for the last few (flow, N) pairs."""
    for entry in _CACHE:
        if entry[0] is flow and entry[1] == n and entry[2] == three_d:
            return entry[3]
    op = StabilityOperator(flow, n, three_d=three_d)
    _CACHE.insert(0, (flow, n, three_d, op))
    del _CACHE[_CACHE_SIZE:]
    return op


# -- the mode object ---------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Mode:
    """One eigenmode (ν̂, û, v̂, T̂)(y) exp(αt + ikx) of a steady flow (label eq:lin).

    Attributes
    ----------
    alpha : complex
        Eigenvalue α; Re α is the growth rate, Im α < 0 a wave travelling down the slope.
    k, kz : float
        Wavenumber along the slope (and across it, 3D).
    theta, nu0 : float
        Parameters of the base flow (degrees, floor packing fraction).
    n : int
        Resolution N (Chebyshev intervals) the eigenpair was computed at.
    y : ndarray
        The N + 1 collocation nodes on [0, y_max].
    fields : dict
        ``"nu"``, ``"u"``, ``"v"``, ``"T"`` (and ``"w"``) → complex nodal values, divided by
        the largest component of the whole eigenvector (paper's normalisation).
    drift : float
        |α(N) − α(N')|, N' = :attr:`n_check` < N: the eigenvalue's convergence estimate.
    tail : float
        Largest of the highest ten Chebyshev coefficients over the fields (normalised).
    physical : bool
        drift < ``drift_tol`` and tail < ``tail_tol``.
    """

    alpha: complex
    k: float
    kz: float
    theta: float
    nu0: float
    n: int
    y: np.ndarray = field(repr=False)
    fields: dict = field(repr=False)
    drift: float
    tail: float
    n_check: int
    physical: bool
    drift_tol: float = DRIFT_TOL
    tail_tol: float = TAIL_TOL

    @property
    def growth_rate(self) -> float:
        """Re α."""
        return float(self.alpha.real)

    @property
    def wave_speed(self) -> float:
        """Phase velocity c = −Im α / k, positive down the slope (→ dQ0/dρ̄0 as k → 0,
        appendix B); the convention of :mod:`chuteflow.conventions`."""
        return phase_velocity(self.alpha, self.k)

    def summary(self) -> dict:
        """JSON-ready scalars (keys used by the CLI)."""
        return {"k": self.k, "kz": self.kz, "alpha_re": float(self.alpha.real),
                "alpha_im": float(self.alpha.imag), "drift": float(self.drift),
                "tail": float(self.tail), "n": int(self.n), "n_check": int(self.n_check),
                "physical": bool(self.physical), "theta": self.theta, "nu0": self.nu0}

    def to_xarray(self):
        """Eigenfunctions as an :class:`xarray.Dataset` over y (complex), scalars as attrs."""
        import xarray as xr
        names = {"nu": "density perturbation ν̂", "u": "velocity perturbation û",
                 "v": "velocity perturbation v̂", "w": "velocity perturbation ŵ",
                 "T": "temperature perturbation T̂"}
        ds = xr.Dataset({f: ("y", v, {"long_name": names[f]}) for f, v in self.fields.items()},
                        coords={"y": ("y", self.y, {"long_name": "height above the floor",
                                                    "units": "sigma"})})
        ds.attrs.update({k: (str(v) if isinstance(v, bool) else v)
                         for k, v in self.summary().items()})
        return ds


def normalise(V: np.ndarray) -> np.ndarray:
    """V divided by its largest-modulus component (so that |Re| + |Im| of it is 1)."""
    i = int(np.argmax(np.abs(V)))
    return V / V[i] if V[i] != 0 else V


def tail(V: np.ndarray, nfields: int, m: int = TAIL_TERMS) -> float:
    """The paper's tail test statistic of an eigenvector (see module docstring)."""
    c = np.abs(coefficients(normalise(V).reshape(nfields, -1)))
    return float(c[:, -m:].max())


def _make_mode(pencil: Pencil, alpha, v, drift, n_check, drift_tol, tail_tol) -> Mode:
    v = normalise(pencil.unscale(np.asarray(v)))
    t = tail(v, len(pencil.fields))
    flow = pencil.flow
    return Mode(alpha=complex(alpha), k=pencil.k, kz=pencil.kz, theta=flow.theta,
                nu0=flow.nu0, n=pencil.n, y=pencil.grid.y,
                fields={f: v[s].copy() for f, s in pencil.slices().items()},
                drift=float(drift), tail=t, n_check=int(n_check),
                physical=bool(drift < drift_tol and t < tail_tol),
                drift_tol=drift_tol, tail_tol=tail_tol)


@functools.lru_cache(maxsize=32)
def _interp_matrix(n_from: int, n_to: int) -> np.ndarray:
    """Matrix mapping nodal values on N = n_from to the nodes of N = n_to (same interval)."""
    x = ChebyshevGrid(n_to, -1.0, 1.0).y
    C = coefficients(np.eye(n_from + 1))  # row j: Chebyshev coefficients of cardinal j
    return np.polynomial.chebyshev.chebvander(x, n_from) @ C.T


def _interp_vector(v: np.ndarray, nfields: int, n_from: int, n_to: int) -> np.ndarray:
    """Move an eigenvector between Chebyshev grids on the same interval (per field)."""
    M = _interp_matrix(n_from, n_to)
    return (v.reshape(nfields, n_from + 1) @ M.T).reshape(-1)


def _tols(drift_tol, tail_tol):
    for name, v in (("drift_tol", drift_tol), ("tail_tol", tail_tol)):
        if not (isinstance(v, (int, float)) and 0 < v < 1):
            raise ParameterError(f"{name} = {v!r} is outside (0, 1): it is a threshold on an "
                                 "eigenvalue change or a normalised Chebyshev coefficient")
    return float(drift_tol), float(tail_tol)


def nearest_eigenpair(pencil: Pencil, sigma: complex, v0=None):
    """The eigenpair (alpha, w) nearest σ, by shift-invert on the equilibrated pencil.

    One LU of A − σB; inverse iteration first (from ``v0`` if given, else from a random
    vector), Arnoldi (ARPACK) if that does not settle. With ``v0`` close to an eigenvector
    (continuation, another resolution) the iteration stays on that eigenpair even if
    another eigenvalue is marginally nearer σ — callers check the answer. ``w`` is an
    eigenvector of the *equilibrated* pencil (:meth:`Pencil.equilibrated`; the eigenvector
    of (A, B) is ``pencil.unscale(w)``); ``v0`` lives there too.
    """
    A, B = pencil.equilibrated()
    try:
        si = ShiftInvert(A, B, sigma, diagonal_B=True)
    except ConvergenceError:  # σ hit an eigenvalue to machine precision: nudge it
        sigma = complex(sigma) * (1 + 1e-12) + 1e-14 * (1 + 1j)
        si = ShiftInvert(A, B, sigma, diagonal_B=True)
    if v0 is not None:
        # a start vector from a nearby solve (continuation, the other resolution) makes
        # inverse iteration converge in a few solves; ARPACK is the fallback
        found = si.iterate(v0)
        if found is not None:
            return found
    else:
        # inverse iteration from a vector in the range of (A − σB)⁻¹B converges as fast
        # as Arnoldi when σ is close, for a fraction of the overhead
        rng = np.random.default_rng(2024)
        v0 = si.apply(rng.standard_normal(si.size) + 1j * rng.standard_normal(si.size))
        found = si.iterate(v0, maxiter=16)
        if found is not None:
            return found
    start = si.apply(v0)
    alpha, V = si.nearest(1, v0=start)
    if len(alpha) == 0:
        raise ConvergenceError(f"no eigenvalue converged near {complex(sigma):.6g} at "
                               f"N = {pencil.n}")
    return alpha[0], V[:, 0]


def drift_of(flow, alpha, v, n, kx, kz, three_d):
    """|α(N) − α(N')| with α(N') the eigenvalue at N' = check_n(N) nearest α(N)."""
    n2 = check_n(n)
    p2 = stability_operator(flow, n2, three_d).pencil(kx, kz)
    nf = len(p2.fields)
    a2, _ = nearest_eigenpair(p2, alpha, v0=_interp_vector(v, nf, n, n2))
    return abs(a2 - alpha), n2


def mode_near(flow: SteadyFlow, k: float, sigma: complex, *, kz: float = 0.0, n: int,
              drift_tol: float = DRIFT_TOL, tail_tol: float = TAIL_TOL, v0=None) -> Mode:
    """The eigenmode nearest the shift σ at resolution N, with drift and tail."""
    three_d = bool(kz)
    pencil = stability_operator(flow, n, three_d).pencil(k, kz)
    alpha, v = nearest_eigenpair(pencil, sigma, v0=v0)
    drift, n2 = drift_of(flow, alpha, v, n, k, kz, three_d)
    return _make_mode(pencil, alpha, v, drift, n2, drift_tol, tail_tol)


# -- whole spectrum (dense QZ) -----------------------------------------------------------
def spectrum(flow: SteadyFlow, k: float, *, kz: float = 0.0, n: int = N_DEFAULT,
             drift_tol: float = DRIFT_TOL, tail_tol: float = TAIL_TOL,
             physical_only: bool = True) -> list[Mode]:
    """All eigenmodes at wavenumber ``k`` by dense QZ at N and N', best first.

    Parameters
    ----------
    flow : SteadyFlow
        Base state.
    k, kz : float
        Wavenumbers (k ≥ 0; kz ≠ 0 for three-dimensional perturbations).
    n : int
        Resolution N; the drift is measured against N' = round(0.8 N).
    drift_tol, tail_tol : float
        Thresholds of the physical-mode tests (paper: 1e-7 both).
    physical_only : bool
        Return only physical modes (default) or every finite eigenvalue.

    Returns
    -------
    list of Mode
        Sorted by decreasing Re α. This is the reference the targeted solvers are tested
        against; it costs two dense QZ decompositions (seconds at N ~ 100).
    """
    k, kz = _check_k(k, "k"), _check_k(kz, "kz", signed=True)
    n = _check_n(n)
    drift_tol, tail_tol = _tols(drift_tol, tail_tol)
    three_d = bool(kz)
    p1 = stability_operator(flow, n, three_d).pencil(k, kz)
    n2 = check_n(n)
    p2 = stability_operator(flow, n2, three_d).pencil(k, kz)
    w1, V1 = qz(*p1.equilibrated())
    w2, _ = qz(*p2.equilibrated(), vectors=False)
    modes = []
    for j, a in enumerate(w1):
        drift = float(np.abs(w2 - a).min()) if len(w2) else math.inf
        mode = _make_mode(p1, a, V1[:, j], drift, n2, drift_tol, tail_tol)
        if mode.physical or not physical_only:
            modes.append(mode)
    return modes


# -- the least-stable mode ---------------------------------------------------------------
def least_stable(flow: SteadyFlow, k: float, *, kz: float = 0.0, n: int | None = None,
                 sigma: complex | None = None, method: str = "branch",
                 drift_tol: float = DRIFT_TOL, tail_tol: float = TAIL_TOL,
                 n_max: int = N_MAX) -> Mode:
    """The least-stable physical mode at wavenumber ``k``.

    Parameters
    ----------
    flow : SteadyFlow
        Base state.
    k, kz : float
        Wavenumber(s).
    n : int, optional
        Resolution N. Default: adaptive, from N = 80 upwards by factors 1.25 until the
        mode is physical (drift and tail below their thresholds), at most ``n_max``.
    sigma : complex, optional
        Shift: return the physical mode nearest σ (shift-invert Arnoldi at N, drift at N').
    method : {"branch", "qz"}
        Without ``sigma``: ``"branch"`` follows the branch with α(0) = 0 (the kinematic-wave
        mode of Appendix B, which the paper finds to be the least stable) from k = 0 by
        continuation — fast; ``"qz"`` scans the whole spectrum by dense QZ — the global
        reference, seconds.

    Raises
    ------
    ConvergenceError
        No physical mode reaches the thresholds by N = ``n_max``.
    """
    k, kz = _check_k(k, "k"), _check_k(kz, "kz", signed=True)
    drift_tol, tail_tol = _tols(drift_tol, tail_tol)
    if method not in ("branch", "qz"):
        raise ParameterError(f"method = {method!r}: choose 'branch' (continuation from k = 0) "
                             "or 'qz' (dense scan of the whole spectrum)")
    ns = [_check_n(n)] if n is not None else _ladder(n_max)
    last = None
    for nn in ns:
        if sigma is not None:
            mode = mode_near(flow, k, sigma, kz=kz, n=nn, drift_tol=drift_tol,
                             tail_tol=tail_tol)
        elif method == "qz":
            found = spectrum(flow, k, kz=kz, n=nn, drift_tol=drift_tol, tail_tol=tail_tol)
            mode = found[0] if found else None
        else:
            from .dispersion import branch_mode
            mode = branch_mode(flow, k, kz=kz, n=nn, drift_tol=drift_tol, tail_tol=tail_tol)
        if mode is not None and mode.physical:
            return mode
        last = mode
        if n is not None:
            break
    what = ("no physical mode" if last is None else
            f"best candidate α = {last.alpha:.6g} with drift {last.drift:.1e}, tail "
            f"{last.tail:.1e}")
    raise ConvergenceError(
        f"least-stable mode at theta = {flow.theta:g}, nu0 = {flow.nu0:g}, k = {k:g}: "
        f"{what} (thresholds drift {drift_tol:g}, tail {tail_tol:g}) up to N = "
        f"{ns[-1]}; raise n_max or relax the thresholds")


def _ladder(n_max: int, start: int = N_DEFAULT) -> list[int]:
    n_max = _check_n(n_max)
    out = [min(start, n_max)]
    while out[-1] < n_max:
        out.append(min(n_max, int(round(out[-1] * 1.25))))
    return out


def choose_n(flow: SteadyFlow, k: float, *, kz: float = 0.0, drift_tol: float = DRIFT_TOL,
             tail_tol: float = TAIL_TOL, n_max: int = N_MAX) -> int:
    """Smallest N of the ladder 80, 100, 125, … at which the least-stable (α(0) = 0 branch)
    mode at (k, kz) passes the drift and tail tests."""
    return least_stable(flow, k, kz=kz, drift_tol=drift_tol, tail_tol=tail_tol,
                        n_max=n_max).n

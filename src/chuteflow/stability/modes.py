"""Eigenmodes with their convergence estimates, and spurious-mode rejection (paper §4.1).

A computed eigenpair is *physical* when both of the paper's tests pass:

* **drift** — the eigenvalue changes by less than ``drift_tol`` (1e-7) between the
  resolution N and the coarser N' = round(0.8 N) (modes paired by nearest eigenvalue);
* **tail** — with the eigenvector normalised so that |Re| + |Im| of its largest component
  is 1 (we divide by that component, which also fixes the phase), the highest ten
  Chebyshev coefficients of every field are below ``tail_tol`` (1e-7).

Drift alone is not enough: the dilute top carries a continuum of near-neutral modes
α ≈ −ik u0(y) − 1e-8 that barely move with N but whose eigenvectors are not resolved
(tails ~1e-4; docs/errata.md). Every :class:`Mode` carries both numbers. The thresholds, the number
of tail coefficients and the ladder of resolutions N tried are one
:class:`~chuteflow.stability.policy.RejectionPolicy`, passed as ``policy=``.

Operators come from an :class:`OperatorCache` (``cache=``; default the shared
:data:`OPERATORS`), which never hands one flow's operator to another flow.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections import OrderedDict
from dataclasses import dataclass, field

import numpy as np

from ..closures import ChuteModel
from ..conventions import phase_velocity
from ..errors import ConvergenceError, ParameterError
from ..spectral import ChebyshevGrid, coefficients
from ..steady import SteadyFlow
from .eigen import ShiftInvert, qz
from .operator import Pencil, StabilityOperator, validate_k, validate_n
from .policy import DEFAULT_POLICY, RejectionPolicy

#: The paper's thresholds and ladder (fields of :data:`DEFAULT_POLICY`, kept as names).
DRIFT_TOL = DEFAULT_POLICY.drift_tol
TAIL_TOL = DEFAULT_POLICY.tail_tol
TAIL_TERMS = DEFAULT_POLICY.tail_terms
#: Default and largest resolution of the adaptive choice of N.
N_DEFAULT = DEFAULT_POLICY.n_start
N_MAX = DEFAULT_POLICY.n_max
#: Largest wavenumber (1/σ) the hydrodynamic description covers: k = 2π is a wavelength of one
#: particle diameter σ. Beyond it a continuum (kinetic-theory) field varying over less than a
#: grain has no meaning, and the solvers refuse the request instead of failing inside.
K_HYDRO_MAX = 2 * math.pi
#: Above this wavenumber the least-stable mode is solved directly at k (dense QZ with the
#: paper's rejection tests), without continuation of the α(0) = 0 branch from k = 0.
K_DIRECT = 1.0


def check_hydrodynamic_k(k: float, kz: float = 0.0) -> None:
    """Raise :class:`ParameterError` when |k| > :data:`K_HYDRO_MAX` (= 2π, wavelength below
    one particle diameter), where the hydrodynamic equations of the paper (§2) do not apply."""
    kk = math.hypot(k, kz)
    if kk > K_HYDRO_MAX:
        raise ParameterError(
            f"k = {kk:g} is outside [0, 2π = {K_HYDRO_MAX:.4g}]: the wavelength 2π/k = "
            f"{2 * math.pi / kk:.3g} σ is shorter than one particle diameter, where the "
            "continuum (kinetic-theory) hydrodynamics does not apply"
        )


def resolve_policy(
    policy: RejectionPolicy | None = None,
    *,
    drift_tol: float | None = None,
    tail_tol: float | None = None,
    n_max: int | None = None,
) -> RejectionPolicy:
    """``policy`` (default :data:`DEFAULT_POLICY`) with the given fields overridden.

    The keywords ``drift_tol``, ``tail_tol`` and ``n_max`` of the solvers are shorthands for
    these overrides (``None``: the policy's value).
    """
    if policy is None:
        policy = DEFAULT_POLICY
    elif not isinstance(policy, RejectionPolicy):
        raise ParameterError(f"policy = {policy!r}: expected a RejectionPolicy")
    return policy.replace(drift_tol=drift_tol, tail_tol=tail_tol, n_max=n_max)


def check_n(n: int) -> int:
    """The comparison resolution N' = round(0.8 N) (at most N − 8).

    The coarser of the two resolutions is the check: |α(N) − α(N')| then bounds the error
    of α(N') and, the discretisation converging spectrally, over-estimates that of α(N),
    which is what is returned. It also costs half a factorisation at N rather than two.
    """
    return max(min(int(round(0.8 * n)), n - 8), 8)


# -- operator cache ----------------------------------------------------------------------
def _fingerprint(flow: SteadyFlow) -> tuple:
    """What an operator depends on and could change in place: the profiles' bytes."""
    return (
        flow.theta,
        flow.nu0,
        flow.nu_top,
        flow.n,
        flow.y_max,
        id(flow.model),
        hash(np.asarray(flow.log_nu).tobytes()),
        hash(np.asarray(flow.u).tobytes()),
        hash(np.asarray(flow.T).tobytes()),
    )


class OperatorCache:
    """The last few :class:`StabilityOperator` s built, per (flow, N, three_d).

    A flow is matched by identity *and* by a fingerprint of its profiles, so two different
    flow objects never share an operator (even if one is freed and the other reuses its
    address: an operator keeps its flow alive while cached) and a flow whose arrays were
    changed in place gets a new one. Least recently used entries are dropped beyond
    ``maxsize`` (an operator at N = 256 holds ~60 MB).

    The solvers take ``cache=`` (default: one cache shared by the module's functions,
    :data:`OPERATORS`); pass an own cache to keep a computation's operators apart.
    ``mapped`` chooses the grid of every operator it builds: the sinh-mapped grid (default,
    :func:`~chuteflow.stability.operator.layer_map`) or, with False, the paper's plain
    Chebyshev grid — ``cache=OperatorCache(mapped=False)`` runs any solver on the plain
    grid, as an independent check.
    """

    def __init__(self, maxsize: int = 6, *, mapped: bool = True, mapped_3d: bool = False):
        if int(maxsize) < 1:
            raise ParameterError(f"maxsize = {maxsize!r}: an operator cache holds at least one")
        self.maxsize = int(maxsize)
        self.mapped = bool(mapped)
        self.mapped_3d = bool(mapped_3d) and self.mapped
        self._entries: OrderedDict = OrderedDict()

    def for_finite_k(self) -> OperatorCache:
        """The cache of the same grid choice for modes at finite wavevectors in 3D: itself
        when it already maps 3D operators or builds plain ones only (``mapped=False``, a
        check on the paper's grid), else :data:`OPERATORS_3D` (see :func:`cache_for`)."""
        if self.mapped_3d or not self.mapped:
            return self
        return OPERATORS_3D

    def get(self, flow: SteadyFlow, n: int, three_d: bool = False) -> StabilityOperator:
        """The operator of ``flow`` at N = ``n``, built on the first request."""
        key = (id(flow), int(n), bool(three_d))
        fp = _fingerprint(flow)
        entry = self._entries.get(key)
        if entry is not None and entry[0].flow is flow and entry[1] == fp:
            self._entries.move_to_end(key)
            return entry[0]
        op = StabilityOperator(flow, n, three_d=three_d, mapped=self.mapped_3d if three_d else self.mapped)
        self._entries[key] = (op, fp)
        self._entries.move_to_end(key)
        while len(self._entries) > self.maxsize:
            self._entries.popitem(last=False)
        return op

    def clear(self) -> None:
        """Drop every cached operator."""
        self._entries.clear()

    def __len__(self) -> int:
        return len(self._entries)


#: The cache the module's functions use unless given another: 2D operators on the mapped
#: grid, 3D ones on the plain grid (the k → 0 quantities, :func:`cache_for`).
OPERATORS = OperatorCache(6)
#: 3D operators on the mapped grid: finite-wavevector modes (:func:`cache_for`).
OPERATORS_3D = OperatorCache(4, mapped_3d=True)


def cache_for(kz: float, cache: OperatorCache | None = None) -> OperatorCache:
    """The one place where the grid of a question is chosen.

    Finite-wavevector modes, 2D and 3D, are solved on the sinh-mapped grid clustered at the
    layer's edge (:func:`~chuteflow.stability.operator.layer_map`): at P5, (k_x, k_z) =
    (0.002, 0.02) the least-stable mode passes the paper's tests at N = 75 on it and needs
    N ≈ 200–250 on the plain grid. The plain grid stays only where a k → 0 quantity needs it:
    α2z and the tracked transverse branch (:mod:`chuteflow.longwave.spanwise`,
    :mod:`chuteflow.stability.transverse`, which build their operators from :data:`OPERATORS`), whose
    relative change N = 80 → 100 is 4e-5 on the mapped grid against 8e-6 on the plain one.
    ``cache`` (default :data:`OPERATORS`) keeps its own choice when it maps 3D operators or
    builds plain ones only (``OperatorCache(mapped=False)``, the independent check)."""
    cache = OPERATORS if cache is None else cache
    return cache.for_finite_k() if kz else cache


def stability_operator(
    flow: SteadyFlow, n: int, three_d: bool = False, *, cache: OperatorCache | None = None
) -> StabilityOperator:
    """A :class:`StabilityOperator` of ``flow`` at N = ``n``, from ``cache`` (default
    :data:`OPERATORS`)."""
    return (OPERATORS if cache is None else cache).get(flow, n, three_d)


# -- the mode object ---------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Mode:
    """One eigenmode (ν̂, û, v̂, T̂)(y) exp(αt + ikx) of a steady flow (eq. (4.4)).

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
    grid : ChebyshevGrid
        The collocation grid of :attr:`y` (sinh-mapped by default; derivatives,
        quadrature and interpolation of the fields go through it).
    fields : dict
        ``"nu"``, ``"u"``, ``"v"``, ``"T"`` (and ``"w"``) → complex nodal values, divided by
        the largest component of the whole eigenvector (paper's normalisation).
    drift : float
        |α(N) − α(N')|, N' = :attr:`n_check` < N: the eigenvalue's convergence estimate.
    tail : float
        Largest of the highest ten Chebyshev coefficients over the fields (normalised).
    physical : bool
        drift < ``drift_tol`` and tail < ``tail_tol``.
    model : ChuteModel or None
        Parameters and closures of the base flow the mode was computed with.
    method : str
        Which solver answered: ``"branch"`` (continuation of the α(0) = 0 branch),
        ``"qz"`` (dense QZ at k), ``"shift"`` (shift-invert near a given σ),
        ``"branch (relaxed)"`` (the branch followed with the continuation's tail threshold
        relaxed after it was lost near the continuum,
        :func:`~chuteflow.stability.lost.near_continuum_branch`), or
        ``"qz (branch lost)"`` (direct solve where even that did not reach k, or where the
        policy ranks it above the relaxed branch,
        :meth:`~chuteflow.stability.RejectionPolicy.direct_outranks_relaxed`).
    note : str
        What the solver wants the reader to know about this answer (e.g. where the branch
        was lost, the largest Re α of the unresolved continuum); empty if nothing.
    continuum_re : float
        Direct solves (:func:`direct_mode`): the largest Re α of eigenvalues above this mode
        that converge in N but whose eigenvectors are not resolved (the dilute top's
        continuum, or a branch N does not yet resolve); NaN when there are none.
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
    model: ChuteModel | None = None
    method: str = "branch"
    note: str = ""
    grid: ChebyshevGrid | None = field(default=None, repr=False)
    continuum_re: float = math.nan

    @property
    def converged(self) -> bool:
        """Both of the paper's tests pass (same as :attr:`physical`); when False the mode is
        the best estimate found, with its :attr:`drift` and :attr:`tail`."""
        return bool(self.physical)

    @property
    def growth_rate(self) -> float:
        """Re α."""
        return float(self.alpha.real)

    @property
    def wave_speed(self) -> float:
        """Phase velocity c = −Im α / k, positive down the slope (→ dQ0/dρ̄0 as k → 0,
        appendix B); the convention of :mod:`chuteflow.conventions`."""
        return phase_velocity(self.alpha, self.k)

    def to_dict(self) -> dict:
        """JSON-ready scalars (keys used by the CLI)."""
        return {
            "k": self.k,
            "kz": self.kz,
            "alpha_re": float(self.alpha.real),
            "alpha_im": float(self.alpha.imag),
            "drift": float(self.drift),
            "tail": float(self.tail),
            "n": int(self.n),
            "n_check": int(self.n_check),
            "physical": bool(self.physical),
            "converged": bool(self.physical),
            "method": self.method,
            "note": self.note,
            "theta": self.theta,
            "nu0": self.nu0,
            **(self.model.to_dict() if self.model is not None else {}),
        }

    def to_xarray(self):
        """Eigenfunctions as an :class:`xarray.Dataset` over y (complex), scalars as attrs."""
        import xarray as xr

        names = {
            "nu": "density perturbation ν̂",
            "u": "velocity perturbation û",
            "v": "velocity perturbation v̂",
            "w": "velocity perturbation ŵ",
            "T": "temperature perturbation T̂",
        }
        ds = xr.Dataset(
            {f: ("y", v, {"long_name": names[f]}) for f, v in self.fields.items()},
            coords={"y": ("y", self.y, {"long_name": "height above the floor", "units": "sigma"})},
        )
        ds.attrs.update({k: (str(v) if isinstance(v, bool) else v) for k, v in self.to_dict().items()})
        if self.model is not None:
            ds.attrs.update(self.model.attrs())
        return ds


def normalise(V: np.ndarray) -> np.ndarray:
    """V divided by its largest-modulus component (so that |Re| + |Im| of it is 1)."""
    i = int(np.argmax(np.abs(V)))
    return V / V[i] if V[i] != 0 else V


def tail(V: np.ndarray, nfields: int, m: int = TAIL_TERMS) -> float:
    """The paper's tail test statistic of an eigenvector (see module docstring)."""
    c = np.abs(coefficients(normalise(V).reshape(nfields, -1)))
    return float(c[:, -m:].max())


def tails(pencil: Pencil, W: np.ndarray, m: int = TAIL_TERMS) -> np.ndarray:
    """:func:`tail` of every column of W (eigenvectors of the equilibrated ``pencil``),
    vectorised."""
    nf, n1 = len(pencil.fields), pencil.n + 1
    V = pencil.unscale(W)
    big = V[np.argmax(np.abs(V), axis=0), np.arange(V.shape[1])]
    V = V / np.where(big == 0, 1.0, big)[None, :]
    c = np.abs(coefficients(V.T.reshape(-1, nf, n1)))
    return c[:, :, -m:].max(axis=(1, 2))


def make_mode(pencil: Pencil, alpha, v, drift, n_check, policy: RejectionPolicy = DEFAULT_POLICY) -> Mode:
    """A :class:`Mode` from an eigenpair of the equilibrated ``pencil``.

    The eigenvector ``v`` is unscaled to the physical (ν̂, û, v̂, T̂) and normalised (largest
    component 1); its Chebyshev tail is measured, and ``physical`` is decided by ``policy``
    from ``drift`` (|α(N) − α(N')|, N' = ``n_check``) and that tail.
    """
    v = normalise(pencil.unscale(np.asarray(v)))
    t = tail(v, len(pencil.fields), policy.tail_terms)
    flow = pencil.flow
    return Mode(
        alpha=complex(alpha),
        k=pencil.k,
        kz=pencil.kz,
        theta=flow.theta,
        nu0=flow.nu0,
        n=pencil.n,
        y=pencil.grid.y,
        grid=pencil.grid,
        fields={f: v[s].copy() for f, s in pencil.slices().items()},
        drift=float(drift),
        tail=t,
        n_check=int(n_check),
        physical=policy.accepts(drift, t),
        drift_tol=policy.drift_tol,
        tail_tol=policy.tail_tol,
        model=flow.model,
    )


@functools.lru_cache(maxsize=32)
def _interp_matrix(n_from: int, n_to: int) -> np.ndarray:
    """Matrix mapping nodal values on N = n_from to the nodes of N = n_to (same interval)."""
    x = ChebyshevGrid(n_to, -1.0, 1.0).y
    C = coefficients(np.eye(n_from + 1))  # row j: Chebyshev coefficients of cardinal j
    return np.polynomial.chebyshev.chebvander(x, n_from) @ C.T


def interp_vector(v: np.ndarray, nfields: int, n_from: int, n_to: int) -> np.ndarray:
    """Move an eigenvector between two grids of the same map (per field; exact in the
    computational variable, whatever the map)."""
    M = _interp_matrix(n_from, n_to)
    return (v.reshape(nfields, n_from + 1) @ M.T).reshape(-1)


def nearest_eigenpair(pencil: Pencil, sigma: complex, v0=None, *, restarts: int = 60):
    """The eigenpair (alpha, w) nearest σ, by shift-invert on the equilibrated pencil.

    One LU of A − σB; inverse iteration first (from ``v0`` if given, else from a random
    vector), Arnoldi (ARPACK, at most ``restarts`` restarts per Krylov size,
    :meth:`ShiftInvert.nearest`) if that does not settle. With ``v0`` close to an eigenvector
    (continuation, another resolution) the iteration stays on that eigenpair even if
    another eigenvalue is marginally nearer σ — callers check the answer. ``w`` is an
    eigenvector of the *equilibrated* pencil (:meth:`Pencil.equilibrated`; the eigenvector
    of (A, B) is ``pencil.unscale(w)``); ``v0`` lives there too.
    """
    A, B = pencil.equilibrated()
    si = ShiftInvert.nudged(A, B, sigma, diagonal_B=True)
    sigma = si.sigma
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
    alpha, V = si.nearest(1, v0=start, maxiter=restarts)
    if len(alpha) == 0:
        raise ConvergenceError(f"no eigenvalue converged near {complex(sigma):.6g} at N = {pencil.n}")
    return alpha[0], V[:, 0]


def drift_of(flow, alpha, v, n, kx, kz, three_d, *, cache: OperatorCache | None = None):
    """|α(N) − α(N')| with α(N') the eigenvalue at N' = check_n(N) nearest α(N)."""
    n2 = check_n(n)
    p2 = stability_operator(flow, n2, three_d, cache=cache).pencil(kx, kz)
    nf = len(p2.fields)
    a2, _ = nearest_eigenpair(p2, alpha, v0=interp_vector(v, nf, n, n2))
    return abs(a2 - alpha), n2


def mode_near(
    flow: SteadyFlow,
    k: float,
    sigma: complex,
    *,
    kz: float = 0.0,
    n: int,
    policy: RejectionPolicy | None = None,
    drift_tol: float | None = None,
    tail_tol: float | None = None,
    v0=None,
    cache: OperatorCache | None = None,
) -> Mode:
    """The eigenmode nearest the shift σ at resolution N, with drift and tail judged by
    ``policy`` (``drift_tol``, ``tail_tol``: overrides of its thresholds)."""
    policy = resolve_policy(policy, drift_tol=drift_tol, tail_tol=tail_tol)
    three_d = bool(kz)
    pencil = stability_operator(flow, n, three_d, cache=cache).pencil(k, kz)
    alpha, v = nearest_eigenpair(pencil, sigma, v0=v0)
    drift, n2 = drift_of(flow, alpha, v, n, k, kz, three_d, cache=cache)
    return make_mode(pencil, alpha, v, drift, n2, policy)


# -- whole spectrum (dense QZ) -----------------------------------------------------------
def spectrum(
    flow: SteadyFlow,
    k: float,
    *,
    kz: float = 0.0,
    n: int | None = None,
    policy: RejectionPolicy | None = None,
    drift_tol: float | None = None,
    tail_tol: float | None = None,
    physical_only: bool = True,
    cache: OperatorCache | None = None,
) -> list[Mode]:
    """All eigenmodes at wavenumber ``k`` by dense QZ at N and N', best first.

    Parameters
    ----------
    flow : SteadyFlow
        Base state.
    k, kz : float
        Wavenumbers (k ≥ 0; kz ≠ 0 for three-dimensional perturbations).
    n : int, optional
        Resolution N (default ``policy.n_start``, 80); the drift is measured against
        N' = round(0.8 N).
    policy : RejectionPolicy, optional
        Thresholds of the physical-mode tests (default: the paper's, 1e-7 both).
    drift_tol, tail_tol : float, optional
        Overrides of the policy's thresholds.
    physical_only : bool
        Return only physical modes (default) or every finite eigenvalue.
    cache : OperatorCache, optional
        Where the operators come from (default: the module's shared cache).

    Returns
    -------
    list of Mode
        Sorted by decreasing Re α. This is the reference the targeted solvers are tested
        against; it costs two dense QZ decompositions (seconds at N ~ 100).
    """
    k, kz = validate_k(k, "k"), validate_k(kz, "kz", signed=True)
    policy = resolve_policy(policy, drift_tol=drift_tol, tail_tol=tail_tol)
    n = validate_n(policy.n_start if n is None else n)
    three_d = bool(kz)
    op1 = stability_operator(flow, n, three_d, cache=cache)
    p1 = op1.pencil(k, kz)
    n2 = check_n(n)
    op2 = stability_operator(flow, n2, three_d, cache=cache)
    w1, V1 = qz(*p1.equilibrated())
    op1.remember_eigenvalues(k, kz, w1)
    # on the policy's ladder (80, 100, 125, …: factors 1.25) N' is the rung below, whose
    # eigenvalues the previous call computed: the check's QZ is not repeated
    w2 = op2.qz_eigenvalues.get((float(k), float(kz)))
    if w2 is None:
        w2, _ = qz(*op2.pencil(k, kz).equilibrated(), vectors=False)
        op2.remember_eigenvalues(k, kz, w2)
    modes = []
    for j, a in enumerate(w1):
        drift = float(np.abs(w2 - a).min()) if len(w2) else math.inf
        mode = make_mode(p1, a, V1[:, j], drift, n2, policy)
        if mode.physical or not physical_only:
            modes.append(mode)
    return modes


# -- the least-stable mode ---------------------------------------------------------------
def mode_score(mode: Mode, policy: RejectionPolicy) -> float:
    """How far a mode is from passing both tests (≤ 1: passes)."""
    return max(mode.drift / policy.drift_tol, mode.tail / policy.tail_tol)


def join_notes(*parts: str) -> str:
    """The non-empty ``parts`` joined by ``"; "`` (the :attr:`Mode.note` of a combined answer)."""
    return "; ".join(p for p in parts if p)


def direct_mode(
    flow: SteadyFlow,
    k: float,
    *,
    kz: float = 0.0,
    n: int,
    policy: RejectionPolicy | None = None,
    cache: OperatorCache | None = None,
    modes: list[Mode] | None = None,
) -> Mode | None:
    """The least-stable mode at (k, kz) solved directly at that wavenumber (dense QZ at N
    and N', no continuation from k = 0), judged by ``policy``; ``modes``: the spectrum
    (:func:`spectrum` with ``physical_only=False``) when the caller has it already.

    Returns the physical mode of largest Re α; when none passes both tests, the candidate
    nearest to passing (smallest max(drift/drift_tol, tail/tail_tol)) among the resolved
    eigenvectors (tail below ``policy.track_tail_tol``, or all of them if none is), flagged
    ``physical = False``; None when QZ gives no finite eigenvalue.
    """
    policy = resolve_policy(policy)
    if modes is None:
        modes = spectrum(flow, k, kz=kz, n=n, policy=policy, physical_only=False, cache=cache)
    phys = [m for m in modes if m.physical]
    # the near-neutral continuum of the dilute top: eigenvalues that converge (drift) but
    # whose eigenvectors are not resolved (tail); they are not modes, but bound Re α
    cont = [
        m
        for m in modes
        if not m.physical and m.drift < 1e-4 and (not phys or m.alpha.real > phys[0].alpha.real)
    ]
    note = ""
    if cont:
        top = max(cont, key=lambda m: m.alpha.real)
        note = (
            f"unresolved continuum (dilute top) up to Re α = {top.alpha.real:.2e} at "
            f"Im α/k = {top.alpha.imag / k if k else math.nan:.4g}"
        )
    # an eigenvalue above the best physical one whose eigenvector is nearly resolved (tail
    # below the tracking threshold, unlike the continuum's ~1e-4) is a physical mode that
    # N does not yet resolve (e.g. the α(0) = 0 branch near the continuum): it is the
    # least-stable estimate, flagged, rather than a more stable mode that passes
    near = [
        m
        for m in modes
        if not m.physical
        and m.tail < policy.track_tail_tol
        and m.drift < 1e-3 * max(1.0, abs(m.alpha))
        and (not phys or m.alpha.real > phys[0].alpha.real)
    ]
    if near:
        best = max(near, key=lambda m: m.alpha.real)
        return dataclasses.replace(
            best,
            method="qz",
            note=join_notes(
                note,
                f"least-stable candidate not resolved at N = {n} (drift {best.drift:.1e}, "
                f"tail {best.tail:.1e})"
                + (f"; the least-stable resolved mode has Re α = {phys[0].alpha.real:.4g}" if phys else ""),
            ),
        )
    if phys:
        return dataclasses.replace(
            phys[0],
            method="qz",
            note=note,
            continuum_re=max(m.alpha.real for m in cont) if cont else math.nan,
        )
    if not modes:
        return None
    resolved = [m for m in modes if m.tail < policy.track_tail_tol] or modes
    return dataclasses.replace(min(resolved, key=lambda m: mode_score(m, policy)), method="qz", note=note)

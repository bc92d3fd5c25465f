"""The least-stable physical mode at any wavevector (k_x, k_z): dense scan and k_z scans.

Across the slope (k_x = 0) the pencil is real after the diagonal similarity ŵ → i ŵ
(:mod:`chuteflow.stability.realform`), so its eigenvalues are real or come in conjugate
pairs and the real QZ (half the cost of the complex one) applies. At each wavevector the
finite eigenvalues at N are all scanned by decreasing Re α (:func:`least_stable_3d`); an
eigenvalue is accepted, as in 2D (paper §4.1, :class:`RejectionPolicy`), when its
eigenvector's Chebyshev tail and its drift |α(N) − α(N')| (N' = round(0.8 N), nearest
eigenvalue of the QZ at N') are below the policy's thresholds. The near-neutral continuum
of the dilute top (α ≈ −1e-8 at k_x = 0) fails the tail test. N is raised along the
policy's ladder when no eigenvalue passes, or when a resolved eigenvector (tail below the
threshold) with a larger Re α than the accepted one fails only the drift test (P1,
k_z = 0.005: α = −0.2719 + 0.5123i drifts by 1e-7 between N = 64 and 80 and is converged
from N = 100 on).

The dense scan costs two QZ per k_z (about 1 s at N = 80–100). The fast path,
:class:`~chuteflow.stability.transverse_tracking.TransverseTracker`, follows the α(0) = 0
branch in k_z instead (real inverse iteration on the continuation of
:func:`chuteflow.continuation.continue_to`). At P1 the branch rises to α ~ 6e-5 at
k_z ~ 2e-3, falls back through the near-neutral continuum of the dilute top at
k_z ≈ 3.25e-3 and is lost in it (its eigenvector is no longer resolved); the least-stable
physical mode at larger k_z is another one. :func:`transverse_dispersion` with
``method="track"`` follows the branch while it is resolved and, beyond, a few candidate
modes taken from one dense scan (each by shift-invert, re-seeded by a dense scan whenever a
candidate is lost; :mod:`chuteflow.stability.transverse_beyond`); ``method="dense"`` is the
reference scan at every k_z. Past the branch the shift-invert solves also run on the real
form (a real LU when the shift is real, a fifth of the complex one's cost), the seeding scan
is the dense eigenproblem of (A' − σB')⁻¹B' (a third of the QZ's), and the check α(N') of a
rung of the resolution ladder is the α just solved on the rung below: the same eigenpairs as
the complex solves, to round-off (at P1 the 50-k_z dispersion past the branch took 3.3 s of
CPU before, 1.7–2.0 s after).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ..conventions import RATE_UNITS, WAVENUMBER_UNITS
from ..errors import ConvergenceError, ParameterError
from ..steady import SteadyFlow
from .modes import (
    Mode,
    OperatorCache,
    check_n,
    drift_of,
    interp_vector,
    make_mode,
    nearest_eigenpair,
    stability_operator,
    tails,
)
from .operator import validate_k
from .policy import DEFAULT_POLICY, RejectionPolicy
from .realform import pencil_qz, real_form
from .tracking import branch_mode
from .transverse_beyond import _beyond_branch
from .transverse_tracking import TransverseTracker, TransverseTrackingPolicy

__all__ = [
    "TransverseDispersion",
    "TransverseTracker",
    "TransverseTrackingPolicy",
    "dense_modes",
    "growth_plane",
    "judge_resolved",
    "least_stable_3d",
    "real_form",
    "transverse_dispersion",
    "transverse_mode",
]


def least_stable_3d(
    flow: SteadyFlow,
    kx: float,
    kz: float,
    *,
    policy: RejectionPolicy = DEFAULT_POLICY,
    n: int | None = None,
    strict: bool = False,
) -> Mode:
    """The physical mode of largest Re α at (k_x, k_z), by a dense scan (module docstring).

    Parameters
    ----------
    flow : SteadyFlow
        Base state.
    kx, kz : float
        Wavevector (k_x ≥ 0; k_z of either sign).
    policy : RejectionPolicy
        Drift and tail thresholds and the resolution ladder.
    n : int, optional
        First resolution (default ``policy.n_start``).
    strict : bool
        Raise :class:`ConvergenceError` when no physical mode is found up to ``policy.n_max``;
        otherwise return the best candidate (``physical = False``).
    """
    kx, kz = validate_k(kx, "kx"), validate_k(kz, "kz", signed=True)
    best = accepted = None
    for nn in policy.ladder(n):
        n2 = max(8, round(0.8 * nn))
        p1 = stability_operator(flow, nn, True).pencil(kx, kz)
        p2 = stability_operator(flow, n2, True).pencil(kx, kz)
        w1, V1 = pencil_qz(p1, True)
        w2, _ = pencil_qz(p2, False)
        tl = tails(p1, V1, policy.tail_terms)
        pending = False  # a resolved eigenvector above the accepted one whose α drifts
        for j in range(len(w1)):
            if tl[j] >= policy.track_tail_tol:
                continue
            drift = float(np.abs(w2 - w1[j]).min()) if len(w2) else math.inf
            if policy.accepts(drift, tl[j]):
                accepted = make_mode(p1, w1[j], V1[:, j], drift, n2, policy)
                break
            if tl[j] < policy.tail_tol:
                pending = True
            if best is None:
                best = make_mode(p1, w1[j], V1[:, j], drift, n2, policy)
        if accepted is not None and not pending:
            return accepted
        best = None
    if accepted is not None:
        return accepted
    if strict or best is None:
        raise ConvergenceError(
            f"no physical mode at kx = {kx:g}, kz = {kz:g} (theta = {flow.theta:g}, "
            f"nu0 = {flow.nu0:g}) up to N = {policy.n_max}"
        )
    return best


def transverse_mode(
    flow: SteadyFlow, kz: float, *, policy: RejectionPolicy = DEFAULT_POLICY, n: int | None = None
) -> Mode:
    """The least-stable physical mode across the slope (k_x = 0): :func:`least_stable_3d`."""
    return least_stable_3d(flow, 0.0, kz, policy=policy, n=n)


@dataclass(frozen=True, eq=False)
class TransverseDispersion:
    """α(k_z) of the least-stable physical mode at k_x = 0, with convergence estimates.

    Attributes
    ----------
    kz, alpha_re, alpha_im, drift, tail : ndarray
        Wavenumbers and, at each, Re α, Im α, |α(N) − α(N')| and the Chebyshev tail.
    n : ndarray of int
        Resolution N of each point.
    physical : ndarray of bool
        Whether each point passes the policy's tests.
    theta, nu0 : float
        The flow.
    attrs : dict
        The flow's model attributes.
    method : ndarray of str, optional
        Which solver answered at each k_z: ``"branch"`` (the tracked α(0) = 0 branch),
        ``"shift"`` (a candidate followed by shift-invert past the branch), ``"qz"`` (dense).
    branch_lost_at : float or None
        Where the tracked branch entered the continuum (None: not lost, or dense scan).
    """

    kz: np.ndarray
    alpha_re: np.ndarray
    alpha_im: np.ndarray
    drift: np.ndarray
    tail: np.ndarray
    n: np.ndarray
    physical: np.ndarray
    theta: float
    nu0: float
    attrs: dict
    method: np.ndarray | None = None
    branch_lost_at: float | None = None

    @property
    def converged(self) -> bool:
        """Every k_z was computed and passed the policy's drift and tail tests."""
        return bool(np.isfinite(self.alpha_re).all() and np.asarray(self.physical, dtype=bool).all())

    @property
    def note(self) -> str:
        """Empty when converged; else how many k_z were not computed or missed a test."""
        done = np.isfinite(self.alpha_re)
        bad = int((~np.asarray(self.physical, dtype=bool)[done]).sum())
        parts = []
        if not done.all():
            parts.append(f"{int((~done).sum())} of {len(done)} k_z not computed")
        if bad:
            parts.append(f"{bad} k_z miss the drift or tail test")
        return "; ".join(parts)

    def to_dict(self) -> dict:
        """JSON-ready dict: the arrays as lists, the flow and the convergence."""
        return {
            "theta": self.theta,
            "nu0": self.nu0,
            "kz": [float(v) for v in self.kz],
            "alpha_re": [float(v) for v in self.alpha_re],
            "alpha_im": [float(v) for v in self.alpha_im],
            "drift": [float(v) for v in self.drift],
            "tail": [float(v) for v in self.tail],
            "n": [int(v) for v in self.n],
            "physical": [bool(v) for v in self.physical],
            "branch_lost_at": self.branch_lost_at,
            "converged": self.converged,
            "note": self.note,
            **self.attrs,
        }

    def to_xarray(self):
        """An :class:`xarray.Dataset` over ``kz``."""
        import xarray as xr

        u = RATE_UNITS
        return xr.Dataset(
            {
                "alpha_re": ("kz", self.alpha_re, {"long_name": "growth rate Re alpha", "units": u}),
                "alpha_im": ("kz", self.alpha_im, {"long_name": "Im alpha", "units": u}),
                "drift": ("kz", self.drift, {"long_name": "|alpha(N) - alpha(N')|", "units": u}),
                "tail": ("kz", self.tail, {"long_name": "Chebyshev tail", "units": "1"}),
                "n": ("kz", self.n, {"long_name": "Chebyshev intervals N"}),
                "physical": ("kz", self.physical, {"long_name": "passes drift and tail tests"}),
                **(
                    {"method": ("kz", np.asarray(self.method, dtype=str), {"long_name": "solver"})}
                    if self.method is not None
                    else {}
                ),
            },
            coords={"kz": ("kz", self.kz, {"long_name": "spanwise wavenumber", "units": WAVENUMBER_UNITS})},
            attrs={
                "long_name": "transverse dispersion relation (kx = 0)",
                "theta": self.theta,
                "nu0": self.nu0,
                **({"branch_lost_at": self.branch_lost_at} if self.branch_lost_at is not None else {}),
                **self.attrs,
            },
        )


def transverse_dispersion(
    flow: SteadyFlow,
    kz,
    *,
    policy: RejectionPolicy = DEFAULT_POLICY,
    n: int | None = None,
    method: str = "track",
    alpha2z: float | None = None,
    beyond: bool = False,
    cache: OperatorCache | None = None,
    tracker: TransverseTracker | None = None,
    tracking: TransverseTrackingPolicy | None = None,
) -> TransverseDispersion:
    """α(k_z) at k_x = 0 of the least-stable physical mode at each k_z (module docstring).

    Parameters
    ----------
    flow : SteadyFlow
        Base state.
    kz : array_like
        Spanwise wavenumbers (> 0).
    policy : RejectionPolicy
        Drift and tail thresholds and the resolution ladder.
    n : int, optional
        First resolution (default ``policy.n_start``).
    method : {"track", "dense"}
        ``"track"`` (fast): the α(0) = 0 branch by
        :class:`~chuteflow.stability.transverse_tracking.TransverseTracker` while it is
        resolved; the k_z past the point where it enters the continuum are left NaN
        (``method = "lost"``) unless ``beyond``. ``"dense"``: the dense scan
        (:func:`least_stable_3d`) at every k_z, the reference.
    alpha2z : float, optional
        Predictor of the tracked branch's first steps (``"track"``).
    beyond : bool
        ``"track"`` only: past the branch, follow candidate modes seeded by a coarse dense
        scan (N = ``tracking.seed_n``, 48) by shift-invert at N ≤ 125. Approximate: the
        least-stable mode there lies among modes that the drift and tail tests accept only
        at different N, and the candidates and the dense scan can each miss one the other
        finds (P1, k_z = 0.038: dense −0.052 at N = 156, candidates −0.347 at N = 100).
    cache : OperatorCache, optional
        Where the operators come from (``"track"``).
    tracker : TransverseTracker, optional
        A tracker to continue (``"track"``; its history is kept for later refinement).
    tracking : TransverseTrackingPolicy, optional
        Tuning of the tracked branch and of the candidates past it (``"track"``; default:
        the tracker's, else :data:`~chuteflow.stability.transverse_tracking.DEFAULT_TRANSVERSE`).

    Returns
    -------
    TransverseDispersion
        Points where no physical mode is found keep the best resolved candidate, flagged
        ``physical = False``; ``method`` says which solver answered at each k_z
        (``"branch"``, ``"shift"`` past the branch, ``"qz"``).
    """
    ks = np.atleast_1d(np.asarray(kz, dtype=float))
    if ks.ndim != 1 or len(ks) == 0:
        raise ParameterError("kz: expected a non-empty 1-D array of wavenumbers")
    if method not in ("track", "dense"):
        raise ParameterError(f"method = {method!r}: choose 'track' (fast) or 'dense' (reference scan)")
    if np.any(ks <= 0) or not np.all(np.isfinite(ks)):
        raise ParameterError("kz: wavenumbers must be finite and > 0 (k_z = 0 is the mass mode)")
    out = np.full((4, len(ks)), np.nan)
    nres = np.zeros(len(ks), dtype=int)
    phys = np.zeros(len(ks), dtype=bool)
    how = np.full(len(ks), "", dtype=object)
    modes: list[Mode | None] = [None] * len(ks)
    lost_at = None
    if method == "dense":
        for i, k in enumerate(ks):
            try:
                m = transverse_mode(flow, float(k), policy=policy, n=n)
                modes[i] = dataclasses.replace(m, method="qz")
            except ConvergenceError:
                continue
    else:
        order = np.argsort(ks)
        tr = tracker or TransverseTracker(
            flow, alpha2z=alpha2z, n=n, policy=policy, cache=cache, tracking=tracking
        )
        rest = []
        for i in order:
            got = tr.mode(float(ks[i])) if lost_at is None else None
            if got is not None and got.physical:
                modes[i] = got
                continue
            if lost_at is None:
                lost_at = tr.lost_at if tr.lost_at is not None else float(ks[i])
            rest.append(i)
        if rest and beyond:
            knobs = tracking or tr.tracking
            for i, got in zip(rest, _beyond_branch(flow, ks[rest], tr.n, policy, cache, knobs)):
                modes[i] = got
        else:
            how[rest] = "lost"
    for i, mm in enumerate(modes):
        if mm is None:
            continue
        out[:, i] = mm.alpha.real, mm.alpha.imag, mm.drift, mm.tail
        nres[i], phys[i], how[i] = mm.n, mm.physical, mm.method
    how[how == ""] = "none"
    return TransverseDispersion(
        ks,
        out[0],
        out[1],
        out[2],
        out[3],
        nres,
        phys,
        flow.theta,
        flow.nu0,
        flow.model.attrs(),
        method=how.astype(str),
        branch_lost_at=lost_at,
    )


def growth_plane(
    flow: SteadyFlow,
    kx,
    kz,
    *,
    policy: RejectionPolicy = DEFAULT_POLICY,
    n: int | None = None,
    method: str = "dense",
):
    """Growth rate Re α of the least-stable physical mode over the (k_x, k_z) plane.

    ``method="dense"``: the dense scan at every wavevector (:func:`least_stable_3d`, ~1 s a
    point); ``"branch"``: the α(0) = 0 branch continued along the ray through each
    wavevector (:func:`chuteflow.stability.tracking.branch_mode`, coarse continuation and
    one solve at N), ~10× faster in the long-wave region; where the branch is lost (at
    k_x = 0 past the transverse band, in the continuum) the point is left NaN.

    Returns
    -------
    xarray.Dataset
        ``alpha_re``, ``alpha_im``, ``drift``, ``tail``, ``physical`` over (kx, kz);
        attributes ``growth_max``, ``kx_max``, ``kz_max`` (where the largest Re α lies) and
        ``direction`` ("longitudinal" if it lies at kz = 0, "transverse" at kx = 0, else
        "oblique").
    """
    import xarray as xr

    if method not in ("dense", "branch"):
        raise ParameterError(f"method = {method!r}: choose 'dense' or 'branch'")
    kxs = np.atleast_1d(np.asarray(kx, dtype=float))
    kzs = np.atleast_1d(np.asarray(kz, dtype=float))
    shape = (len(kxs), len(kzs))
    arr = {name: np.full(shape, np.nan) for name in ("alpha_re", "alpha_im", "drift", "tail")}
    phys = np.zeros(shape, dtype=bool)
    for i, a in enumerate(kxs):
        for j, b in enumerate(kzs):
            if a == 0 and b == 0:
                arr["alpha_re"][i, j] = arr["alpha_im"][i, j] = 0.0  # the mass mode
                phys[i, j] = True
                continue
            try:
                if method == "branch":
                    m = branch_mode(flow, float(a), kz=float(b), n=n, policy=policy)
                else:
                    m = least_stable_3d(flow, float(a), float(b), policy=policy, n=n)
            except ConvergenceError:
                continue
            for name, v in (
                ("alpha_re", m.alpha.real),
                ("alpha_im", m.alpha.imag),
                ("drift", m.drift),
                ("tail", m.tail),
            ):
                arr[name][i, j] = v
            phys[i, j] = m.physical
    g = np.where(np.isfinite(arr["alpha_re"]), arr["alpha_re"], -np.inf)
    im, jm = (int(x) for x in np.unravel_index(int(np.argmax(g)), shape))
    kxm, kzm = float(kxs[im]), float(kzs[jm])
    direction = "longitudinal" if kzm == 0 else "transverse" if kxm == 0 else "oblique"
    u = RATE_UNITS
    return xr.Dataset(
        {
            "alpha_re": (("kx", "kz"), arr["alpha_re"], {"long_name": "growth rate Re alpha", "units": u}),
            "alpha_im": (("kx", "kz"), arr["alpha_im"], {"long_name": "Im alpha", "units": u}),
            "drift": (("kx", "kz"), arr["drift"], {"units": u}),
            "tail": (("kx", "kz"), arr["tail"], {"units": "1"}),
            "physical": (("kx", "kz"), phys),
        },
        coords={
            "kx": ("kx", kxs, {"units": WAVENUMBER_UNITS}),
            "kz": ("kz", kzs, {"units": WAVENUMBER_UNITS}),
        },
        attrs={
            "theta": flow.theta,
            "nu0": flow.nu0,
            "growth_max": float(g[im, jm]),
            "kx_max": kxm,
            "kz_max": kzm,
            "direction": direction,
            "method": method,
            **flow.model.attrs(),
        },
    )


def dense_modes(
    flow: SteadyFlow,
    kx: float,
    kz: float,
    *,
    policy: RejectionPolicy = DEFAULT_POLICY,
    n: int | None = None,
) -> tuple[list[Mode], list[np.ndarray]]:
    """All physical modes at (k_x, k_z) by the dense scan of :func:`least_stable_3d`, best
    first, with their eigenvectors of the equilibrated pencil (start vectors for tracking);
    empty lists when none passes up to ``policy.n_max``."""
    kx, kz = validate_k(kx, "kx"), validate_k(kz, "kz", signed=True)
    for nn in policy.ladder(n):
        n2 = check_n(nn)
        p1 = stability_operator(flow, nn, True).pencil(kx, kz)
        p2 = stability_operator(flow, n2, True).pencil(kx, kz)
        w1, V1 = pencil_qz(p1, True)
        w2, _ = pencil_qz(p2, False)
        tl = tails(p1, V1, policy.tail_terms)
        modes, vecs, pending = [], [], False
        for j in range(len(w1)):
            if tl[j] >= policy.track_tail_tol:
                continue
            drift = float(np.abs(w2 - w1[j]).min()) if len(w2) else math.inf
            if policy.accepts(drift, tl[j]):
                m = make_mode(p1, w1[j], V1[:, j], drift, n2, policy)
                modes.append(dataclasses.replace(m, method="qz"))
                vecs.append(V1[:, j])
            elif tl[j] < policy.tail_tol and not modes:
                pending = True
        if modes and not pending:
            return modes, vecs
    return [], []


def judge_resolved(
    flow: SteadyFlow,
    kx: float,
    kz: float,
    alpha: complex,
    v: np.ndarray,
    n: int,
    *,
    three_d: bool,
    policy: RejectionPolicy = DEFAULT_POLICY,
    cache: OperatorCache | None = None,
    rungs: int | None = None,
) -> Mode | None:
    """The resolution check of one eigenpair: (α, v), found at N on the pencil at (k_x, k_z),
    with its drift |α(N) − α(N')| (N' = round(0.8 N), shift-invert from the interpolated
    vector) and its tail, judged by ``policy`` (paper §4.1); while it fails, N is raised
    along ``policy.ladder(n)`` (the first ``rungs`` rungs, all by default) and the eigenpair
    re-solved there from the interpolated vector.

    Returns the mode at the last N tried (drift ``inf`` where no eigenvalue at N' settles;
    None only when the ladder is empty). Used by the metric's longitudinal maximum
    (:func:`chuteflow.longwave.spanwise.longitudinal_peak`); past the tracked branch
    (:func:`transverse_dispersion`) the same check runs on the real form of the k_x = 0
    pencil, each rung's α(N') reused from the rung below.
    """
    nf = 5 if three_d else 4
    mode = None
    ladder = policy.ladder(n)
    for nn in ladder if rungs is None else ladder[:rungs]:
        p = stability_operator(flow, nn, three_d, cache=cache).pencil(kx, kz)
        if nn != n:
            try:
                alpha, v = nearest_eigenpair(p, alpha, v0=interp_vector(v, nf, n, nn))
            except ConvergenceError:
                break
            n = nn
        n2 = check_n(nn)
        try:
            drift, _ = drift_of(flow, alpha, v, nn, kx, kz, three_d, cache=cache)
        except ConvergenceError:
            drift = math.inf
        mode = make_mode(p, alpha, v, drift, n2, policy)
        if mode.physical:
            break
    return mode

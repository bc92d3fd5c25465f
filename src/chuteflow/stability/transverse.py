"""The least-stable physical mode at any wavevector (k_x, k_z), by a dense scan.

Across the slope (k_x = 0) the pencil is real after the diagonal similarity ŵ → i ŵ (every
term odd in ∂_z couples ŵ to the other fields), so its eigenvalues are real or come in
conjugate pairs and the real QZ (half the cost of the complex one) applies. At each
wavevector the finite eigenvalues at N are all scanned by decreasing Re α; an eigenvalue is
accepted, as in 2D (paper §4.1, :class:`RejectionPolicy`), when its eigenvector's
Chebyshev tail and its drift |α(N) − α(N')| (N' = round(0.8 N), nearest eigenvalue of the
QZ at N') are below the policy's thresholds. The near-neutral continuum of the dilute top
(α ≈ −1e-8 at k_x = 0) fails the tail test. N is raised along the policy's ladder when no
eigenvalue passes, or when a resolved eigenvector (tail below the threshold) with a larger
Re α than the accepted one fails only the drift test (P1, k_z = 0.005: α = −0.2719 + 0.5123i
drifts by 1e-7 between N = 64 and 80 and is converged from N = 100 on).

The dense scan costs two QZ per k_z (about 1 s at N = 80–100). The fast path,
:class:`TransverseTracker`, follows the α(0) = 0 branch in k_z instead: it starts from the
k = 0 null vector ∂X0/∂β, predicts α ≈ α2z k_z² (the perturbation theory of
:mod:`chuteflow.longwave.transverse`) for the first steps and by quadratic extrapolation of
the last three points after that, and solves each step by real inverse iteration (one real
LU of A' − σB' per k_z, the pencil made real by ŵ → iŵ). At P1 the branch rises to α ~ 6e-5
at k_z ~ 2e-3, falls back through the near-neutral continuum of the dilute top at
k_z ≈ 3.25e-3 and is lost in it (its eigenvector is no longer resolved); the least-stable
physical mode at larger k_z is another one. :func:`transverse_dispersion` with
``method="track"`` follows the branch while it is resolved and, beyond, a few candidate
modes taken from one dense scan (each by shift-invert, re-seeded by a dense scan whenever a
candidate is lost); ``method="dense"`` is the reference scan at every k_z. Past the branch
the shift-invert solves also run on the real form (a real LU when the shift is real, a fifth
of the complex one's cost), the seeding scan is the dense eigenproblem of (A' − σB')⁻¹B'
(a third of the QZ's), and the check α(N') of a rung of the resolution ladder is the α just
solved on the rung below: the same eigenpairs as the complex solves, to round-off (at P1 the
50-k_z dispersion past the branch took 3.3 s of CPU before, 1.7–2.0 s after; issue 10).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla

from ..conventions import RATE_UNITS, WAVENUMBER_UNITS
from ..errors import ConvergenceError, ParameterError
from ..steady import SteadyFlow
from .eigen import ShiftInvert, factor_shifted
from .modes import (
    Mode,
    OperatorCache,
    check_n,
    drift_of,
    interp_vector,
    make_mode,
    nearest_eigenpair,
    stability_operator,
    tail,
    tails,
)
from .operator import Pencil, validate_k
from .policy import DEFAULT_POLICY, RejectionPolicy
from .tracking import branch_mode

__all__ = [
    "TransverseDispersion",
    "TransverseTracker",
    "dense_modes",
    "growth_plane",
    "judge_resolved",
    "least_stable_3d",
    "real_form",
    "transverse_dispersion",
    "transverse_mode",
]


def real_form(pencil: Pencil) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(A', B', s): the equilibrated pencil at k_x = 0 made real by A' = S⁻¹ A S, S = diag(s)
    with s = i on the ŵ block and 1 elsewhere (B' = B). An eigenvector W' of (A', B') is
    W = S W' of the equilibrated pencil."""
    if pencil.kx != 0 or "w" not in pencil.fields:
        raise ParameterError("real_form: needs the three-dimensional pencil at kx = 0")
    A, B = pencil.equilibrated()
    s = np.ones(A.shape[0], dtype=complex)
    s[pencil.slices()["w"]] = 1j
    Ar = (A * s[None, :]) / s[:, None]
    scale = np.abs(Ar).max()
    if np.abs(Ar.imag).max() > 1e-12 * scale:  # pragma: no cover - structural identity
        raise AssertionError("the kx = 0 pencil is not real after ŵ → iŵ")
    return np.ascontiguousarray(Ar.real), np.asarray(B, dtype=float), s


def _finite_spectrum(pencil: Pencil, vectors: bool):
    """Finite eigenvalues (decreasing Re) and, if asked, eigenvectors of the equilibrated
    pencil (real QZ at k_x = 0)."""
    if pencil.kx == 0 and "w" in pencil.fields:
        A, B, s = real_form(pencil)
    else:
        (A, B), s = pencil.equilibrated(), None
    if vectors:
        w, V = sla.eig(A, B, check_finite=False)
    else:
        w, V = sla.eig(A, B, right=False, check_finite=False), None
    fin = np.isfinite(w)
    w = w[fin]
    order = np.argsort(-w.real, kind="stable")
    w = w[order]
    if V is not None:
        V = V[:, fin][:, order]
        if s is not None:
            V = V * s[:, None]
    return w, V


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
        w1, V1 = _finite_spectrum(p1, True)
        w2, _ = _finite_spectrum(p2, False)
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
        ``"track"`` (fast): the α(0) = 0 branch by :class:`TransverseTracker` while it is
        resolved; the k_z past the point where it enters the continuum are left NaN
        (``method = "lost"``) unless ``beyond``. ``"dense"``: the dense scan
        (:func:`least_stable_3d`) at every k_z, the reference.
    alpha2z : float, optional
        Predictor of the tracked branch's first steps (``"track"``).
    beyond : bool
        ``"track"`` only: past the branch, follow candidate modes seeded by a coarse dense
        scan (N = 48) by shift-invert at N ≤ 125. Approximate: the least-stable mode there
        lies among modes that the drift and tail tests accept only at different N, and the
        candidates and the dense scan can each miss one the other finds (P1, k_z = 0.038:
        dense −0.052 at N = 156, candidates −0.347 at N = 100).
    cache : OperatorCache, optional
        Where the operators come from (``"track"``).
    tracker : TransverseTracker, optional
        A tracker to continue (``"track"``; its history is kept for later refinement).

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
        tr = tracker or TransverseTracker(flow, alpha2z=alpha2z, n=n, policy=policy, cache=cache)
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
            for i, got in zip(rest, _beyond_branch(flow, ks[rest], tr.n, policy, cache)):
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


# -- the fast path: the α(0) = 0 branch tracked in k_z -----------------------------------
@dataclass(frozen=True, eq=False)
class _Point:
    """One tracked point: k_z, α, the real-form eigenvector at N and N."""

    kz: float
    alpha: complex
    vec: np.ndarray = field(repr=False)
    n: int


def _shifted(A: np.ndarray, bdiag: np.ndarray, sigma, dtype=float) -> np.ndarray:
    """A − σ diag(bdiag), a new array in Fortran order: LAPACK's, so that ``lu_factor``
    factors it in place instead of copying a C-ordered array first (bitwise the same
    factors, one copy of the matrix fewer)."""
    M = np.empty(A.shape, dtype=dtype, order="F")
    M[...] = A
    i = np.arange(A.shape[0])
    M[i, i] -= sigma * bdiag
    return M


def _real_lu(A: np.ndarray, bdiag: np.ndarray, sigma: float):
    return sla.lu_factor(_shifted(A, bdiag, sigma), overwrite_a=True, check_finite=False)


def _inverse_iteration(lu, bdiag, sigma, v0, *, maxiter=14, tol=1e-9, floor=1e-15):
    """Real inverse iteration x ↦ (A' − σB')⁻¹ B' x from v0: (α, v) or None if unsettled.

    Settled: |Δα| ≤ tol |α − σ| + 1e-13 |α| + ``floor``; the absolute floor is the
    round-off of the solves (~1e-17 at P1 near α ~ 1e-8, where A' − σB' is nearly singular),
    far below the drift threshold 1e-7."""
    v = np.asarray(v0, dtype=float)
    nv = np.linalg.norm(v)
    if nv == 0 or not np.isfinite(nv):
        return None
    v = v / nv
    prev = None
    (getrs,) = sla.get_lapack_funcs(("getrs",), (lu[0],))  # lu_solve's routine, unchecked
    for _ in range(maxiter):
        w, _info = getrs(lu[0], lu[1], bdiag * v)
        vw = float(v @ w)
        nw = float(np.linalg.norm(w))
        if vw == 0 or not np.isfinite(nw) or nw == 0:
            return None
        alpha = sigma + 1.0 / vw
        v = w / nw
        if prev is not None and abs(alpha - prev) <= tol * abs(alpha - sigma) + 1e-13 * abs(alpha) + floor:
            return alpha, v
        prev = alpha
    return None


_REAL_PIECES: dict = {}
#: The last (op, k_z, result) of :func:`_real_pencil` per operator (its A' is never written).
_REAL_LAST: dict = {}


def _real_pieces(op):
    """(R0, R1, R2, diag B', s) of the real form A'(k_z) = S⁻¹ A(0, k_z) S = R0 + k_z R1 +
    k_z² R2 (:func:`real_form`) at k_z ≥ 0, straight from the operator's equilibrated real
    pieces: A(0, k_z) = Σ_d (ik_z)^d A_{0,d} + k_z K, each term times i^d s_c / s_r, which is
    real wherever the piece is not zero (checked)."""
    m, M = op.grid.n + 1, op.size
    jw = op.fields.index("w")
    s = np.ones(M, dtype=complex)
    s[jw * m : (jw + 1) * m] = 1j
    inw = np.zeros(M)
    inw[jw * m : (jw + 1) * m] = 1.0
    # i^d s_c / s_r: d even → (−1)^(d/2) within the ŵ block and outside it (imaginary across);
    # d odd → +1 from the ŵ rows to the other columns, −1 from the other rows to ŵ
    # (imaginary within): the real factor of each order and where it vanishes
    cross = np.abs(inw[:, None] - inw[None, :])  # 1 across the ŵ block's edge
    odd = inw[:, None] - inw[None, :]
    R = [np.zeros((M, M)) for _ in range(3)]
    scale, worst = 0.0, 0.0
    for (b, d), P in op._pieces_eq.items():  # the same package's operator
        if b:
            continue
        if d > 2:  # pragma: no cover - the equations are of second order in ∂_z
            raise AssertionError(f"a piece of order {d} in k_z")
        if d == 1:
            R[1] += odd * P
            imag = (1.0 - cross) * P
        else:
            R[d] += (1.0 - cross) * P if d == 0 else (cross - 1.0) * P
            imag = cross * P
        scale, worst = max(scale, float(np.abs(P).max())), max(worst, float(np.abs(imag).max()))
    rows, cols, vals = op._K_eq  # the |k| coefficient (top conditions)
    c = cross[rows, cols]
    np.add.at(R[1], (rows, cols), (1.0 - c) * vals)
    worst = max(worst, float(np.abs(c * vals).max(initial=0.0)))
    if worst > 1e-12 * scale:  # pragma: no cover - structural identity
        raise AssertionError("the kx = 0 pencil is not real after ŵ → iŵ")
    return R[0], R[1], R[2], np.diag(op.B_eq).copy(), s


def _real_pencil(op, kz: float):
    """(pencil, A', diag B', s) at (0, k_z ≥ 0) from the real form's three pieces
    A'(k_z) = R0 + k_z R1 + k_z² R2 (:func:`_real_pieces`, once per operator), a few
    additions per k_z instead of a complex assembly; the last k_z of each operator is kept.
    Callers must not write into A'."""
    key = id(op)
    hit = _REAL_PIECES.get(key)
    if hit is None or hit[0] is not op:
        hit = (op, *_real_pieces(op))
        if len(_REAL_PIECES) > 8:
            _REAL_PIECES.clear()
        _REAL_PIECES[key] = hit
    _, R0, R1, R2, bd, s = hit
    kz = abs(float(kz))
    last = _REAL_LAST.get(key)
    if last is not None and last[0] is op and last[1] == kz:
        return last[2]  # the same k_z again (candidates, drifts, judging): not rebuilt
    A = R1 * kz
    A += R0
    if kz:
        A += (kz * kz) * R2
    out = (op.pencil(0.0, kz), A, bd, s)
    if len(_REAL_LAST) > 8:
        _REAL_LAST.clear()
    _REAL_LAST[key] = (op, kz, out)
    return out


def _null_vector(op) -> np.ndarray:
    """The right eigenvector of the equilibrated k = 0 pencil for its eigenvalue nearest 0:
    the shift-invert Arnoldi at σ = 0 of :func:`~chuteflow.stability.tracking.null_vectors`
    on the real form (a real LU; the left vector is not needed here)."""
    _, Ar, bd, s = _real_pencil(op, 0.0)
    _, W = _RealFormShiftInvert.nudged(Ar, bd, 0.0).nearest(1)
    return s * W[:, 0]


class TransverseTracker:
    """Continuation of the α(0) = 0 branch across the slope (k_x = 0) in k_z ≥ 0.

    The fast path of the transverse analysis (module docstring): real arithmetic (the k_x = 0
    pencil made real by ŵ → iŵ, :func:`real_form`), one real LU and a few solves per step.

    Parameters
    ----------
    flow : SteadyFlow
        Base state.
    alpha2z : float, optional
        α2z of α(0, k_z) ≈ α2z k_z² (:func:`chuteflow.longwave.transverse_longwave`), the
        predictor of the first steps; without it the first step takes the resolved eigenvalue
        nearest 0.
    n : int, optional
        Resolution N (default ``policy.n_start``).
    policy : RejectionPolicy
        Drift and tail thresholds (the branch is lost when its eigenvector's tail exceeds
        ``policy.track_tail_tol``) and the resolution ladder.
    cache : OperatorCache, optional
        Where the operators come from.
    max_ratio : float
        Largest step ratio k_z(next)/k_z(last) of the continuation.
    """

    def __init__(
        self,
        flow: SteadyFlow,
        *,
        alpha2z: float | None = None,
        n: int | None = None,
        policy: RejectionPolicy = DEFAULT_POLICY,
        cache: OperatorCache | None = None,
        max_ratio: float = 1.6,
    ):
        self.flow, self.policy, self.cache = flow, policy, cache
        self.alpha2z = None if alpha2z is None else float(alpha2z)
        self.n = int(policy.n_start if n is None else n)
        self.max_ratio = float(max_ratio)
        w = _null_vector(self._op(self.n))  # eigenvector of the equilibrated pencil at k = 0
        w = w / w[np.argmax(np.abs(w))]
        self.history: list[_Point] = [_Point(0.0, 0.0, np.ascontiguousarray(w.real), self.n)]
        self.lost_at: float | None = None

    def _op(self, n):
        return stability_operator(self.flow, n, True, cache=self.cache)

    def _real(self, n, kz):
        return _real_pencil(self._op(n), kz)

    def _predict(self, kz: float) -> float:
        h = self.history
        if len(h) == 1:
            return self.alpha2z * kz**2 if self.alpha2z is not None else 0.0
        if len(h) == 2 and self.alpha2z is None:
            # α ∝ k_z² through the first point (no O(k_z) term across the slope)
            return h[1].alpha.real * (kz / h[1].kz) ** 2
        if len(h) == 2 and self.alpha2z is not None:
            # α2z k² + c3 k³ through the first point (the next term is O(|k_z|³))
            k1, a1 = h[1].kz, h[1].alpha.real
            c3 = (a1 - self.alpha2z * k1**2) / k1**3
            return self.alpha2z * kz**2 + c3 * kz**3
        pts = h[-3:] if len(h) >= 3 else h
        xs = [p.kz for p in pts]
        ys = [p.alpha.real for p in pts]
        out = 0.0
        for i, (xi, yi) in enumerate(zip(xs, ys)):
            li = 1.0
            for j, xj in enumerate(xs):
                if j != i:
                    li *= (kz - xj) / (xi - xj)
            out += yi * li
        return out

    def _solve(self, kz, sigma, v0, n=None):
        """Eigenpair nearest σ at (0, k_z) by real inverse iteration from v0, with its tail:
        (α, real-form vector, pencil, s, tail) or None."""
        n = self.n if n is None else n
        p, A, bd, s = self._real(n, kz)
        try:
            lu = _real_lu(A, bd, sigma)
        except (ValueError, np.linalg.LinAlgError):  # pragma: no cover - exact hit
            sigma = sigma * (1 + 1e-10) + 1e-14
            lu = _real_lu(A, bd, sigma)
        found = _inverse_iteration(lu, bd, sigma, v0)
        if found is None:
            return None
        alpha, v = found
        t = tail(p.unscale(s * v), len(p.fields), self.policy.tail_terms)
        return alpha, v, p, s, t

    def _step(self, kz) -> bool:
        last = self.history[-1]
        pred = self._predict(kz)
        res = self._solve(kz, pred, last.vec)
        if res is None:
            return False
        alpha, v, _, _, t = res
        miss = abs(alpha - pred)
        if len(self.history) > 1 or self.alpha2z is not None:
            if miss > 0.25 * abs(pred - last.alpha.real) + 1e-3 * abs(pred) + 1e-14:
                return False
        if t > self.policy.track_tail_tol:
            return False
        self.history.append(_Point(float(kz), complex(alpha), v, self.n))
        return True

    def advance(self, kz: float, max_halvings: int = 10) -> _Point | None:
        """Continue the branch to k_z (≥ the last point); None once it is lost (the reason:
        :attr:`lost_at`, the k_z where the continuation could not step on).

        A rejected step is halved in ln k_z, at most ``max_halvings`` times. The branch is
        real and its step's acceptance (a miss below a quarter of the predicted change plus
        1e-3 |α|) tightens where Re α is flat, at its maximum: the miss falls with the step
        and the threshold to 1e-3 |α|, so short steps pass. With 6 halvings, flows a
        round-off apart were followed over P1's maximum (k_z ≈ 1.9e-3) or "lost" there; 10
        cross it whatever the round-off
        (tests/stability/test_transverse.py::test_p1_branch_followed_past_its_maximum_whatever_the_round_off)."""
        if self.lost_at is not None and kz >= self.lost_at:
            return None
        while self.history[-1].kz < kz:
            k0 = self.history[-1].kz
            target = kz if k0 == 0 else min(kz, k0 * self.max_ratio)
            if k0 == 0:
                target = min(kz, 1e-5)
            ok = False
            for _ in range(max_halvings):
                if self._step(target):
                    ok = True
                    break
                target = math.sqrt(k0 * target) if k0 > 0 else 0.5 * target
            if not ok:
                self.lost_at = float(target)
                return None
        return self.history[-1] if self.history[-1].kz == kz else self._near(kz)

    def _near(self, kz):
        for p in reversed(self.history):
            if p.kz == kz:
                return p
        return None  # pragma: no cover

    def at(self, kz: float) -> complex | None:
        """α of the branch at k_z inside the tracked range, solved from the nearest tracked
        point (the history is not changed): for bracketed searches. None if it does not land
        on a resolved eigenvector near the interpolated prediction."""
        pt = self.point_at(kz)
        return None if pt is None else pt.alpha

    def point_at(self, kz: float) -> _Point | None:
        """The branch's point at k_z inside the tracked range (as :meth:`at`, with its
        eigenvector, for :meth:`judge`); the history is not changed."""
        h = [p for p in self.history if p.kz > 0]
        if not h or kz > h[-1].kz * self.max_ratio:
            return None
        i = int(np.argmin([abs(math.log(p.kz / kz)) for p in h]))
        j = max(0, min(len(h) - 3, i - 1))
        pts = h[j : j + 3]
        xs, ys = [p.kz for p in pts], [p.alpha.real for p in pts]
        pred = float(np.polyval(np.polyfit(xs, ys, len(xs) - 1), kz)) if len(xs) > 1 else ys[0]
        res = self._solve(kz, pred, h[i].vec, n=h[i].n)
        if res is None or res[4] > self.policy.track_tail_tol:
            return None
        return _Point(float(kz), complex(res[0]), res[1], h[i].n)

    def mode(self, kz: float) -> Mode | None:
        """The tracked mode at k_z with its drift (N' = 0.8 N) and tail, N raised along the
        policy's ladder while it is not physical; None where the branch is lost."""
        pt = self.advance(kz)
        if pt is None:
            return None
        return self.judge(pt)

    def judge(self, pt: _Point) -> Mode:
        """The mode of a tracked point (from :meth:`advance` or :meth:`point_at`) with its
        drift |α(N) − α(N')| (N' = 0.8 N) and tail, N raised along the policy's ladder while
        it is not physical."""
        nf = 5
        alpha, v, n = pt.alpha.real, pt.vec, pt.n
        mode = None
        for nn in self.policy.ladder(n):
            if nn != n:
                res = self._solve(pt.kz, alpha, interp_vector(v, nf, n, nn), n=nn)
                if res is None:
                    break
                alpha, v, n = res[0], res[1], nn
            p, _, _, s = self._real(n, pt.kz)
            n2 = check_n(n)
            res2 = self._solve(pt.kz, alpha, interp_vector(v, nf, n, n2), n=n2)
            drift = abs(res2[0] - alpha) if res2 is not None else math.inf
            mode = dataclasses.replace(make_mode(p, alpha, s * v, drift, n2, self.policy), method="branch")
            if mode.physical:
                break
        return mode  # type: ignore[return-value]


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
        w1, V1 = _finite_spectrum(p1, True)
        w2, _ = _finite_spectrum(p2, False)
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


#: Resolution of the coarse dense scan that seeds the candidate modes past the branch.
SEED_N = 48
#: How many candidate modes are followed past the branch.
N_CANDIDATES = 2
#: A seed (N = :data:`SEED_N`) within this relative distance of an eigenvalue already
#: followed at N is taken to be that eigenvalue and is not solved again (P1, k_z = 0.01–3:
#: resolved seeds differ from their N = 80 eigenvalues by 6e-8 to 1.1e-3 relative; two
#: distinct eigenvalues that close would rank the same to that accuracy).
SEED_MATCH = 2e-3


#: Shift of the dense shift-invert that seeds the candidates past the branch
#: (:func:`_seed_spectrum`): to the right of the decaying spectrum there.
SEED_SHIFT = 0.5


def _seed_spectrum(op, kz):
    """Finite eigenvalues (decreasing Re) and eigenvectors of the equilibrated pencil at
    (0, k_z) on ``op``, as :func:`_finite_spectrum` returns them, by the dense eigenproblem
    of C = (A' − σB')⁻¹B' (real form, σ = :data:`SEED_SHIFT`, one real LU and a real
    ``geev``; α = σ + 1/θ for the eigenvalues θ ≠ 0 of C, the infinite ones mapping to θ = 0):
    about a third of the real QZ's time at N = 48. The same eigenpairs: at P1, k_z = 0.004–3,
    the seeds (eigenvalues and tails) agree with the QZ ones to 1e-12 and 1e-9 relative.
    Falls back on QZ when σ lies on an eigenvalue (a zero pivot or θ not finite)."""
    p, Ar, bd, s = _real_pencil(op, kz)
    m = Ar.shape[0]
    lu, piv = sla.lu_factor(_shifted(Ar, bd, SEED_SHIFT), overwrite_a=True, check_finite=False)
    d = np.abs(np.diag(lu))
    if not np.all(np.isfinite(d)) or d.min() == 0.0:
        return _finite_spectrum(p, True)
    # C is zero on the columns of the boundary rows (B' = 0 there): its eigenvalues θ ≠ 0
    # are those of the block on the other rows and columns, y = (y_i, C_bi y_i / θ)
    inner = bd != 0
    C = sla.lu_solve((lu, piv), np.eye(m)[:, inner], check_finite=False) * bd[inner][None, :]
    theta, Yi = np.linalg.eig(C[inner])
    if not np.all(np.isfinite(theta)):  # pragma: no cover - σ on an eigenvalue
        return _finite_spectrum(p, True)
    keep = np.abs(theta) > 1e-10 * np.abs(theta).max()
    theta, Yi = theta[keep], Yi[:, keep]
    Y = np.empty((m, len(theta)), dtype=complex)
    Y[inner] = Yi
    Y[~inner] = (C[~inner] @ Yi) / theta[None, :]
    w = SEED_SHIFT + 1.0 / theta
    order = np.argsort(-w.real, kind="stable")
    return w[order], Y[:, order] * s[:, None]


def _seed_candidates(flow, kz, policy, cache):
    """Candidate eigenpairs at (0, k_z) from one coarse dense eigensolve (N = :data:`SEED_N`,
    real form, :func:`_seed_spectrum`), best first, one of each conjugate pair: those whose
    eigenvectors are nearly resolved there (tail < 1e-4; the continuum of the dilute top is
    dropped by |α| > 1e-5 and by the tail test at N). Returns [(α, eigenvector of the
    equilibrated pencil at N = :data:`SEED_N`)]: the vector starts the shift-invert at N
    (without it the inverse iteration starts from a random vector and often falls back on
    Arnoldi)."""
    op = stability_operator(flow, SEED_N, True, cache=cache)
    w, V = _seed_spectrum(op, kz)
    t = tails(op.pencil(0.0, kz), V, policy.tail_terms)
    keep = np.nonzero((t < 1e-4) & (w.imag >= 0) & (np.abs(w) > 1e-5))[0][: 2 * N_CANDIDATES]
    return [(complex(w[i]), V[:, i]) for i in keep]


#: ‖A'‖∞ of the last few real-form matrices (by identity), for the residuals of the polish.
_NORMS: dict = {}


class _RealFormShiftInvert(ShiftInvert):
    """:class:`~chuteflow.stability.eigen.ShiftInvert` on the real form (A', diag B') of the
    k_x = 0 pencil (:func:`real_form`). For a real shift the LU of A' − σB' is real (about a
    fifth of the complex one's time at N = 80–125) and a complex vector is solved as two
    real right-hand sides; for a complex shift it is the complex LU of the real A'. Vectors
    live in the real form's coordinates W' = S⁻¹W; |s| = 1, so norms, inner products and
    residuals are those of the equilibrated pencil and every iteration (inverse iteration,
    Arnoldi, polish) is the one :class:`ShiftInvert` runs on (A, B)."""

    def __init__(self, Ar: np.ndarray, bdiag: np.ndarray, sigma: complex):
        self.A, self.sigma, self._bdiag, self._bd = Ar, complex(sigma), bdiag, bdiag
        self.size = Ar.shape[0]
        self._real = self.sigma.imag == 0
        if self._real:
            M = _shifted(Ar, bdiag, self.sigma.real)
        else:
            M = _shifted(Ar, bdiag, self.sigma, complex)
        self.lu = factor_shifted(M, self.sigma)
        (self._getrs,) = sla.get_lapack_funcs(("getrs",), (self.lu[0],))

    @property
    def B(self) -> np.ndarray:  # type: ignore[override]
        """The diagonal B' as a matrix."""
        return np.diag(self._bd)

    def norms(self) -> tuple[float, float]:
        """(‖A'‖∞, ‖B'‖∞) = those of the equilibrated pencil (|s| = 1), ‖A'‖∞ kept per A'."""
        if not hasattr(self, "_norms"):
            key = id(self.A)
            hit = _NORMS.get(key)
            if hit is None or hit[0] is not self.A:
                hit = (self.A, float(np.abs(self.A).sum(axis=1).max()))
                if len(_NORMS) > 8:
                    _NORMS.clear()
                _NORMS[key] = hit
            self._norms = (hit[1], float(np.abs(self._bd).max()))
        return self._norms

    def solve(self, x):
        """(A' − σB')⁻¹ x."""
        x = np.asarray(x, dtype=complex)
        if not self._real:
            return super().solve(x)
        rhs = np.empty((self.size, 2 * (x.size // self.size)), order="F")
        xr = x.reshape(self.size, -1)
        rhs[:, 0::2], rhs[:, 1::2] = xr.real, xr.imag
        y, info = self._getrs(self.lu[0], self.lu[1], rhs)
        if info != 0:  # pragma: no cover - only for malformed arguments
            raise ValueError(f"getrs: illegal value in argument {-info}")
        return (y[:, 0::2] + 1j * y[:, 1::2]).reshape(x.shape)


#: A shift whose imaginary part is below this fraction of its modulus is taken as real by
#: :func:`_nearest_kx0` (the real LU). Real eigenvalues solved in complex arithmetic carry
#: imaginary parts of round-off, up to 1.4e-9 relative at P1 next to the continuum; the
#: complex pairs past the branch have |Im α| > 0.1 |α|.
REAL_SHIFT_RTOL = 1e-8


def _nearest_kx0(op, kz: float, sigma: complex, v0=None):
    """:func:`~chuteflow.stability.nearest_eigenpair` on ``op.pencil(0, k_z)`` computed on
    its real form (:class:`_RealFormShiftInvert`, the matrix from :func:`_real_pencil`'s
    pieces instead of a complex assembly): the same inverse iteration from ``v0`` (a random
    start without it), the same nudge of a shift on an eigenvalue and the same Arnoldi
    fallback, so the same eigenpair up to round-off. A shift within
    :data:`REAL_SHIFT_RTOL` relative of the real axis is taken as real. Returns
    (α, w, pencil), w an eigenvector of the equilibrated pencil."""
    p, Ar, bd, s = _real_pencil(op, kz)
    sigma = complex(sigma)
    if abs(sigma.imag) <= REAL_SHIFT_RTOL * abs(sigma):
        sigma = complex(sigma.real)
    si = _RealFormShiftInvert.nudged(Ar, bd, sigma)
    sigma = si.sigma
    if v0 is not None:
        start = np.asarray(v0, dtype=complex) / s
        found = si.iterate(start)
    else:
        rng = np.random.default_rng(2024)
        start = si.apply((rng.standard_normal(si.size) + 1j * rng.standard_normal(si.size)) / s)
        found = si.iterate(start, maxiter=16)
    if found is None:
        alpha, V = si.nearest(1, v0=si.apply(start))
        if len(alpha) == 0:
            raise ConvergenceError(f"no eigenvalue converged near {complex(sigma):.6g} at N = {p.n}")
        found = alpha[0], V[:, 0]
    return found[0], s * found[1], p


#: Past the branch the candidates are re-seeded by a coarse dense scan every time k_z has
#: grown by this factor (modes resolved only at larger k_z join the race).
RESEED_RATIO = 2.0


def _beyond_branch(flow, ks, n, policy, cache):
    """Least-stable physical mode at each k_z of ``ks`` (increasing, past the tracked
    branch): candidates seeded by a coarse dense scan (again whenever k_z has grown by
    :data:`RESEED_RATIO` or every candidate is lost), followed by shift-invert from their
    last eigenvectors at the N where the last winner passed (``n`` again at each seeding),
    N raised along the ladder while not physical. Seeds that cannot reach the best
    :data:`N_CANDIDATES` found, and candidates just lost on the same pencil, are not solved
    (again)."""
    nf = 5
    out: list[Mode | None] = []
    # candidates: (α, start vector, the N of that vector)
    cands: list[tuple[complex, np.ndarray, int]] = []
    k_seed = None
    n_cur = n
    for k in ks:
        k = float(k)
        found: list = []
        for attempt in range(2):
            if not cands or attempt == 1 or (k_seed is not None and k >= RESEED_RATIO * k_seed):
                if attempt == 1 and n_cur == n:
                    if k_seed == k:
                        break  # seeded here already: the same seeds would be lost again
                    # every candidate was just lost on this very pencil: solving them again
                    # from the same shifts and vectors would give the same answers
                    cands = []
                n_cur = n  # new candidates: from the first rung again
                seeds = [(a, v, SEED_N) for a, v in _seed_candidates(flow, k, policy, cache)]
                cands = cands + seeds  # the followed ones first: their vectors are at N
                k_seed = k
            op = stability_operator(flow, n_cur, True, cache=cache)
            pencil = op.pencil(0.0, k)
            found = []
            for a, v, nv in cands:
                if nv == SEED_N and any(
                    abs(a.real - f.real) + abs(abs(a.imag) - abs(f.imag)) <= SEED_MATCH * max(abs(a), 1e-3)
                    for f, *_ in found
                ):
                    continue  # a seed of an eigenvalue already followed
                if nv == SEED_N and len(found) >= N_CANDIDATES:
                    # an accepted solve lies within 0.2 max(|a|, 1e-3) of the seed: one that
                    # cannot reach the best N_CANDIDATES found so far is not solved
                    kth = sorted((f.real for f, *_ in found), reverse=True)[N_CANDIDATES - 1]
                    if a.real + 0.2 * max(abs(a), 1e-3) < kth:
                        continue
                try:
                    alpha, w, _ = _nearest_kx0(op, k, a, v0=interp_vector(v, nf, nv, n_cur))
                except ConvergenceError:
                    continue
                if abs(alpha - a) > 0.2 * max(abs(a), 1e-3):
                    continue  # jumped to another eigenvalue
                alpha = complex(alpha)
                tol = 1e-8 * max(1.0, abs(alpha))
                near = [abs(alpha.real - f.real) + abs(abs(alpha.imag) - abs(f.imag)) for f, *_ in found]
                if near and min(near) <= tol:
                    continue  # the same eigenvalue or its conjugate
                t = tail(pencil.unscale(w), len(pencil.fields), policy.tail_terms)
                if t < policy.track_tail_tol:
                    found.append((alpha, w, t))
            found = sorted(found, key=lambda f: -f[0].real)[:N_CANDIDATES]
            if found:
                break
        cands = [(a, w, n_cur) for a, w, _ in found]
        mode = None
        for a, w, *_ in found:
            mode = _judge_complex(flow, k, a, w, n_cur, policy, cache)
            if mode.physical:
                break
        if mode is not None and mode.physical:
            n_cur = mode.n  # the next k_z starts where this one passed (until the next seeding)
        out.append(mode)
    return out


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
    (:func:`chuteflow.longwave.transverse.longitudinal_peak`); past the tracked branch
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


def _judge_complex(flow, kz, alpha, w, n, policy, cache) -> Mode:
    """Drift and tail of a shift-invert eigenpair at (0, k_z), N raised while not physical
    (at most three rungs), ``method = "shift"``: :func:`judge_resolved` on the real form
    (:func:`_nearest_kx0`). A rung's check resolution N' = round(0.8 N) is the rung before
    (80 → 100 → 125 → 156 …), where this eigenvalue was just solved: that α(N') is reused
    instead of solving again from the interpolated vector (the same eigenvalue at the same
    N, to the inverse iteration's tolerance 1e-7 |α − σ|)."""
    nf = 5
    mode = None
    before = None  # (N, α) of the rung before
    for nn in policy.ladder(n)[:3]:
        op = stability_operator(flow, nn, True, cache=cache)
        if nn != n:
            try:
                a_new, w, _ = _nearest_kx0(op, kz, alpha, v0=interp_vector(w, nf, n, nn))
            except ConvergenceError:
                break
            before = (n, alpha)
            alpha, n = a_new, nn
        n2 = check_n(nn)
        if before is not None and before[0] == n2:
            drift = abs(alpha - before[1])
        else:
            try:
                op2 = stability_operator(flow, n2, True, cache=cache)
                a2, _, _ = _nearest_kx0(op2, kz, alpha, v0=interp_vector(w, nf, nn, n2))
                drift = abs(a2 - alpha)
            except ConvergenceError:
                drift = math.inf
        mode = make_mode(op.pencil(0.0, kz), alpha, w, drift, n2, policy)
        if mode.physical:
            break
    assert mode is not None  # the ladder from n has at least one rung
    return dataclasses.replace(mode, method="shift")

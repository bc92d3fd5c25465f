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

The tracked branch of :class:`~chuteflow.stability.BranchTracker` is no use here: at
k_x = 0 the α(0) = 0 branch rises to α ~ 6e-5 at k_z ~ 2e-3 (P1), falls back through the
continuum at k_z ≈ 3.25e-3 and leaves it unresolved; the least-stable physical mode at
larger k_z is another one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from ..conventions import RATE_UNITS, WAVENUMBER_UNITS
from ..errors import ConvergenceError, ParameterError
from ..spectral import coefficients
from ..steady import SteadyFlow
from .modes import Mode, make_mode, stability_operator
from .operator import Pencil, validate_k
from .policy import DEFAULT_POLICY, RejectionPolicy

__all__ = [
    "TransverseDispersion",
    "growth_plane",
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


def _tails(pencil: Pencil, W: np.ndarray, m: int) -> np.ndarray:
    """The paper's tail statistic (:func:`chuteflow.stability.tail`) of every column of W
    (eigenvectors of the equilibrated pencil), vectorised."""
    nf, n1 = len(pencil.fields), pencil.n + 1
    V = pencil.unscale(W)
    big = V[np.argmax(np.abs(V), axis=0), np.arange(V.shape[1])]
    V = V / np.where(big == 0, 1.0, big)[None, :]
    c = np.abs(coefficients(V.T.reshape(-1, nf, n1)))
    return c[:, :, -m:].max(axis=(1, 2))


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
        tails = _tails(p1, V1, policy.tail_terms)
        pending = False  # a resolved eigenvector above the accepted one whose α drifts
        for j in range(len(w1)):
            if tails[j] >= policy.track_tail_tol:
                continue
            drift = float(np.abs(w2 - w1[j]).min()) if len(w2) else math.inf
            if policy.accepts(drift, tails[j]):
                accepted = make_mode(p1, w1[j], V1[:, j], drift, n2, policy)
                break
            if tails[j] < policy.tail_tol:
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
            },
            coords={"kz": ("kz", self.kz, {"long_name": "spanwise wavenumber", "units": WAVENUMBER_UNITS})},
            attrs={
                "long_name": "transverse dispersion relation (kx = 0)",
                "theta": self.theta,
                "nu0": self.nu0,
                **self.attrs,
            },
        )


def transverse_dispersion(
    flow: SteadyFlow, kz, *, policy: RejectionPolicy = DEFAULT_POLICY, n: int | None = None
) -> TransverseDispersion:
    """α(k_z) at k_x = 0 of the least-stable physical mode at each k_z (module docstring).

    Points where no physical mode is found keep the best resolved candidate, flagged
    ``physical = False``.
    """
    ks = np.atleast_1d(np.asarray(kz, dtype=float))
    if ks.ndim != 1 or len(ks) == 0:
        raise ParameterError("kz: expected a non-empty 1-D array of wavenumbers")
    out = np.full((4, len(ks)), np.nan)
    nres = np.zeros(len(ks), dtype=int)
    phys = np.zeros(len(ks), dtype=bool)
    for i, k in enumerate(ks):
        try:
            m = transverse_mode(flow, float(k), policy=policy, n=n)
        except ConvergenceError:
            continue
        out[:, i] = m.alpha.real, m.alpha.imag, m.drift, m.tail
        nres[i], phys[i] = m.n, m.physical
    return TransverseDispersion(
        ks, out[0], out[1], out[2], out[3], nres, phys, flow.theta, flow.nu0, flow.model.attrs()
    )


def growth_plane(flow: SteadyFlow, kx, kz, *, policy: RejectionPolicy = DEFAULT_POLICY, n: int | None = None):
    """Growth rate Re α of the least-stable physical mode over the (k_x, k_z) plane.

    Returns
    -------
    xarray.Dataset
        ``alpha_re``, ``alpha_im``, ``drift``, ``tail``, ``physical`` over (kx, kz);
        attributes ``growth_max``, ``kx_max``, ``kz_max`` (where the largest Re α lies) and
        ``direction`` ("longitudinal" if it lies at kz = 0, "transverse" at kx = 0, else
        "oblique").
    """
    import xarray as xr

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
            **flow.model.attrs(),
        },
    )

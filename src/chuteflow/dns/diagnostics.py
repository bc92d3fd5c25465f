"""Measurements on a run: the linear mode's eigenvalue and the resolution of the highest
modes; the saturated wave (amplitude, speed, wavelength, time to saturate, verdict) is
measured by :func:`chuteflow.trackers.wave_measures`, shared with the 1D model."""

from __future__ import annotations

import math

import numpy as np

from ..spectral import coefficients as chebyshev_coefficients
from ..trackers import VERDICTS, WavePolicy, wave_measures
from .discretisation import Discretisation

__all__ = [
    "bdf2_eigenvalue",
    "fourier_tail",
    "spectrum_share",
    "measure_mode",
    "resolution_tails",
    "wave_measures",
    "VERDICTS",
    "WavePolicy",
]


def bdf2_eigenvalue(growth_factor: complex, dt: float) -> complex:
    """The eigenvalue α whose BDF2 amplification per step is ``growth_factor`` G.

    BDF2 applied to X' = αX gives (3/2 G² − 2G + 1/2) = αΔt G², so α = (3/2 − 2/G + 1/(2G²))/Δt:
    the discrete operator's eigenvalue, free of the time discretisation error.
    """
    G = complex(growth_factor)
    return (1.5 - 2.0 / G + 0.5 / G**2) / dt


def measure_mode(t: np.ndarray, amplitude: np.ndarray, k: float) -> dict[str, float]:
    """Growth rate and phase velocity of a complex mode amplitude A(t) ∝ exp(αt).

    Least-squares lines through ln|A| and the unwrapped arg A: Re α and Im α; the phase
    velocity is c = −Im α / k (positive down the slope, :attr:`chuteflow.stability.Mode.wave_speed`).
    """
    t = np.asarray(t, dtype=float)
    A = np.asarray(amplitude, dtype=complex)
    ok = np.isfinite(A) & (np.abs(A) > 0)
    if ok.sum() < 3:
        return {"growth_rate": math.nan, "phase_velocity": math.nan, "omega": math.nan}
    t, A = t[ok], A[ok]
    gr = np.polyfit(t, np.log(np.abs(A)), 1)[0]
    om = np.polyfit(t, np.unwrap(np.angle(A)), 1)[0]
    return {"growth_rate": float(gr), "omega": float(om), "phase_velocity": float(-om / k) if k else math.nan}


def spectrum_share(S: np.ndarray, first: int) -> float:
    """The share of the modes m ≥ ``first`` in a spectrum S (fields, nodes, modes 0 …): for each
    field the largest |Ŝ_m(y_j)|, m ≥ ``first``, over the largest of all m ≥ 1; the largest
    over the fields; 0 where there are no such modes or for a field whose modes m ≥ 1 are below
    1e-12 of its mean (a wave at the round-off level, an unperturbed run, has no spectrum to
    judge). :func:`fourier_tail` (the top eighth) and
    :func:`~chuteflow.dns.remap.lost_fraction` (beyond a grid's modes) are this."""
    if S.shape[-1] < 2 or first >= S.shape[-1]:
        return 0.0
    a = np.abs(S[:, :, 1:]).max(axis=1)  # (fields, modes − 1): the largest over the nodes
    peak = a.max(axis=1)
    ok = peak > 1e-12 * (np.abs(S[:, :, 0]).max(axis=1) + 1.0)
    if not ok.any():
        return 0.0
    return float((a[ok, max(first, 1) - 1 :].max(axis=1) / peak[ok]).max())


def fourier_tail(C: np.ndarray) -> float:
    """The x tail of :func:`resolution_tails` of coefficients C (fields, nodes, M + 1): for each
    field the largest |Ĉ_m(y_j)| of the top eighth of the modes m ≥ 1 (at least M) over the
    largest of all m ≥ 1, the largest over the fields; 0 for M = 0 or a field whose modes
    m ≥ 1 are below 1e-12 of its mean (:func:`spectrum_share`)."""
    M = C.shape[-1] - 1
    return spectrum_share(C, M - max(1, M // 8) + 1) if M >= 1 else 0.0


def resolution_tails(disc: Discretisation, C: np.ndarray) -> dict[str, float]:
    """Amplitude of the highest resolved modes relative to the largest, in x and in y.

    ``x_tail``: for each field (ln ν, u, v, T) the largest |Ĉ_m(y_j)| of the top eighth of the
    Fourier modes m (at least the highest, M) over the largest of all modes m ≥ 1; the
    largest over the fields (0 without a wave: a field whose modes m ≥ 1 are below 1e-12 of
    its mean is left out). ``y_tail``: for each field, the Chebyshev
    coefficients of its profile at every x of the padded grid; the largest of the top tenth
    (at least two) over the largest coefficient; the largest over fields and x. A spectrum
    that has decayed by 1e-4 over the resolved modes has tails ≤ 1e-4.
    """
    x_tail = fourier_tail(C)
    phys = np.stack([disc.to_physical(C[f]) for f in range(4)])  # (4, N+1, nxp)
    c = np.abs(chebyshev_coefficients(np.moveaxis(phys, 1, -1)))  # (4, nxp, N+1)
    top = max(2, (disc.n + 1) // 10)
    peak = c.max(axis=(1, 2))
    tails = c[..., -top:].max(axis=(1, 2))
    ok = peak > 0
    y_tail = float((tails[ok] / peak[ok]).max()) if ok.any() else 0.0
    return {"x_tail": x_tail, "y_tail": y_tail}

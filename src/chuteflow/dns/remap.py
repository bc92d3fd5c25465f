"""Moving a run onto a grid that follows its front: where the front is, which map resolves it,
and the state carried over to that grid.

:class:`~chuteflow.dns.DnsSimulation` with ``x_map=True`` answers a rising x tail (the
:class:`~chuteflow.trackers.ResolutionMonitor`'s ``"refine x"``) with :func:`best_grid`: the
state re-represented on tan maps (:class:`~chuteflow.dns.xmap.TanMap`) centred at the
front, with g'(x0) = β from :data:`BETAS`, at the run's modes first, and with half as many
modes again where no map at the run's modes lowers the tail enough. The re-representation
(:func:`remap_coefficients`) evaluates the run's Fourier series exactly at the new grid's
points and projects onto its modes: the same function, apart from what the new grid cannot
carry (its own tail, which is what the choice minimises).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import scipy.fft

from ..spectral import fourier_evaluate
from .diagnostics import fourier_tail, spectrum_share
from .discretisation import Discretisation
from .xmap import TanMap

__all__ = [
    "BETAS",
    "REMAP_GAIN",
    "GridChoice",
    "front_position",
    "remap_coefficients",
    "best_grid",
    "lost_fraction",
]

#: The map strengths tried (g'(x0) = β; 1 is the uniform grid). At P5's bore (θ 17°,
#: ν0(0) 0.1, L = 2000, t = 14616) the modes needed for an x tail ≤ 1e-4 are 96 uniform,
#: 48, 32, 32, 48 at β = 0.5, 0.35, 0.25, 0.15 (docs/dns.md, *A grid that follows the
#: front*): below ≈ 0.25 the coarse side of the map costs more than the front gains.
BETAS = (1.0, 0.5, 0.35, 0.25)

#: :func:`remap_coefficients` samples the old series at this many times the new padded grid's
#: points (a projection, not an interpolation, onto the new modes).
OVERSAMPLE = 4

#: A map at the run's modes is taken where it lowers the x tail at least this many times;
#: else the modes are doubled (with the best map for them).
REMAP_GAIN = 8.0


@dataclass(frozen=True)
class GridChoice:
    """One candidate x grid: ``modes`` and ``x_map`` (None: uniform), the x tail the state has
    on it (the larger of :func:`~chuteflow.dns.diagnostics.fourier_tail` and
    :func:`lost_fraction`) and the state's coefficients there."""

    modes: int
    x_map: TanMap | None
    tail: float
    C: np.ndarray

    @property
    def beta(self) -> float:
        """g'(x0) of the map (1 for the uniform grid)."""
        return 1.0 if self.x_map is None else self.x_map.beta

    @property
    def centre(self) -> float:
        """x0 of the map (0 for the uniform grid)."""
        return 0.0 if self.x_map is None else self.x_map.centre


def front_position(disc: Discretisation, C: np.ndarray) -> float:
    """Position x (in [0, L)) of the steepest point of ln ν: the padded grid's point where
    max over y of |∂_x ln ν| is largest (the bore's front; the map's centre)."""
    ds = disc.to_physical(C[0] * (1j * disc.k))  # ∂_s ln ν on the padded grid (N + 1, nxp)
    if disc.x_map is not None:
        ds = ds * disc.map_metric[0]  # ∂_x = (1/g') ∂_s
    j = int(np.argmax(np.abs(ds).max(axis=0)))
    return float(np.mod(disc.x[j], disc.length))


def _spectrum(C: np.ndarray, old: Discretisation, new: Discretisation, oversample: int) -> np.ndarray:
    """The old series sampled at ``oversample`` times the new padded grid's points (uniform in
    the new s) and transformed: its modes in the new s up to that grid's Nyquist."""
    points = scipy.fft.next_fast_len(max(1, int(oversample)) * new.nxp, real=True)
    s_new = np.arange(points) * new.length / points
    x = s_new if new.x_map is None else new.x_map.x(s_new)
    s_old = x if old.x_map is None else old.x_map.s(x)
    values = fourier_evaluate(C, s_old, old.length)
    return scipy.fft.rfft(values, axis=-1, norm="forward")[..., : (points - 1) // 2 + 1]


def remap_coefficients(
    C: np.ndarray, old: Discretisation, new: Discretisation, oversample: int = OVERSAMPLE
) -> np.ndarray:
    """Coefficients on ``new`` of the function whose coefficients on ``old`` are ``C`` (the
    same period; either grid mapped or uniform): the old series evaluated exactly at
    ``oversample`` times the new padded grid's points (uniform in the new s), projected onto
    the new modes. Exact where the new grid resolves the function; where it does not, what
    it cannot carry stays in the modes beyond M rather than aliasing onto the kept ones (at
    the new padded grid's points alone, content of the old grid finer than the map's coarse
    spacing would fold into low modes unseen by the tail)."""
    return _spectrum(C, old, new, oversample)[..., : new.modes + 1]


def lost_fraction(S: np.ndarray, modes: int) -> float:
    """What a grid of ``modes`` modes cannot carry of a spectrum S (fields, nodes, modes): for
    each field the largest |Ŝ_m|, m > ``modes``, over the largest of all m ≥ 1; the largest
    over the fields (0 for a field without a wave, as :func:`fourier_tail`)."""
    return spectrum_share(S, modes + 1)


def _candidate(disc: Discretisation, C: np.ndarray, modes: int, x_map: TanMap | None) -> GridChoice:
    new = replace(disc, modes=modes, nxp=0, x_map=x_map)  # (nxp 0: the default padded grid)
    S = _spectrum(C, disc, new, OVERSAMPLE)
    Cn = S[..., : modes + 1]
    # the tail the state has there: its own highest modes, and what the grid cannot carry
    return GridChoice(modes, x_map, max(fourier_tail(Cn), lost_fraction(S, modes)), Cn)


def best_grid(disc: Discretisation, C: np.ndarray, max_modes: int, betas=BETAS) -> GridChoice | None:
    """The x grid the run's state ``C`` (on ``disc``) goes to where its x tail rises.

    Candidates: the tan maps of strengths ``betas`` centred at :func:`front_position` (β = 1:
    the uniform grid). The best at the run's modes M is taken where it lowers the tail at
    least :data:`REMAP_GAIN` times below the run's; else the best at half as many modes again
    (3M/2 to a multiple of 8, at most ``max_modes``; as the y grid grows, ``Y_REFINE``) —
    there the run's own grid with more modes carries the band-limited state whole, so the
    choice keeps it; None where neither exists (the modes at ``max_modes`` and no map helps:
    the run warns). Until 2026-12-07 the modes doubled: at P1, L = 2000 (±68 %) that took
    the x tail from 2.5e-5 to 1.7e-7, far below the 1e-4 the run asks for, on a 193 × 96
    grid that cost 150 GMRES iterations a step (docs/dns.md).
    """
    centre = front_position(disc, C)
    now = fourier_tail(C)
    m = disc.modes
    maps = [None if b == 1.0 else TanMap(centre, b, disc.length) for b in betas]
    grown = min(8 * math.ceil(1.5 * m / 8), max_modes)
    for modes in (m, grown) if grown > m else (m,):
        if not 1 <= modes <= max_modes:
            continue
        best = min((_candidate(disc, C, modes, mp) for mp in maps), key=lambda c: c.tail)
        if modes > m or best.tail * REMAP_GAIN <= now:
            return best
    return None

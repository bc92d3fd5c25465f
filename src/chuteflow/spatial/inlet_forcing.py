"""The signalling problem in a laboratory's units: does a wave forced at the inlet grow by a
visible factor before the end of the chute?

The paper scales lengths by the grain diameter σ and times by √(σ/g) (§2.1, after the
constitutive relations: "the length unit σ, the mass unit ρp σ³, and the time unit √(σ/g)").
A dimensionless angular frequency ω̂ and spatial growth rate −Im k̂ (the spatial branch k̂(ω̂) of
:func:`~chuteflow.spatial.spatial_dispersion`) are therefore, for grains of diameter σ (m)
under gravity g (m/s²),

    f = ω̂ √(g/σ) / (2π)            (Hz)
    −Im k = −Im k̂ / σ               (1/m)
    A(X) = exp(−Im k · X) = exp(−Im k̂ · X/σ)     (the amplitude gain over a length X, m)

The chute length X is measured along x, the coordinate down the slope parallel to the floor
(the paper's figure 1), from the point where the disturbance enters (the inlet) to where it
is observed (the end). The base flow is the paper's uniform steady flow (§3), so the gain
depends only on that distance: the chute is assumed to carry the fully developed flow from
the inlet on (its acceleration zone, the inlet's own shaping of the forcing and the outlet
are not modelled). A forcing exp(−2πif t) of amplitude a0 at the inlet arrives at the end
with amplitude a0 A(X); the gain is a property of the linear theory (small a0).

The signalling problem is the relevant one for a **convectively** unstable flow (Huerre &
Monkewitz 1990, §3): the paper's unstable points P1, P4, P5 are
(:func:`~chuteflow.spatial.absolute_instability`). For an absolutely unstable flow the
response at a fixed point grows in time whatever the inlet does, and the gain of this
module does not describe what is seen.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..closures import ChuteModel
from ..errors import ConvergenceError, ParameterError
from ..steady import SteadyFlow
from ._core import DEFAULT_SPATIAL_POLICY, SpatialPolicy, check_flow
from .branches import spatial_dispersion

__all__ = ["SignallingResult", "signalling", "G_EARTH"]

#: Standard gravity (m/s²), the default of :func:`signalling`.
G_EARTH = 9.81


def _positive(name: str, value, why: str) -> float:
    """``value`` as a finite float > 0, or a one-line :class:`ParameterError`."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ParameterError(f"{name} = {value!r}: expected a number ({why})") from None
    if not (math.isfinite(v) and v > 0):
        raise ParameterError(f"{name} = {value!r} is outside (0, inf): {why}")
    return v


def check_units(
    grain_diameter, chute_length, g, threshold, names=("grain_diameter", "chute_length", "g", "threshold")
) -> tuple[float, float, float, float]:
    """The four physical inputs of :func:`signalling`, checked (one-line errors naming each by
    ``names``: the CLI's option names differ)."""
    d = _positive(names[0], grain_diameter, "the grain diameter σ in metres, the paper's length unit")
    X = _positive(names[1], chute_length, "the distance in metres from the inlet down the slope")
    gg = _positive(names[2], g, "the gravitational acceleration in m/s^2")
    try:
        t = float(threshold)
    except (TypeError, ValueError):
        raise ParameterError(f"{names[3]} = {threshold!r}: expected a number (an amplitude gain)") from None
    if not (math.isfinite(t) and t > 1):
        raise ParameterError(
            f"{names[3]} = {threshold!r} is outside (1, inf): the amplitude gain that counts as "
            "visible (a gain <= 1 is no growth)"
        )
    return d, X, gg, t


@dataclass(frozen=True, eq=False)
class SignallingResult:
    """The amplification of inlet forcing over a chute, in physical units (module docstring).

    Per frequency (arrays over the forcing frequencies, increasing):

    Attributes
    ----------
    frequency : ndarray
        Forcing frequency f (Hz).
    omega : ndarray
        The same, dimensionless: ω̂ = 2πf √(σ/g).
    spatial_growth : ndarray
        −Im k (1/m): the wave's amplitude grows as exp(−Im k · x) down the slope (< 0: decays).
    amplification : ndarray
        exp(−Im k · X): the amplitude gain over the chute.
    wavelength : ndarray
        2π/Re k (m).
    point_converged : ndarray of bool
        Each spatial point passed the temporal modes' tests.

    Scalars:

    frequency_max : float
        The most amplified frequency (Hz): the maximum of −Im k over f, refined
        (:func:`~chuteflow.spatial.spatial_dispersion`'s ``omega_max``); NaN where nothing grows.
    spatial_growth_max : float
        −Im k at ``frequency_max`` (1/m).
    amplification_max : float
        exp(``spatial_growth_max`` · X); where nothing grows, the largest sampled gain (< 1).
    frequency_cutoff : float
        The cut-off frequency (Hz): above it every forced wave decays (the frequency of the
        neutral temporal mode at the paper's k_c, §4.2); NaN where the flow is long-wave stable.
    visible : bool
        ``amplification_max`` ≥ ``threshold``: some frequency grows by the threshold before
        the end of the chute.
    length_to_threshold : float
        ln(threshold) / ``spatial_growth_max`` (m): the chute length the most amplified
        frequency needs to grow by the threshold (inf where nothing grows).
    depth, speed : float
        The steady layer's thickness h σ (m) and mean velocity Q0/ρ̄0 · √(gσ) (m/s).
    time_unit : float
        √(σ/g) (s).
    grain_diameter, chute_length, g, threshold : float
        The inputs (m, m, m/s², 1).
    converged : bool
        Every spatial point converged (the dispersion curve's ``converged``).
    note : str
        Why it is flagged; empty if nothing.
    """

    frequency: np.ndarray
    omega: np.ndarray
    spatial_growth: np.ndarray
    amplification: np.ndarray
    wavelength: np.ndarray
    point_converged: np.ndarray
    frequency_max: float
    spatial_growth_max: float
    amplification_max: float
    frequency_cutoff: float
    visible: bool
    length_to_threshold: float
    depth: float
    speed: float
    time_unit: float
    grain_diameter: float
    chute_length: float
    g: float
    threshold: float
    omega_max: float
    omega_c: float
    converged: bool
    note: str = ""
    theta: float = math.nan
    nu0: float = math.nan
    model: ChuteModel | None = field(default=None, repr=False)

    def to_dict(self) -> dict:
        """JSON-ready scalars and the per-frequency list ``spectrum`` (the keys of
        ``chuteflow signalling --json``, docs/cli.md)."""
        return {
            "theta": self.theta,
            "nu0": self.nu0,
            **(self.model.to_dict() if self.model is not None else {}),
            "grain_diameter": self.grain_diameter,
            "chute_length": self.chute_length,
            "g": self.g,
            "threshold": self.threshold,
            "time_unit": self.time_unit,
            "depth": self.depth,
            "speed": self.speed,
            "frequency_max": self.frequency_max,
            "spatial_growth_max": self.spatial_growth_max,
            "amplification_max": self.amplification_max,
            "frequency_cutoff": self.frequency_cutoff,
            "length_to_threshold": self.length_to_threshold,
            "visible": bool(self.visible),
            "omega_max": self.omega_max,
            "omega_c": self.omega_c,
            "spectrum": [
                {
                    "frequency": float(f),
                    "omega": float(w),
                    "spatial_growth": float(s),
                    "amplification": float(a),
                    "wavelength": float(lam),
                    "converged": bool(c),
                }
                for f, w, s, a, lam, c in zip(
                    self.frequency,
                    self.omega,
                    self.spatial_growth,
                    self.amplification,
                    self.wavelength,
                    self.point_converged,
                )
            ],
            "converged": bool(self.converged),
            "note": self.note,
        }

    def to_xarray(self):
        """The per-frequency arrays as an :class:`xarray.Dataset` over ``frequency`` (Hz),
        the scalars as attributes."""
        import xarray as xr

        ds = xr.Dataset(
            {
                "omega": (
                    "frequency",
                    self.omega,
                    {"units": "sqrt(g/sigma)", "long_name": "2 pi f sqrt(sigma/g)"},
                ),
                "spatial_growth": (
                    "frequency",
                    self.spatial_growth,
                    {"units": "1/m", "long_name": "spatial growth rate -Im k"},
                ),
                "amplification": (
                    "frequency",
                    self.amplification,
                    {"units": "1", "long_name": "amplitude gain exp(-Im k X) over the chute"},
                ),
                "wavelength": ("frequency", self.wavelength, {"units": "m", "long_name": "2 pi / Re k"}),
                "converged": ("frequency", self.point_converged),
            },
            coords={
                "frequency": ("frequency", self.frequency, {"units": "Hz", "long_name": "forcing frequency"})
            },
        )
        d = {k: v for k, v in self.to_dict().items() if k != "spectrum"}
        ds.attrs.update({k: (str(v) if isinstance(v, bool) or v is None else v) for k, v in d.items()})
        if self.model is not None:
            ds.attrs.update(self.model.attrs())
            ds.attrs["model"] = self.model.describe()
        return ds


def signalling(
    flow: SteadyFlow,
    *,
    grain_diameter: float,
    chute_length: float,
    g: float = G_EARTH,
    frequencies=None,
    num: int = 24,
    threshold: float = 10.0,
    policy: SpatialPolicy | None = None,
    cache=None,
    strict: bool = False,
) -> SignallingResult:
    """The gain exp(−Im k X) of inlet forcing over a chute of length X, in physical units.

    Parameters
    ----------
    flow : SteadyFlow
        Base state (dimensionless, the paper's §3).
    grain_diameter : float
        The grain diameter σ (m) > 0: the paper's length unit (§2.1).
    chute_length : float
        X (m) > 0, measured down the slope along the floor from the inlet (module docstring).
    g : float
        Gravitational acceleration (m/s²) > 0 (default 9.81).
    frequencies : array_like, optional
        Forcing frequencies (Hz) > 0. Default: ``num`` frequencies on (0, 1.25 f_c], f_c the
        cut-off (:func:`~chuteflow.spatial.spatial_dispersion`'s default grid).
    num : int
        Number of default frequencies (24).
    threshold : float
        Amplitude gain > 1 that counts as visible (10).
    policy, cache
        As for :func:`~chuteflow.spatial.spatial_dispersion` (which this wraps: nothing is
        solved here that it does not solve).
    strict : bool
        True: raise :class:`~chuteflow.errors.ConvergenceError` where a point is flagged.

    Returns
    -------
    SignallingResult
        Flagged (``converged=False``, ``note``) where a spatial point missed its tests.
    """
    flow = check_flow(flow)
    sigma, X, gg, thr = check_units(grain_diameter, chute_length, g, threshold)
    policy = DEFAULT_SPATIAL_POLICY if policy is None else policy
    t_unit = math.sqrt(sigma / gg)  # the paper's time unit √(σ/g), s
    omegas = None
    if frequencies is not None:
        fs = np.atleast_1d(np.asarray(frequencies, dtype=float))
        if fs.size == 0:
            raise ParameterError(
                "frequencies: empty (give at least one frequency in Hz, or none for the default)"
            )
        for f in fs:
            _positive("frequencies", f, "forcing frequencies in Hz")
        omegas = 2.0 * math.pi * fs * t_unit
    elif not (isinstance(num, int) and num >= 3):
        raise ParameterError(f"num = {num!r}: at least 3 default frequencies")
    ds = spatial_dispersion(flow, omegas, num=num, policy=policy, cache=cache)
    w = np.asarray(ds["omega"].values, dtype=float)
    gh = np.asarray(ds["spatial_growth"].values, dtype=float)  # −Im k̂, 1/σ
    kr = np.asarray(ds["k_re"].values, dtype=float)
    conv = np.asarray(ds["converged"].values, dtype=bool)
    growth = gh / sigma
    amp = np.exp(growth * X)
    w_max = float(ds.attrs["omega_max"])
    g_max_hat = float(ds.attrs["spatial_growth_max"])
    w_c = float(ds.attrs["omega_c"])
    if math.isfinite(g_max_hat):
        g_max = g_max_hat / sigma
        a_max = math.exp(g_max * X)
        l_thr = math.log(thr) / g_max
    else:
        g_max = math.nan
        a_max = float(np.nanmax(amp)) if np.isfinite(amp).any() else math.nan
        l_thr = math.inf
    notes = []
    if not conv.all():
        bad = w[~conv]
        notes.append(
            f"{bad.size} of {w.size} spatial points not converged (first at f = "
            f"{bad[0] / (2 * math.pi * t_unit):.4g} Hz)"
        )
    res = SignallingResult(
        frequency=w / (2.0 * math.pi * t_unit),
        omega=w,
        spatial_growth=growth,
        amplification=amp,
        wavelength=np.where(kr > 0, 2.0 * math.pi * sigma / np.where(kr > 0, kr, 1.0), np.nan),
        point_converged=conv,
        frequency_max=w_max / (2.0 * math.pi * t_unit),
        spatial_growth_max=float(g_max),
        amplification_max=float(a_max),
        frequency_cutoff=w_c / (2.0 * math.pi * t_unit),
        visible=bool(a_max >= thr),
        length_to_threshold=float(l_thr),
        depth=float(flow.h * sigma),
        speed=float(flow.Q / flow.rho_bar * math.sqrt(gg * sigma)),
        time_unit=t_unit,
        grain_diameter=sigma,
        chute_length=X,
        g=gg,
        threshold=thr,
        omega_max=w_max,
        omega_c=w_c,
        converged=bool(conv.all()),
        note="; ".join(notes),
        theta=flow.theta,
        nu0=flow.nu0,
        model=flow.model,
    )
    if strict and not res.converged:
        raise ConvergenceError(f"signalling at theta = {flow.theta:g}, nu0 = {flow.nu0:g}: {res.note}")
    return res

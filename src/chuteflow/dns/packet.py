"""The growth of a wave packet along rays, measured on a simulated impulse response.

A localised pulse released at t = 0 in a long periodic domain spreads into a packet whose
amplitude, along each ray x = x0 + V t, behaves for large t as (the saddle point k*(V) of
α(k) + ikV; Bers 1983, Huerre & Monkewitz 1990 §2; :mod:`chuteflow.spatial.absolute`)

    |A(x0 + V t, t)| ≃ a(V) t^{-1/2} exp(σ(V) t) (1 + O(1/t)),    σ(V) = Re[α(k*) + i k* V].

So between two late times t1 < t2 of a run

    σ_measured(V) = [ln|A(V t2)| − ln|A(V t1)|]/(t2 − t1) + ½ ln(t2/t1)/(t2 − t1)

(the second term removes the t^{-1/2} of the saddle) differs from σ(V) by O(1/(t1 t2)), and
its zeros are the packet's edges V− < V+ (the growing range of Briggs–Bers). ``A`` is the
analytic signal of the deviation δρ̄(x, t) of the depth-integrated density from its mean: the
Fourier modes k > 0 of δρ̄ doubled, k ≤ 0 dropped — the part of the impulse response whose
Fourier integral runs over k > 0, the one whose saddle k* lies near the positive real axis.
It is evaluated on each ray by its Fourier series (exact at any x, no interpolation).

Where the edge is the branch point k = 0 (α(0) = 0: the kinematic-wave speed; P1's V−) the
saddle reaches the end of the integral and σ(V) touches zero quadratically; there the
prefactor is not t^{-1/2} and the measured edge converges only slowly (docs/spatial.md).

:func:`ray_growth` works on arrays (x, t, δρ̄(t, x)) — a run of :func:`chuteflow.dns.simulate`
started with ``initial=`` a pulse (``benchmarks/probes/packet_edges.py``) or any other record.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..conventions import RATE_UNITS, VELOCITY_UNITS
from ..errors import ParameterError
from ..steady import SteadyFlow

__all__ = ["PacketGrowth", "analytic_signal", "ray_growth", "growth_edges", "simulate_pulse"]


def analytic_signal(field_: np.ndarray, axis: int = -1) -> np.ndarray:
    """Fourier coefficients of the analytic signal of a real periodic ``field_`` along
    ``axis``: c_m for m = 1 … ⌈n/2⌉ − 1 (2 × the rfft coefficient over n; the mean and a
    Nyquist mode dropped), so that A(x) = Σ c_m e^{i k_m x}."""
    f = np.asarray(field_, dtype=float)
    n = f.shape[axis]
    c = np.fft.rfft(f, axis=axis) * (2.0 / n)
    m_hi = (n - 1) // 2
    return np.take(c, np.arange(1, m_hi + 1), axis=axis)


def _envelope_on_rays(c: np.ndarray, length: float, xi: np.ndarray) -> np.ndarray:
    """|A(ξ)| at the points ``xi`` of the Fourier coefficients ``c`` (m = 1 … M)."""
    k = 2.0 * math.pi * np.arange(1, c.shape[-1] + 1) / length
    return np.abs(np.exp(1j * np.outer(xi, k)) @ c)


@dataclass(frozen=True, eq=False)
class PacketGrowth:
    """The growth along rays of a measured packet (module docstring).

    Attributes
    ----------
    V : ndarray
        Ray speeds (lab frame), √(gσ).
    growth : ndarray
        σ_measured(V) between ``t1`` and ``t2`` (with the ½ ln(t2/t1)/(t2 − t1) of the
        saddle's t^{-1/2}), 1/τ.
    v_minus, v_plus : float
        The zeros of ``growth`` on either side of its maximum (linear interpolation); NaN where
        the growth does not change sign inside ``V``.
    v_peak, growth_peak : float
        The ray of the largest measured growth and that growth.
    t1, t2 : float
        The two times compared.
    converged : bool
        Both edges found inside ``V``.
    note : str
        Why not.
    """

    V: np.ndarray = field(repr=False)
    growth: np.ndarray = field(repr=False)
    v_minus: float
    v_plus: float
    v_peak: float
    growth_peak: float
    t1: float
    t2: float
    converged: bool
    note: str = ""

    def to_dict(self) -> dict:
        """JSON-ready scalars."""
        return {
            "v_minus": self.v_minus,
            "v_plus": self.v_plus,
            "v_peak": self.v_peak,
            "growth_peak": self.growth_peak,
            "t1": self.t1,
            "t2": self.t2,
            "converged": bool(self.converged),
            "note": self.note,
        }

    def to_xarray(self):
        """σ_measured(V) as an :class:`xarray.Dataset` over V."""
        import xarray as xr

        return xr.Dataset(
            {
                "growth": (
                    "V",
                    self.growth,
                    {"units": RATE_UNITS, "long_name": "growth along the ray x = V t"},
                )
            },
            coords={"V": ("V", self.V, {"units": VELOCITY_UNITS, "long_name": "ray speed"})},
            attrs={k: (str(v) if isinstance(v, bool) else v) for k, v in self.to_dict().items()},
        )


def growth_edges(V: np.ndarray, growth: np.ndarray) -> tuple[float, float, int]:
    """The zeros of ``growth(V)`` either side of its maximum (linear interpolation between
    samples; NaN where it stays positive to the end of ``V``) and the index of the maximum."""
    V = np.asarray(V, dtype=float)
    g = np.asarray(growth, dtype=float)
    i = int(np.nanargmax(g))
    edges = []
    for rng in (range(i, 0, -1), range(i, len(V) - 1)):
        e = math.nan
        for j in rng:
            a, b = (j - 1, j) if rng.step < 0 else (j, j + 1)
            ga, gb = g[a], g[b]
            if ga * gb <= 0 and ga != gb:
                e = float(V[a] + (V[b] - V[a]) * ga / (ga - gb))
                break
        edges.append(e)
    return edges[0], edges[1], i


def ray_growth(
    x: np.ndarray,
    t: np.ndarray,
    field_: np.ndarray,
    V: np.ndarray,
    *,
    t1: float,
    t2: float,
    length: float | None = None,
    x0: float = 0.0,
    frame: float = 0.0,
    mass_speed: float | None = None,
) -> PacketGrowth:
    """σ(V) of a packet released at (x0, t = 0), measured between ``t1`` and ``t2``.

    Parameters
    ----------
    x : ndarray
        Equally spaced points of the periodic domain (the run's frame ξ = x − frame·t).
    t : ndarray
        Times of the records; ``t1``, ``t2`` are taken at the nearest record.
    field_ : ndarray
        The record (time, x), e.g. ``ds.rho_bar`` of :func:`chuteflow.dns.simulate`; its mean
        over x is removed (the analytic signal drops k = 0).
    V : ndarray
        Ray speeds (lab frame).
    length : float, optional
        Period; default ``len(x) · (x[1] − x[0])``.
    x0 : float
        Where the pulse was at t = 0 (in the run's frame, which coincides with the lab's then).
    frame : float
        Speed of the run's frame: the ray x = x0 + V t is at ξ = x0 + (V − frame) t.
    mass_speed : float, optional
        The speed at which the pulse's net mass travels (the kinematic-wave speed dQ0/dρ̄0,
        ``ds.attrs["kinematic_wave_speed"]``). A field with net mass m has an analytic signal
        with a tail m/(π d) at a distance d from the mass (its k → 0 end): a floor under the
        packet's edges. Given this speed, the analytic signal of the first record
        (t = 0), carried rigidly at ``mass_speed``, is subtracted at each time: it has the same
        tail, and elsewhere it is the initial pulse, negligible away from the ray
        V = ``mass_speed`` (where the measurement is then not meaningful).

    Returns
    -------
    PacketGrowth
    """
    x = np.asarray(x, dtype=float)
    t = np.asarray(t, dtype=float)
    f = np.asarray(field_, dtype=float)
    V = np.asarray(V, dtype=float)
    if f.shape != (len(t), len(x)):
        raise ParameterError(f"field_: shape {f.shape}, expected (time, x) = {(len(t), len(x))}")
    if not (0 < t1 < t2):
        raise ParameterError(f"t1 = {t1!r}, t2 = {t2!r}: need 0 < t1 < t2 (the pulse starts at t = 0)")
    L = float(length) if length is not None else float(len(x) * (x[1] - x[0]))
    i1, i2 = int(np.argmin(np.abs(t - t1))), int(np.argmin(np.abs(t - t2)))
    T1, T2 = float(t[i1]), float(t[i2])
    if not T1 < T2:
        raise ParameterError(f"t1 = {t1!r}, t2 = {t2!r}: the nearest records coincide (t = {T1:g})")
    logs = []
    m = np.arange(1, (len(x) - 1) // 2 + 1)
    # the grid may not start at 0: shift the phases so that c_m refer to ξ = 0
    shift = np.exp(-2j * math.pi * m * x[0] / L)
    i0 = int(np.argmin(np.abs(t)))
    if mass_speed is not None and abs(t[i0]) > 1e-9 * max(abs(t[-1]), 1.0):
        raise ParameterError("mass_speed: the record must start at t = 0 (the pulse's release)")
    for i, ti in ((i1, T1), (i2, T2)):
        c = analytic_signal(f[i]) * shift
        if mass_speed is not None:
            c = c - analytic_signal(f[i0]) * shift * np.exp(-2j * math.pi * m * (mass_speed - frame) * ti / L)
        xi = x0 + (V - frame) * ti
        logs.append(np.log(_envelope_on_rays(c, L, xi) + 1e-300))
    g = (logs[1] - logs[0]) / (T2 - T1) + 0.5 * math.log(T2 / T1) / (T2 - T1)
    vm, vp, ip = growth_edges(V, g)
    notes = []
    if math.isnan(vm) or math.isnan(vp):
        notes.append("the measured growth does not change sign on both sides inside V: widen V")
    return PacketGrowth(
        V=V,
        growth=g,
        v_minus=vm,
        v_plus=vp,
        v_peak=float(V[ip]),
        growth_peak=float(g[ip]),
        t1=T1,
        t2=T2,
        converged=not notes,
        note="; ".join(notes),
    )


def simulate_pulse(
    flow: SteadyFlow,
    length: float,
    *,
    time: float,
    width: float,
    amplitude: float = 1e-6,
    frame_speed: float = 0.0,
    n: int | None = None,
    modes: int | None = None,
    dt: float | None = None,
    record_every: int = 1,
):
    """The impulse response of ``flow`` by :func:`chuteflow.dns.simulate`: a Gaussian bump
    δ ln ν = ``amplitude`` · exp(−(x − L/2)²/(2 ``width``²)) (uniform in y) at the centre of
    the periodic domain, run to ``time`` in the frame moving at ``frame_speed``. Returns the
    run's dataset with the attributes ``pulse_centre`` (L/2) and ``pulse_width``; measure it
    with :func:`ray_growth` (``x0=ds.attrs["pulse_centre"]``, ``frame=ds.attrs["frame_speed"]``).

    The bump has a net mass, so the analytic signal of δρ̄ keeps a tail ∝ mass/x (the Hilbert
    transform of a bump): about 4e-9 of ρ̄ at 3e4 diameters for the 1e-6 bump of width 150,
    well below the packet's edges for the runs of ``benchmarks/probes/packet_edges.py``. A
    zero-mass (Ricker) pulse removes that floor but its spectrum ∝ k² varies on the scale
    of the saddles k*(V) near k = 0, and the O(1/t) corrections grew (measured at P1: V+
    8.97 against 9.009 from the bump at t = 6000).
    """
    from .api import simulate

    if not (math.isfinite(width) and 0 < width < length / 8):
        raise ParameterError(f"width = {width!r}: the pulse's width must be in (0, L/8) (a localised pulse)")
    x0 = 0.5 * float(length)

    def pulse(x: np.ndarray) -> np.ndarray:
        return amplitude * np.exp(-0.5 * ((x - x0) / width) ** 2)

    ds = simulate(
        flow,
        length,
        time=time,
        n=n,
        modes=modes,
        dt=dt,
        frame_speed=frame_speed,
        initial=pulse,
        snapshots=1,
        record_every=record_every,
    )
    ds.attrs["pulse_centre"] = x0
    ds.attrs["pulse_width"] = float(width)
    return ds

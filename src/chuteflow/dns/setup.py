"""What defines a run of the time-dependent simulation: its set-up, checks and initial state."""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import dataclass

import numpy as np

from ..closures import ChuteModel
from ..errors import ParameterError
from ..spectral import ChebyshevGrid
from ..stability import Mode
from ..steady import SteadyFlow
from .discretisation import TOPS, Discretisation
from .stepper import Stepper

__all__ = [
    "DnsSetup",
    "INITS",
    "check_setup",
    "relax_steady",
    "initial_coefficients",
    "history_coefficients",
    "FORMAT",
]

#: Initial conditions: the least-stable eigenmode at k = 2π/L, or small random noise.
INITS = ("mode", "noise")
#: Version of the checkpoint's content (part of the run's key).
FORMAT = 5


@dataclass(frozen=True)
class DnsSetup:
    """Everything that defines a run (and the key of its checkpoint).

    Attributes
    ----------
    theta, nu0 : float
        Inclination (degrees) and floor packing fraction of the steady flow.
    length : float
        Period L along the slope (diameters).
    time : float
        Simulated time.
    n : int
        Chebyshev intervals N.
    modes : int
        Highest Fourier mode M (``nx = 2M + 1`` real unknowns per node and field).
    dt : float
        Time step (halved automatically where Newton fails).
    init : str
        ``"mode"`` or ``"noise"``.
    amplitude : float
        Largest component of the initial perturbation.
    seed : int
        Random seed of ``init="noise"``.
    model : ChuteModel
        Closures and parameters.
    relax : bool
        Start from this grid's discrete steady state (:func:`relax_steady`).
    frame : float
        Speed of the frame ξ = x − ct of the unknowns (:class:`Discretisation`).
    top : str
        Row of s = ln ν at the top node (:data:`chuteflow.dns.discretisation.TOPS`).
    y_max : float
        Top of the domain (the steady flow's).
    snapshots, record_every : int
        Full-field snapshots stored; ρ̄, Q recorded every this many steps.
    """

    theta: float
    nu0: float
    length: float
    time: float
    n: int
    modes: int
    dt: float
    init: str
    amplitude: float
    seed: int
    model: ChuteModel
    relax: bool = True
    frame: float = 0.0
    top: str = "transport"
    y_max: float = 0.0
    snapshots: int = 6
    record_every: int = 1

    def key(self) -> str:
        """Content hash identifying the run (a checkpoint is reused only for the same key)."""
        d = {
            k: getattr(self, k)
            for k in (
                "theta",
                "nu0",
                "length",
                "n",
                "modes",
                "dt",
                "init",
                "amplitude",
                "seed",
                "relax",
                "frame",
                "top",
                "y_max",
                "snapshots",
                "record_every",
            )
        }
        d["model"] = self.model.to_dict()
        d["format"] = FORMAT
        return hashlib.sha256(json.dumps(d, sort_keys=True).encode()).hexdigest()[:16]


def relax_steady(
    disc: Discretisation, C: np.ndarray, *, steps: int = 30, tol: float = 1e-12
) -> tuple[np.ndarray, float]:
    """The discrete steady state of ``disc`` nearest the x-independent part of ``C``.

    Backward-Euler steps of growing Δt (10, 100, …, 1e6) on mode 0 alone: as Δt → ∞ a step
    is a Newton solve of the steady equations, and every step conserves the mass, so the
    result keeps ∫ν dy of the start (the steady family is one-parameter). Returns the
    coefficients with mode 0 replaced and the largest change max |ΔC| (the steady solver's
    flow interpolated to this grid differs from this grid's steady state by that much).
    """
    d0 = Discretisation(
        disc.theta, disc.model, disc.length, disc.y_max, disc.n, 0, frame=disc.frame, top=disc.top
    )
    st = Stepper(d0)
    c = C[:, :, :1].copy()
    c[..., 0] = c[..., 0].real
    start = c.copy()
    for i in range(steps):
        dt = 10.0 ** min(1 + i, 6)
        ph = st.physical(c)
        new, _ = st.step(c, (ph, ph), dt, first=True)
        change = float(np.max(np.abs(new - c)))
        c = new
        if change < tol and dt >= 1e6:
            break
    out = C.copy()
    out[:, :, 0] = c[..., 0].real
    return out, float(np.max(np.abs(c - start)))


def check_setup(setup: DnsSetup) -> None:
    """A one-line :class:`~chuteflow.errors.ParameterError` for every parameter out of range."""
    if not (math.isfinite(setup.length) and setup.length > 0):
        raise ParameterError(
            f"length = {setup.length!r}: the period L must be a positive number of diameters"
        )
    if not (math.isfinite(setup.time) and setup.time > 0):
        raise ParameterError(f"time = {setup.time!r}: the simulated time must be positive")
    if not (math.isfinite(setup.dt) and 0 < setup.dt <= setup.time):
        raise ParameterError(f"dt = {setup.dt!r}: the time step must be in (0, time]")
    if setup.top not in TOPS:
        raise ParameterError(f"top = {setup.top!r}: choose one of {TOPS}")
    if setup.init not in INITS:
        raise ParameterError(f"init = {setup.init!r}: choose one of {INITS}")
    if not 0 <= setup.modes <= 512:
        raise ParameterError(
            f"nx: {2 * setup.modes + 1} is outside [1, 1025]: modes M = (nx − 1)/2 in [0, 512]"
        )
    if not 8 <= setup.n <= 400:
        raise ParameterError(
            f"ny = {setup.n} is outside [8, 400]: Chebyshev intervals that resolve the layer"
        )
    if int(setup.snapshots) != setup.snapshots or setup.snapshots < 1:
        raise ParameterError(f"snapshots = {setup.snapshots!r}: at least 1 full-field snapshot")
    if int(setup.record_every) != setup.record_every or setup.record_every < 1:
        raise ParameterError(f"record_every = {setup.record_every!r}: a positive number of steps")
    if not (math.isfinite(setup.amplitude) and 0 <= setup.amplitude < 0.5):
        raise ParameterError(f"amplitude = {setup.amplitude!r} is outside [0, 0.5): a small perturbation")


def initial_coefficients(
    disc: Discretisation, flow: SteadyFlow, mode: Mode | None, setup: DnsSetup, dt: float, relax: bool
):
    """Coefficients at t = 0, at t = −Δt (``None`` from noise) and the relaxation change.

    Raises :class:`~chuteflow.errors.ParameterError` when the perturbed state leaves the
    closures' range (ν ≥ ν_m or T ≤ 0 somewhere): ``amplitude`` is too large."""
    p = flow.profiles(disc.grid.y)
    C = np.zeros(disc.shape, dtype=complex)
    C[0, :, 0] = np.log(p["nu"])
    C[1, :, 0] = p["u"]
    C[3, :, 0] = p["T"]
    change = 0.0
    if relax:
        C, change = relax_steady(disc, C)
    if setup.amplitude == 0 or setup.modes == 0:
        return C, C.copy(), change
    if setup.init == "mode":
        assert mode is not None
        g = mode.grid if mode.grid is not None else ChebyshevGrid(mode.n, 0.0, flow.y_max)
        fl = {f: g.interpolate(np.asarray(mode.fields[f]), disc.grid.y) for f in ("nu", "u", "v", "T")}
        V = np.stack([fl["nu"] / p["nu"], fl["u"], fl["v"], fl["T"]])
        # f = 2 Re(C_1 e^{ikx}): the perturbation's largest component is `amplitude`
        V = V * (0.5 * setup.amplitude)
        C0, Cm = C.copy(), C.copy()
        C0[:, :, 1] += V
        # the mode in the frame ξ = x − ct: exp((α + ikc) t + ikξ)
        alpha = mode.alpha + 1j * disc.k[1] * setup.frame
        Cm[:, :, 1] += V * np.exp(-alpha * dt)
        # the x-mean of ν = e^s depends on the amplitude (∝ |ŝ|²): give the level t = −Δt the
        # x-mean density of t = 0 node by node, so that BDF2 starts from equal masses
        Cm[0, :, 0] += np.log(_xmean_nu(disc, C0) / _xmean_nu(disc, Cm))
        _check_valid(disc, C0, setup)
        return C0, Cm, change
    rng = np.random.default_rng(setup.seed)
    m_hi = max(1, setup.modes // 2)
    coef = rng.normal(size=m_hi) + 1j * rng.normal(size=m_hi)
    coef *= 0.5 * setup.amplitude / math.sqrt(m_hi)
    # density perturbation ν̂ ∝ ν0 (ŝ uniform in y): white in the lower half of the modes
    C[0, :, 1 : m_hi + 1] += coef[None, :]
    _check_valid(disc, C, setup)
    return C, None, change


def _check_valid(disc: Discretisation, C: np.ndarray, setup: DnsSetup) -> None:
    nu = np.exp(disc.to_physical(C[0]))
    T = disc.to_physical(C[3])
    nu_m = float(setup.model.nu_max)
    if not (np.all(np.isfinite(nu)) and nu.max() < nu_m and T.min() > 0):
        raise ParameterError(
            f"amplitude = {setup.amplitude:g}: the initial state leaves the closures' range "
            f"(max ν = {nu.max():.4g} of ν_m = {nu_m:g}, min T = {T.min():.3g} must stay > 0); "
            "choose a smaller amplitude"
        )


def _xmean_nu(disc: Discretisation, C: np.ndarray) -> np.ndarray:
    return np.exp(disc.to_physical(C[0])).mean(axis=-1)


def history_coefficients(disc: Discretisation, phys: tuple) -> np.ndarray:
    """Coefficients of a history level (ν, u, v, T) on the padded grid."""
    nu, u, v, T = phys
    return disc.coefficients_of({"s": np.log(nu), "u": u, "v": v, "T": T})

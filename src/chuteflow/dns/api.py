"""The simulation: set-up, time loop with checkpoints, diagnostics and the result Dataset."""

from __future__ import annotations

import hashlib
import json
import math
import os
import time as _time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import xarray as xr

from .._files import atomic_write
from ..closures import ChuteModel
from ..errors import ConvergenceError, ParameterError
from ..spectral import ChebyshevGrid
from ..stability import Mode, OperatorCache, least_stable
from ..steady import SteadyFlow, solve_steady, steady_tangent
from .discretisation import TOPS, Discretisation
from .stepper import NewtonSettings, Stepper

__all__ = ["DnsSetup", "simulate", "summary", "relax_steady", "measure_mode", "bdf2_eigenvalue", "INITS"]

#: Initial conditions: the least-stable eigenmode at k = 2π/L, or small random noise.
INITS = ("mode", "noise")
_FORMAT = 3


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
            )
        }
        d["model"] = self.model.to_dict()
        d["format"] = _FORMAT
        return hashlib.sha256(json.dumps(d, sort_keys=True).encode()).hexdigest()[:16]


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


def _check(setup: DnsSetup) -> None:
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
    if not (math.isfinite(setup.amplitude) and 0 <= setup.amplitude < 0.5):
        raise ParameterError(f"amplitude = {setup.amplitude!r} is outside [0, 0.5): a small perturbation")


def _initial(
    disc: Discretisation, flow: SteadyFlow, mode: Mode | None, setup: DnsSetup, dt: float, relax: bool
):
    """Coefficients at t = 0, at t = −Δt (``None`` from noise) and the relaxation change."""
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
        return C0, Cm, change
    rng = np.random.default_rng(setup.seed)
    m_hi = max(1, setup.modes // 2)
    coef = rng.normal(size=m_hi) + 1j * rng.normal(size=m_hi)
    coef *= 0.5 * setup.amplitude / math.sqrt(m_hi)
    # density perturbation ν̂ ∝ ν0 (ŝ uniform in y): white in the lower half of the modes
    C[0, :, 1 : m_hi + 1] += coef[None, :]
    return C, None, change


def _xmean_nu(disc: Discretisation, C: np.ndarray) -> np.ndarray:
    return np.exp(disc.to_physical(C[0])).mean(axis=-1)


def _coefficients(disc: Discretisation, phys: tuple) -> np.ndarray:
    """Coefficients of a history level (ν, u, v, T) on the padded grid."""
    nu, u, v, T = phys
    return disc.coefficients_of({"s": np.log(nu), "u": u, "v": v, "T": T})


def _checkpoint_path(out: str | os.PathLike | None, checkpoint: str | os.PathLike | None) -> Path | None:
    if checkpoint is not None:
        return Path(checkpoint)
    if out is not None:
        return Path(str(out) + ".checkpoint.npz")
    return None


def _save(path: Path, payload: dict) -> None:
    def write(fh):
        np.savez(fh, **payload)

    atomic_write(path, write)


def simulate(
    theta: float,
    nu0: float,
    length: float,
    *,
    model: ChuteModel | None = None,
    time: float | None = None,
    n: int | None = None,
    modes: int | None = None,
    dt: float | None = None,
    init: str = "mode",
    amplitude: float = 1e-6,
    seed: int = 0,
    snapshots: int = 6,
    record_every: int = 1,
    out: str | os.PathLike | None = None,
    checkpoint: str | os.PathLike | None = None,
    checkpoint_every: float = 30.0,
    progress: Callable[[float, float], None] | None = None,
    settings: NewtonSettings | None = None,
    flow: SteadyFlow | None = None,
    min_dt_fraction: float = 1e-3,
    relax: bool = True,
    frame_speed: float | None = None,
    top: str = "transport",
) -> xr.Dataset:
    """Simulate the time-dependent equations on a slope periodic in x (docs/dns.md).

    Parameters
    ----------
    theta, nu0 : float
        Inclination θ (degrees) and floor packing fraction ν0(0) of the steady flow (§3).
    length : float
        Period L along the slope; the fundamental wavenumber is k = 2π/L.
    model : ChuteModel, optional
        Closures and parameters (the paper's defaults).
    time : float, optional
        Simulated time; default two wave periods 2 × 2π/|Im α| of the least-stable mode.
    n : int, optional
        Chebyshev intervals N; default the resolution at which :func:`chuteflow.stability.least_stable`
        converged at k = 2π/L.
    modes : int, optional
        Highest Fourier mode M; default 2 for ``init="mode"``, max(8, L/30) for noise.
    dt : float, optional
        Time step; default a hundredth of the wave period.
    init : {"mode", "noise"}
        Least-stable eigenmode at k = 2π/L (:func:`chuteflow.stability.least_stable`), or
        random noise in the density (ŝ = δ ln ν uniform in y) in modes 1 … M/2.
    amplitude : float
        Largest component of the initial perturbation.
    seed : int
        Random seed of the noise.
    snapshots : int
        Number of full-field snapshots (equally spaced in time, including both ends).
    record_every : int
        Record ρ̄(x, t), Q(x, t) every this many steps.
    out : path, optional
        NetCDF file written at the end; its checkpoint is ``out + ".checkpoint.npz"``.
    checkpoint : path, optional
        Checkpoint file (overrides the one derived from ``out``). A run with the same
        parameters continues from it; it is removed once the run has finished.
    checkpoint_every : float
        Seconds of wall time between checkpoints.
    progress : callable, optional
        Called as ``progress(t, time)`` after each step.
    settings : NewtonSettings, optional
        Newton–Krylov tolerances.
    flow : SteadyFlow, optional
        The steady flow (else :func:`chuteflow.steady.solve_steady`).
    min_dt_fraction : float
        Stop (status ``"stopped: ..."``) when Newton fails at Δt below this fraction of ``dt``.
    relax : bool
        Start from the discrete steady state of this grid nearest the steady flow
        (:func:`relax_steady`), so that the unperturbed flow stays steady to the solver's
        tolerance; otherwise the interpolated steady flow drifts by its discretisation error.
    frame_speed : float, optional
        Speed c of the frame ξ = x − ct the fields are computed in (x coordinates of the
        result are ξ; velocities are the lab's). Default 0 (lab) from a mode, the eigenmode's
        phase velocity −Im α/k from noise, so that BDF2's damping of the travelling waves
        (∝ (ωΔt)⁴ with ω the frequency seen in the frame) stays small at large Δt.
    top : {"transport", "isothermal"}
        Row of s = ln ν at the top node: eq. (2.1) with the isothermal atmosphere's density
        gradient where the flow enters (default), or the decay condition of eq. (4.5) as a
        constraint (the stability operator's row; at finite amplitude it over-determines
        the outflow and ln ν develops unresolved x-structure there, docs/dns.md).

    Returns
    -------
    xarray.Dataset
        ``rho_bar(time, x)``, ``Q(time, x)``, ``mass(time)``, ``amplitude_re/_im(time)`` (mode-1
        coefficient of ρ̄), fields ``nu, u, v, T(snapshot, y, x)``, and as attributes the
        measured ``growth_rate``, ``phase_velocity``, the eigenvalue compared with
        (``alpha_re``, ``alpha_im``), the BDF2-inverted discrete eigenvalue
        (``alpha_dns_re``, ``alpha_dns_im``), the eigenmode's phase velocity
        ``mode_phase_velocity`` = −Im α/k and the kinematic-wave speed ``kinematic_wave_speed``
        = dQ0/dρ̄0 of the steady family (eq. (B 6)), ``mass_drift``, ``status``, timings and
        the model.
    """
    model = model if model is not None else ChuteModel()
    if flow is None:
        flow = solve_steady(theta, nu0, model)
    k = 2.0 * math.pi / float(length) if length and length > 0 else 0.0
    if not (math.isfinite(k) and k > 0):
        raise ParameterError(f"length = {length!r}: the period L must be a positive number of diameters")
    # the plain Chebyshev grid of the stability operator: the DNS grid is the same, so the
    # linear phase compares discretisation with discretisation
    plain = OperatorCache(mapped=False)
    mode = least_stable(flow, k, cache=plain) if n is None else least_stable(flow, k, n=int(n), cache=plain)
    period = 2.0 * math.pi / max(abs(mode.alpha.imag), 1e-12)
    modes = (2 if init == "mode" else max(8, int(length / 30))) if modes is None else int(modes)
    setup = DnsSetup(
        theta=float(theta),
        nu0=float(nu0),
        length=float(length),
        time=float(time) if time is not None else 2.0 * period,
        n=int(n) if n is not None else int(mode.n),
        modes=modes,
        dt=float(dt) if dt is not None else period / 100.0,
        init=str(init),
        amplitude=float(amplitude),
        seed=int(seed),
        model=model,
        relax=bool(relax),
        frame=float(frame_speed)
        if frame_speed is not None
        else (0.0 if init == "mode" else float(mode.wave_speed)),
        top=str(top),
    )
    _check(setup)
    disc = Discretisation(
        setup.theta, model, setup.length, flow.y_max, setup.n, setup.modes, frame=setup.frame, top=setup.top
    )
    stepper = Stepper(disc, settings)
    ck_path = _checkpoint_path(out, checkpoint)
    key = setup.key()
    n_steps = int(math.ceil(setup.time / setup.dt - 1e-9))
    snap_steps = sorted({int(round(i * n_steps / max(snapshots - 1, 1))) for i in range(max(snapshots, 1))})

    rec_t: list[float] = []
    rec_rho: list[np.ndarray] = []
    rec_Q: list[np.ndarray] = []
    snaps_t: list[float] = []
    snaps: list[np.ndarray] = []
    newton_its: list[int] = []
    wall0 = 0.0
    t, step, dt_now = 0.0, 0, setup.dt
    C_prev_phys = None
    h_prev = setup.dt
    restart_bdf1 = True
    C, Cm, relax_change = _initial(disc, flow, mode, setup, setup.dt, setup.relax)
    C_init = C.copy()
    if Cm is not None:
        C_prev_phys = stepper.physical(Cm)
        restart_bdf1 = False
    if ck_path is not None and ck_path.exists():
        try:
            with np.load(ck_path, allow_pickle=False) as ck:
                if str(ck["key"]) == key:
                    C, C_init = ck["C"], ck["C_init"]
                    C_prev_phys = tuple(ck["prev"]) if ck["prev"].size else None
                    t, step, dt_now = float(ck["t"]), int(ck["step"]), float(ck["dt"])
                    restart_bdf1 = bool(ck["restart"]) or C_prev_phys is None
                    h_prev = float(ck["h_prev"])
                    rec_t = list(ck["rec_t"])
                    rec_rho, rec_Q = list(ck["rec_rho"]), list(ck["rec_Q"])
                    snaps_t, snaps = list(ck["snaps_t"]), list(ck["snaps"])
                    newton_its = list(ck["newton"])
                    wall0 = float(ck["wall"])
        except (OSError, KeyError, ValueError):
            pass

    def record(C):
        rho, Q = disc.depth_integrals(C)
        rec_t.append(t)
        rec_rho.append(rho)
        rec_Q.append(Q)

    def snapshot(C):
        snaps_t.append(t)
        s = np.stack([disc.to_physical(C[i]) for i in range(4)])
        s[0] = np.exp(s[0])
        snaps.append(s)

    if step == 0 and not rec_t:
        record(C)
        snapshot(C)
    status = "ok"
    start = _time.perf_counter()
    last_ck = start
    ok_since_change = 0
    while t < setup.time * (1 - 1e-12):
        h = min(dt_now, setup.time - t)
        now_phys = stepper.physical(C)
        first = restart_bdf1 or C_prev_phys is None
        hist = (now_phys, C_prev_phys if C_prev_phys is not None else now_phys)
        guess = None
        if not first and C_prev_phys is not None:
            # (from the stored level, so that a resumed run takes the same steps)
            C_prev = _coefficients(disc, C_prev_phys)
            # linear extrapolation in time: Newton's starting point
            guess = C + (h / h_prev) * (C - C_prev)
        try:
            C_new, info = stepper.step(C, hist, h, first=first, guess=guess, ratio=h / h_prev)
        except ConvergenceError as exc:
            dt_now *= 0.5
            restart_bdf1 = True
            stepper.reset()
            if dt_now < min_dt_fraction * setup.dt:
                status = f"stopped at t = {t:.6g}: {exc}"
                break
            continue
        if not np.all(np.isfinite(C_new)):
            status = f"stopped at t = {t:.6g}: non-finite fields"
            break
        C_prev_phys, C = now_phys, C_new
        h_prev = h
        restart_bdf1 = False
        t += h
        step += 1
        newton_its.append(info.newton)
        ok_since_change += 1
        if dt_now < setup.dt and ok_since_change >= 20:
            dt_now, ok_since_change = min(2 * dt_now, setup.dt), 0
        if step % record_every == 0 or t >= setup.time * (1 - 1e-12):
            record(C)
        if any(abs(t - s * setup.dt) < 0.5 * setup.dt for s in snap_steps[1:]) and (
            not snaps_t or t - snaps_t[-1] > 0.5 * setup.dt
        ):
            snapshot(C)
        if progress is not None:
            progress(t, setup.time)
        if ck_path is not None and _time.perf_counter() - last_ck > checkpoint_every:
            last_ck = _time.perf_counter()
            _save(
                ck_path,
                dict(
                    key=np.array(key),
                    C=C,
                    C_init=C_init,
                    prev=np.array(C_prev_phys) if C_prev_phys is not None else np.zeros(0),
                    t=t,
                    step=step,
                    dt=dt_now,
                    restart=restart_bdf1,
                    h_prev=h_prev,
                    rec_t=np.array(rec_t),
                    rec_rho=np.array(rec_rho),
                    rec_Q=np.array(rec_Q),
                    snaps_t=np.array(snaps_t),
                    snaps=np.array(snaps),
                    newton=np.array(newton_its, dtype=int),
                    wall=wall0 + _time.perf_counter() - start,
                ),
            )
    wall = wall0 + _time.perf_counter() - start
    if snaps_t and snaps_t[-1] < t - 0.5 * setup.dt:
        snapshot(C)
    ds = _dataset(
        disc, setup, flow, mode, rec_t, rec_rho, rec_Q, snaps_t, snaps, C, C_init, status, wall, newton_its
    )
    ds.attrs["steady_relaxation"] = relax_change
    if out is not None:
        Path(out).parent.mkdir(parents=True, exist_ok=True)
        ds.to_netcdf(out, engine="h5netcdf")
    if ck_path is not None and status == "ok" and ck_path.exists():
        ck_path.unlink()
    return ds


def _dataset(disc, setup, flow, mode, rec_t, rec_rho, rec_Q, snaps_t, snaps, C, C_init, status, wall, newton):
    t = np.asarray(rec_t, dtype=float)
    rho = np.asarray(rec_rho)
    Q = np.asarray(rec_Q)
    x = disc.x
    # mode-1 coefficient of ρ̄(x): amplitude of the wave e^{ikx}
    A = np.fft.rfft(rho, axis=-1)[:, 1] / disc.nxp if disc.nxp > 2 and rho.size else np.zeros(len(t), complex)
    mass = rho.mean(axis=-1) * setup.length if rho.size else np.zeros(0)
    k = 2.0 * math.pi / setup.length
    # linear phase: the records while the wave is below 1e-3 of the mean ρ̄ (all, from a mode)
    if setup.init == "mode":
        lin = np.arange(len(t)) >= 1
    else:
        rel = np.abs(A) / (rho.mean(axis=-1) + 1e-300)
        lin = (t >= 0.2 * t[-1] if len(t) else np.zeros(0, bool)) & (rel < 1e-3)
    meas = measure_mode(t[lin], A[lin], k)
    # back to the lab frame: a phase e^{ik(ξ − c' t)} with ξ = x − c t travels at c + c'
    meas["phase_velocity"] += setup.frame
    alpha_dns = complex(math.nan, math.nan)
    if setup.init == "mode" and lin.sum() > 2 and np.all(np.abs(A[lin]) > 0):
        dts = np.diff(t[lin])
        G = A[lin][1:] / A[lin][:-1]
        same = np.abs(dts - setup.dt) < 1e-9 * setup.dt
        if same.any():
            gm = np.exp(np.mean(np.log(G[same])))
            alpha_dns = bdf2_eigenvalue(gm, setup.dt) - 1j * k * setup.frame
    mass_drift = float(np.max(np.abs(mass - mass[0])) / mass[0]) if mass.size else math.nan
    change = float(np.max(np.abs(C[:, :, 0] - C_init[:, :, 0])))
    sn = np.asarray(snaps) if snaps else np.zeros((0, 4, disc.n + 1, disc.nxp))
    attrs = {
        "theta": setup.theta,
        "nu0": setup.nu0,
        "length": setup.length,
        "k": k,
        "ny": setup.n,
        "nx": 2 * setup.modes + 1,
        "modes": setup.modes,
        "nx_padded": disc.nxp,
        "dt": setup.dt,
        "time_end": float(t[-1]) if len(t) else 0.0,
        "init": setup.init,
        "amplitude": setup.amplitude,
        "seed": setup.seed,
        "frame_speed": setup.frame,
        "top": setup.top,
        "y_max": flow.y_max,
        "growth_rate": meas["growth_rate"],
        "phase_velocity": meas["phase_velocity"],
        "alpha_re": float(mode.alpha.real),
        "alpha_im": float(mode.alpha.imag),
        "alpha_n": int(mode.n),
        "alpha_dns_re": float(alpha_dns.real),
        "alpha_dns_im": float(alpha_dns.imag),
        "mass_drift": mass_drift,
        "mean_flow_change": change,
        "status": status,
        "steps": len(newton),
        "newton_mean": float(np.mean(newton)) if newton else 0.0,
        "wall_time": float(wall),
        "time_per_step": float(wall / max(len(newton), 1)),
        # dQ0/dρ̄0 of the steady family at fixed θ (eq. (B 6), the k → 0 limit of the phase
        # velocity) — not the eigenmode's phase velocity at k = 2π/L, which is stored apart
        "kinematic_wave_speed": float(steady_tangent(flow)["dQ_drho"]),
        "mode_phase_velocity": float(mode.wave_speed),
        "rho_bar0": flow.rho_bar,
        "Q0": flow.Q,
        **{f"model_{k_}": v for k_, v in setup.model.attrs().items()},
    }
    return xr.Dataset(
        {
            "rho_bar": (("time", "x"), rho, {"long_name": "ρ̄ = ∫ν dy (with the isothermal tail)"}),
            "Q": (("time", "x"), Q, {"long_name": "Q = ∫νu dy"}),
            "mass": (("time",), mass, {"long_name": "∫∫ν dy dx"}),
            "amplitude_re": (("time",), A.real, {"long_name": "Re of the k = 2π/L coefficient of ρ̄"}),
            "amplitude_im": (("time",), A.imag, {"long_name": "Im of the k = 2π/L coefficient of ρ̄"}),
            "nu": (("snapshot_time", "y", "x"), sn[:, 0] if len(sn) else sn.reshape(0, disc.n + 1, disc.nxp)),
            "u": (("snapshot_time", "y", "x"), sn[:, 1] if len(sn) else sn.reshape(0, disc.n + 1, disc.nxp)),
            "v": (("snapshot_time", "y", "x"), sn[:, 2] if len(sn) else sn.reshape(0, disc.n + 1, disc.nxp)),
            "T": (("snapshot_time", "y", "x"), sn[:, 3] if len(sn) else sn.reshape(0, disc.n + 1, disc.nxp)),
        },
        coords={
            "time": t,
            "x": ("x", x, {"long_name": f"ξ = x − {setup.frame:g} t (the frame of the run)"}),
            "y": disc.grid.y,
            "snapshot_time": np.asarray(snaps_t, dtype=float),
        },
        attrs=attrs,
    )


def summary(ds: xr.Dataset) -> dict:
    """JSON-ready scalars of a run (what ``chuteflow dns --json`` prints)."""
    keys = (
        "theta",
        "nu0",
        "length",
        "k",
        "nx",
        "ny",
        "dt",
        "time_end",
        "init",
        "amplitude",
        "frame_speed",
        "growth_rate",
        "phase_velocity",
        "alpha_re",
        "alpha_im",
        "alpha_dns_re",
        "alpha_dns_im",
        "kinematic_wave_speed",
        "mode_phase_velocity",
        "mass_drift",
        "mean_flow_change",
        "steady_relaxation",
        "steps",
        "newton_mean",
        "time_per_step",
        "wall_time",
        "status",
    )
    out: dict = {}
    for k_ in keys:
        v = ds.attrs.get(k_)
        if isinstance(v, np.generic):
            v = v.item()
        out[k_] = v
    ar, ai = float(out["alpha_re"]), float(out["alpha_im"])
    c_mode = -ai / float(out["k"])
    out["growth_rate_error"] = abs(out["growth_rate"] - ar) / abs(ar) if ar else math.nan
    out["phase_velocity_error"] = abs(out["phase_velocity"] - c_mode) / abs(c_mode) if c_mode else math.nan
    return out

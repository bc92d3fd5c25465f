"""Tests of the mapped x coordinate (:mod:`chuteflow.dns.xmap`, :class:`Discretisation` with
``x_map``; docs/dns.md, *A grid that follows the front*).

References: the map's analytic inverse and derivatives against finite differences; the
chain rule against analytic x-derivatives of band-limited fields; |∂_x| against its symbol on
a fine uniform grid (the Möbius invariance the mapped top rows rely on); the mass and one
implicit step against the uniform discretisation of the same physical state (an independent
discretisation of the same equations).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from chuteflow.closures import ChuteModel
from chuteflow.dns import Discretisation, NewtonSettings, Stepper
from chuteflow.dns.xmap import TanMap
from chuteflow.errors import ParameterError
from chuteflow.spectral import fourier_evaluate as _evaluate
from chuteflow.steady import solve_steady

MODEL = ChuteModel(roughness=0.05)
L = 1000.0


@pytest.fixture(scope="module")
def p1():
    return solve_steady(16.0, 0.05, MODEL)


def test_fourier_evaluate_is_the_series_at_any_point():
    """spectral.fourier_evaluate (the series at arbitrary points, used to put a state on a
    mapped grid) against the analytic sum of two modes."""
    C = np.zeros((2, 5), complex)
    C[0, 0], C[0, 1], C[1, 3] = 0.5, 0.25 - 0.1j, 0.2j
    x = np.random.default_rng(0).uniform(-L, 2 * L, 37)
    k = 2 * math.pi / L
    ref0 = 0.5 + 0.5 * np.cos(k * x) + 0.2 * np.sin(k * x)
    ref1 = -0.4 * np.sin(3 * k * x)
    got = _evaluate(C, x, L)
    assert np.abs(got[0] - ref0).max() < 1e-13
    assert np.abs(got[1] - ref1).max() < 1e-13


def test_the_map_inverts_and_differentiates():
    m = TanMap(centre=300.0, beta=0.25, length=L)
    s = np.linspace(-1500.0, 2500.0, 4001)
    x = m.x(s)
    assert np.all(np.diff(x) > 0)
    assert np.abs(m.s(x) - s).max() < 1e-9
    assert np.abs(m.x(s + L) - (x + L)).max() < 1e-9
    h = 1e-3
    assert np.abs((m.x(s + h) - m.x(s - h)) / (2 * h) - m.dx_ds(s)).max() < 1e-6
    assert np.abs((m.dx_ds(s + h) - m.dx_ds(s - h)) / (2 * h) - m.d2x_ds2(s)).max() < 1e-8
    assert m.dx_ds(np.array([300.0]))[0] == pytest.approx(0.25)
    assert m.dx_ds(np.array([800.0]))[0] == pytest.approx(4.0)
    # β = 1 is the identity
    assert np.abs(TanMap(300.0, 1.0, L).x(s) - s).max() < 1e-9


@pytest.mark.parametrize(
    ("kw", "name"),
    [
        ({"beta": 0.0}, "beta"),
        ({"beta": 1.5}, "beta"),
        ({"length": -1.0}, "length"),
        ({"centre": math.nan}, "centre"),
    ],
)
def test_a_bad_map_is_refused(kw, name):
    args = {"centre": 0.0, "beta": 0.5, "length": L, **kw}
    with pytest.raises(ParameterError, match=name):
        TanMap(**args)


def _fields(x, y, y_max):
    """Band-limited fields s, u, v, T of x (modes 1 and 3 of L) times smooth profiles in y."""
    k = 2 * math.pi / L
    X, Y = np.meshgrid(x, y / y_max)
    return {
        "s": -3.0 + Y + 0.2 * Y * np.cos(k * X + 0.3) + 0.05 * np.sin(3 * k * X),
        "u": 10 * Y + Y**2 * np.sin(k * X),
        "v": 0.1 * Y * (1 - Y) * np.cos(3 * k * X + 1.0),
        "T": 2.0 + Y + 0.3 * np.cos(k * X) * Y,
    }


def test_mapped_jets_are_the_x_derivatives(p1):
    """The chain rule (∂_x = a ∂_s, ∂_xx = a² ∂_ss − (g''/g'³) ∂_s) at the mapped points:
    the jets of fields sampled at x = g(s) equal their x-derivatives, from the uniform modes
    of the same band-limited fields (exact: modes ≤ 3 of M = 8) evaluated there. β = 0.5 and
    M = 48 resolve the mapped fields to ≈ 1e-12 (M = 24: 1e-6, M = 32: 4e-9)."""
    d = Discretisation(16.0, MODEL, L, p1.y_max, 12, 48, x_map=TanMap(250.0, 0.5, L))
    du = Discretisation(16.0, MODEL, L, p1.y_max, 12, 8)
    C = d.coefficients_of(_fields(d.x, d.grid.y, d.y_max))
    jets = d.primitive_jets(C)
    Cu = du.coefficients_of(_fields(du.x, du.grid.y, du.y_max))
    ik = 1j * du.k
    for i, f in enumerate(("s", "u", "v", "T")):
        for sfx, b in (("", 0), ("_x", 1), ("_xx", 2)):
            ref = _evaluate(Cu[i] * ik**b, d.x, L)
            assert np.abs(jets[f + sfx] - ref).max() < 1e-10 * np.abs(Cu[i]).max() * du.k[3] ** b
        ref = d.grid.D @ _evaluate(Cu[i] * ik, d.x, L)
        assert np.abs(jets[f + "_xy"] - ref).max() < 1e-10 * np.abs(d.grid.D @ Cu[i]).max() * du.k[3]


@pytest.mark.parametrize("beta", [1.0, 0.5, 0.2])
def test_abs_dx_on_a_mapped_grid_is_the_symbol_in_x(p1, beta):
    """|∂_x| f = (1/g') |∂_s| (f∘g): the Hilbert transform is invariant under the tan map (a
    Möbius map of the circle). Reference: |k| on the uniform x modes of f, evaluated at the
    mapped points."""
    d = Discretisation(16.0, MODEL, L, p1.y_max, 4, 96, x_map=TanMap(600.0, beta, L))
    k = 2 * math.pi / L
    f = np.cos(k * d.x + 0.3) + 0.5 * np.sin(3 * k * d.x) - 0.2 * np.cos(5 * k * d.x)
    ref = k * np.cos(k * d.x + 0.3) + 1.5 * k * np.sin(3 * k * d.x) - k * np.cos(5 * k * d.x)
    got = d.to_physical(d.abs_dx(d.to_modes(f)))
    assert np.abs(got - ref).max() < 1e-9 * np.abs(ref).max()


def test_mapped_mass_is_the_uniform_mass(p1):
    """The mass ⟨∫ν dy⟩ + tail of the same physical state on the uniform and mapped grids."""
    du = Discretisation(16.0, MODEL, L, p1.y_max, 12, 8)
    dm = Discretisation(16.0, MODEL, L, p1.y_max, 12, 48, x_map=TanMap(250.0, 0.4, L))
    masses = []
    for d in (du, dm):
        fl = _fields(d.x, d.grid.y, d.y_max)
        masses.append(d.total_mass(np.exp(fl["s"]), fl["T"][-1]))
    assert masses[1] == pytest.approx(masses[0], rel=1e-12)


def _step(d, C, atol):
    st = Stepper(d, NewtonSettings(preconditioner="mean", max_iter=30, atol=atol))
    hist = (st.physical(C), st.physical(C))
    return st.step(C, hist, 8.0, first=True)[0]


def test_a_mapped_step_is_the_uniform_step(p1):
    """One implicit step (BDF1, Δt = 8, the x-mean preconditioner, Newton to 1e-13) from the
    steady flow with a ±1 % density wave (modes 1 and 2, L = 1000): the mapped discretisation
    (β = 0.5, M = 48) and the uniform one (M = 12) give the same physical state at the mapped
    points and the same mass. The whole residual is in this: the chain rule, the pointwise
    rows, the g'-weighted mass rows with their source λ g' ν̄ (ν̄ from the x-average of ln ν)
    and the top conditions' |∂_x|. Measured 4.4e-12; with |∂_s| in the top rows instead of
    (1/g')|∂_s| 2.6e-3, with the source λ in mode 0 only 2.8e-7, with ν̄ from the s-average
    2.1e-10. The isothermal top: the default ``"transport"`` top switches its density
    gradient where v(y_max) changes sign, which is not smooth in x — there the uniform grids
    of M = 12 and 48 themselves differ by 1.3e-7 at the top node."""
    kw = {"frame": 7.8, "top": "isothermal"}
    du = Discretisation(16.0, MODEL, L, p1.y_max, 24, 12, **kw)
    dm = Discretisation(16.0, MODEL, L, p1.y_max, 24, 48, x_map=TanMap(250.0, 0.5, L), **kw)
    prof = p1.profiles(du.grid.y)
    Cu = np.zeros(du.shape, complex)
    Cu[0, :, 0], Cu[1, :, 0], Cu[3, :, 0] = np.log(prof["nu"]), prof["u"], prof["T"]
    Cu[0, :, 1] += 0.01 * (1 + 0.5j)
    Cu[0, :, 2] += 0.003 * (0.2 - 1j)
    Cu[2, 1:, 1] += 1e-3 * du.grid.y[1:] / du.y_max
    Cu1 = _step(du, Cu, 1e-13)
    Cm1 = _step(dm, dm.to_modes(_evaluate(Cu, dm.x, L)), 1e-13)
    assert np.abs(Cu1[0, :, 1:] - Cu[0, :, 1:]).max() > 1e-4  # the step changed the wave
    diff = np.abs(_evaluate(Cu1, dm.x, L) - dm.to_physical(Cm1)).max()
    assert diff < 1e-10
    masses = []
    for d, C in ((du, Cu1), (dm, Cm1)):
        nu, _, _, T = Stepper(d).physical(C)
        masses.append(d.total_mass(nu, T[-1]))
    assert masses[1] == pytest.approx(masses[0], rel=1e-12)


def test_the_preconditioners_jacobian_on_a_mapped_grid(p1):
    """The coefficients the preconditioners are built of (:func:`jet_coefficients`, converted
    to the s-jets and the g'-weighted mass rows on a mapped grid): the mode-coupled matrix
    with every harmonic (reach 2M, x-derivatives exact) is the Jacobian of the residual —
    central differences of :meth:`Discretisation.residual` along a perturbation of modes
    1 … 3 at a ±5 % wave, β = 0.5 — the top rows of u, v, T included ((1/g')|∂_s|, whose
    1/g' is a first harmonic of s: its mean in the diagonal blocks, â_±1 in the
    neighbouring ones) — except the mass source λ (left out by every preconditioner): the
    interior mass rows differ by dλ times the modes of g' only. Measured 1.5e-7 and 4.7e-7
    of the largest entry (the one-sided differences of the coefficients: 1.5e-7 and 5.1e-7
    at β = 1); without the conversion to s-jets 0.11 and 0.53; with the top rows' 1/g'
    kept to its mean 2.6e-4."""
    from chuteflow.dns.columns import jet_coefficients
    from chuteflow.dns.coupled import coupled_matrix
    from chuteflow.dns.discretisation import BDF2

    dm = Discretisation(16.0, MODEL, L, p1.y_max, 16, 8, frame=7.8, x_map=TanMap(250.0, 0.5, L))
    du = Discretisation(16.0, MODEL, L, p1.y_max, 16, 4, frame=7.8)
    prof = p1.profiles(du.grid.y)
    Cu = np.zeros(du.shape, complex)
    Cu[0, :, 0], Cu[1, :, 0], Cu[3, :, 0] = np.log(prof["nu"]), prof["u"], prof["T"]
    Cu[0, :, 1] += 0.05 * (1 + 0.5j)
    Cu[2, 1:, 1] += 5e-3 * du.grid.y[1:] / du.y_max
    C = dm.to_modes(_evaluate(Cu, dm.x, L))
    st = Stepper(dm)
    hist = (st.physical(C), st.physical(C))
    dt, M, m = 4.0, dm.modes, dm.n + 1
    J = coupled_matrix(dm, jet_coefficients(dm, C, hist, dt, BDF2), 2 * M)
    rng = np.random.default_rng(3)
    delta = np.zeros(dm.shape, complex)
    for q in (1, 2, 3):
        delta[..., q] = (rng.normal(size=(4, m)) + 1j * rng.normal(size=(4, m))) / q**2
    # no change of ν̄ = exp(⟨s⟩_x), which the mass rows are divided by and the coefficients
    # hold fixed (its derivative is proportional to the residual of the state)
    delta[0, :, 0] = -dm.x_mean(dm.to_physical(delta[0]))
    full = np.concatenate([np.conj(delta[..., :0:-1]), delta], axis=-1)  # m = −M … M
    Jd = (J @ np.ascontiguousarray(full.transpose(2, 0, 1)).ravel()).reshape(2 * M + 1, 4, m)
    Jd = Jd.transpose(1, 2, 0)[..., M:]
    eps = 1e-6
    plus, minus = (dm.residual(C + e * delta, hist, dt, BDF2) for e in (eps, -eps))
    fd = (plus - minus) / (2 * eps)
    keep = np.ones(dm.shape, bool)
    keep[0, 1:-1] = False  # the interior mass rows: below
    scale = np.abs(fd[keep]).max()
    assert np.abs(Jd - fd)[keep].max() < 1e-5 * scale
    # the interior mass rows differ by the derivative of λ times the modes of g' only
    gmodes = dm.x_weight_modes
    E = (fd - Jd)[0, 1:-1]
    c = np.vdot(np.broadcast_to(gmodes, E.shape), E) / (E.shape[0] * np.vdot(gmodes, gmodes))
    assert np.abs(E - c * gmodes).max() < 1e-5 * np.abs(fd[0, 1:-1]).max()


def test_a_map_of_another_period_is_refused(p1):
    with pytest.raises(
        ParameterError, match="x_map: its period 500 must be the discretisation's length 1000"
    ):
        Discretisation(16.0, MODEL, L, p1.y_max, 8, 4, x_map=TanMap(0.0, 0.5, 500.0))

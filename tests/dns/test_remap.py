"""A run whose x grid follows its front (DnsSimulation(x_map=True), chuteflow.dns.remap).

Reference numbers: a Poisson-kernel pulse δ ln ν = A((1 − r²)/(1 − 2r cos(2π(x − 300)/L) + r²) − 1)
(r = 0.85, L = 1000, on P1's flow) whose steepest point x = 285.07 and spectrum r^m are known
in closed form: at M = 48 it is resolved to a tail of 1.0e-3 on the uniform grid, and a tan
map centred at its front carries it to 1.6e-5 (measured 2026-12-07; the bounds below leave a
factor 2–4). Exactness of the re-representation against band-limited functions (round-off);
resume after a pause against the uninterrupted run (1e-13, the driver's other resume tests).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from chuteflow.closures import ChuteModel
from chuteflow.dns import Discretisation, DnsSimulation, simulate, summary
from chuteflow.dns.diagnostics import fourier_tail
from chuteflow.dns.remap import REMAP_GAIN, best_grid, front_position, lost_fraction, remap_coefficients
from chuteflow.dns.xmap import TanMap
from chuteflow.spectral import fourier_evaluate
from chuteflow.steady import solve_steady
from chuteflow.trackers import Tracker

MODEL = ChuteModel(roughness=0.05)
L = 1000.0
R = 0.85
PULSE_AT = 300.0


@pytest.fixture(scope="module")
def p1():
    return solve_steady(16.0, 0.05, MODEL)


def pulse(x):
    c = np.cos(2 * math.pi * (np.asarray(x) - PULSE_AT) / L)
    return 0.01 * ((1 - R * R) / (1 - 2 * R * c + R * R) - 1) / ((1 + R) / (1 - R))


def steepest_point() -> float:
    x = np.linspace(0.0, L, 200001)
    return float(x[np.argmax(np.abs(np.gradient(pulse(x), x)))])


def pulse_run(p1, modes=48, **kw):
    """The pulse after one step (Δt 4) on a uniform grid of ``modes`` modes."""
    sim = DnsSimulation(p1, L, time=4.0, dt=4.0, n=24, modes=modes, initial=pulse, x_map=True, **kw)
    return sim, sim.run()


def test_remap_is_exact_for_a_resolved_function(p1):
    """A band-limited state (M = 8, random coefficients) onto a mapped grid (β = 0.5, M = 64:
    the composition's spectrum decays as ((1 − β)/(1 + β))^m = 3^−m) and back: the same
    coefficients to round-off (measured 1.3e-14), nothing beyond the mapped grid's M."""
    rng = np.random.default_rng(1)
    C = rng.standard_normal((4, 9, 9)) + 1j * rng.standard_normal((4, 9, 9))
    C[..., 0] = C[..., 0].real
    du = Discretisation(16.0, MODEL, L, p1.y_max, 8, 8)
    dm = Discretisation(16.0, MODEL, L, p1.y_max, 8, 64, x_map=TanMap(300.0, 0.5, L))
    Cm = remap_coefficients(C, du, dm)
    assert Cm.shape == (4, 9, 65)
    np.testing.assert_allclose(remap_coefficients(Cm, dm, du), C, rtol=0, atol=1e-12)
    assert fourier_tail(Cm) < 1e-14
    # the mapped series is the same function: at the mapped points, the uniform one's values
    np.testing.assert_allclose(dm.to_physical(Cm), fourier_evaluate(C, dm.x, L), rtol=0, atol=1e-12)


def test_lost_fraction_sees_what_a_grid_cannot_carry():
    """lost_fraction: the largest mode beyond M over the largest of all (0 where none)."""
    S = np.zeros((1, 2, 9), complex)
    S[0, 0, 1], S[0, 1, 6] = 1.0, 0.25
    assert lost_fraction(S, 8) == 0.0
    assert lost_fraction(S, 5) == 0.25
    assert lost_fraction(S, 6) == 0.0


def test_the_front_is_the_steepest_point(p1):
    """front_position: the padded grid's point of steepest ln ν, within one spacing (1000/150)
    of the pulse's analytic 285.07; the same on a mapped grid (there within its finer spacing)."""
    sim, st = pulse_run(p1)
    x0 = steepest_point()
    assert abs(x0 - 285.07) < 0.01
    assert abs(front_position(sim.disc, st.C) - x0) <= L / sim.disc.nxp
    sim.refine(st)
    d = sim.disc
    assert d.x_map is not None
    spacing = L / d.nxp * d.x_map.beta * 1.2  # (g' ≈ β at the front)
    assert abs(front_position(d, st.C) - x0) <= spacing


def test_a_front_goes_to_a_map_at_the_same_modes(p1):
    """best_grid on the pulse resolved at M = 48 (tail 1.0e-3): a map at the same modes,
    β = 0.25, centred at the front, tail 1.6e-5 (at least REMAP_GAIN times lower); the state
    there is the same function to 5.4e-5 of the wave (the new tail's size: what the uniform
    grid itself missed)."""
    sim, st = pulse_run(p1)
    old, C = sim.disc, st.C.copy()
    tail0 = fourier_tail(C)
    assert 5e-4 < tail0 < 2e-3
    ch = best_grid(old, C, max_modes=48)
    assert ch is not None
    assert (ch.modes, ch.beta) == (48, 0.25)
    assert abs(ch.centre - steepest_point()) <= L / old.nxp
    assert ch.tail * REMAP_GAIN <= tail0
    assert ch.tail < 4e-5
    back = fourier_evaluate(ch.C, ch.x_map.s(old.s), L)
    orig = old.to_physical(C)
    wave = np.abs(orig - orig.mean(axis=-1, keepdims=True)).max(axis=(1, 2))
    err = np.abs(back - orig).max(axis=(1, 2)) / wave
    assert err.max() < 1.5e-4


def test_a_smooth_wave_stays_uniform(p1):
    """P1's mode at 1 % (M = 4): no map lowers its tail REMAP_GAIN times at M = 4, so at the
    most modes nothing is left to refine; with room, the best grid is the uniform one doubled."""
    sim = DnsSimulation(p1, L, time=4.0, dt=4.0, n=24, modes=4, init="mode", amplitude=0.01, x_map=True)
    st = sim.run()
    sim.resolution(st.C)
    assert fourier_tail(st.C) > 1e-3
    assert best_grid(sim.disc, st.C, 4) is None
    assert not sim.can_refine("x")
    ch = best_grid(sim.disc, st.C, 8)
    assert (ch.modes, ch.x_map) == (8, None)


def test_the_modes_grow_by_half(p1):
    """Where no map at the run's modes helps (a resolved sinusoid at M = 16), the next grid
    has half as many modes again (24, to a multiple of 8), not twice (32): the doubling had
    taken P1's x tail at L = 2000 to 1.7e-7 on a costly 193-point grid; capped by max_modes."""
    sim = DnsSimulation(p1, L, time=4.0, dt=4.0, n=16, modes=16, init="mode", amplitude=0.01, x_map=True)
    st = sim.run()
    ch = best_grid(sim.disc, st.C, 64)
    assert (ch.modes, ch.x_map) == (24, None)
    assert ch.tail < 1e-10  # (the band-limited state, carried whole)
    assert best_grid(sim.disc, st.C, 20).modes == 20


def test_refine_to_a_map_keeps_the_mass_and_the_records(p1):
    """refine() with x_map: the state and its history level on the mapped grid, the total
    mass of both kept to round-off (a uniform shift of ln ν, as for the uniform refinement),
    the records on the uniform x grid of nxp points, the map in the state and its records;
    the refined run goes on and conserves the mass to 1e-13; the dataset says where it
    mapped and stays on the uniform x."""
    sim, st = pulse_run(p1)
    old = sim.disc
    mass = [old.total_mass(*sim._mass_fields(sim.stepper, st.C))]
    mass.append(old.total_mass(st.prev[0], st.prev[3][-1]))
    sim.refine(st)
    d = sim.disc
    assert d.modes == 48
    assert d.x_map is not None
    assert st.x_map == (d.x_map.centre, d.x_map.beta)
    assert abs(d.total_mass(*sim._mass_fields(sim.stepper, st.C)) / mass[0] - 1) < 1e-14
    assert abs(d.total_mass(st.prev[0], st.prev[3][-1]) / mass[1] - 1) < 1e-14
    assert st.records["refine_beta"] == [0.25]
    from dataclasses import replace

    sim.setup = replace(sim.setup, time=24.0)
    st.status = "running"
    st = sim.run(state=st)
    ds = sim.dataset(st)
    a = ds.attrs
    assert a["status"] == "ok"
    assert a["mass_drift"] < 1e-13
    assert a["refined_at"] == f"t = 4 (x mapped, β 0.25 at ξ = {d.x_map.centre:.5g})"
    assert (a["x_map"], a["x_map_beta"], a["x_map_centre"]) == (1, 0.25, d.x_map.centre)
    np.testing.assert_allclose(ds["x"].values, np.arange(d.nxp) * L / d.nxp)
    assert ds["rho_bar"].shape[1] == ds["nu"].shape[2] == d.nxp
    # the records: ρ̄ of the mapped state, evaluated at the uniform points
    rho = d.depth_integrals(st.C)[0]
    at = fourier_evaluate(d.to_modes(rho), d.x_map.s(ds["x"].values), L)
    np.testing.assert_allclose(ds["rho_bar"].values[-1], at, rtol=1e-8)
    s = summary(ds)
    assert (s["x_map_beta"], s["x_map_centre"]) == (0.25, d.x_map.centre)


class _At(Tracker):
    """Return ``what`` after step ``at`` (None: never)."""

    def __init__(self, at, what):
        self.at, self.what = at, what

    def handle(self, sim, step):
        return self.what if step.number == self.at else None


def test_a_mapped_run_resumes_exactly(tmp_path, p1):
    """The map is part of the checkpoint: mapped after step 1 and paused after step 3, the same
    call continues on the mapped grid and ends as the uninterrupted run (to 1e-13)."""
    kw = dict(time=24.0, dt=4.0, n=24, modes=48, initial=pulse, x_map=True, resolution_tol=0.5)
    ref = simulate(p1, L, trackers=[_At(1, "refine x"), _At(None, "")], **kw)
    ck = tmp_path / "run.ck.npz"
    first = simulate(p1, L, checkpoint=ck, trackers=[_At(1, "refine x"), _At(3, "paused at 3")], **kw)
    assert first.attrs["status"] == "paused at 3"
    assert first.attrs["x_map_beta"] == 0.25
    ds = simulate(p1, L, checkpoint=ck, trackers=[_At(1, "refine x"), _At(None, "")], **kw)
    assert ds.attrs["status"] == "ok"
    assert ds.attrs["refined_at"] == ref.attrs["refined_at"]
    assert ds.attrs["x_map_centre"] == ref.attrs["x_map_centre"]
    np.testing.assert_allclose(ds["rho_bar"].values, ref["rho_bar"].values, rtol=0, atol=1e-13)
    assert ds.attrs["mass_drift"] < 1e-13

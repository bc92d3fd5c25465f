"""The simulation driver (DnsSimulation, DnsState), the shared trackers and the wave measures.

Reference numbers: synthetic waves whose amplitude, speed and wavelength are known in closed
form (wave_measures, resolution_tails); the driver against :func:`chuteflow.dns.simulate`
(the same run must give the same numbers bit for bit); resume after SIGKILL against the
uninterrupted run (to 1e-13, the tolerance of the existing checkpoint test).
"""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
import textwrap
import time
import warnings
from pathlib import Path

import numpy as np
import pytest

from chuteflow.closures import ChuteModel
from chuteflow.dns import Discretisation, DnsSimulation, DnsState, resolution_tails, simulate, summary
from chuteflow.errors import ParameterError
from chuteflow.steady import solve_steady
from chuteflow.trackers import (
    ProgressTracker,
    ResolutionMonitor,
    ResolutionWarning,
    SaturationStop,
    SnapshotTracker,
    Tracker,
    run_tail,
    wave_measures,
)

MODEL = ChuteModel(roughness=0.05)
SMALL = dict(time=40.0, dt=4.0, modes=2, init="noise", amplitude=1e-4, n=24)


@pytest.fixture(scope="module")
def p1():
    return solve_steady(16.0, 0.05, MODEL)


def _wave(t, x, L, c, amp, m=1):
    return 1.0 + amp[:, None] * np.cos(2 * math.pi * m * (x[None, :] - c * t[:, None]) / L)


def test_wave_measures_of_a_travelling_wave():
    """A wave ρ̄ = 1 + a(t) cos(2π(x − ct)/L) whose amplitude settles at t = 60: every measure
    in closed form (speed c exactly, min/max −a/+a, wavelength L)."""
    L, c = 500.0, 3.7
    t = np.linspace(0.0, 200.0, 401)
    x = np.arange(64) * L / 64
    a = 0.25 * np.minimum(t / 60.0, 1.0) + 1e-6
    rho = _wave(t, x, L, c, a)
    w = wave_measures(t, rho, L, 1.5)  # in a frame moving at 1.5: the lab speed is c + 1.5
    assert w["verdict"] == "saturated"
    assert w["wave_speed"] == pytest.approx(c + 1.5, rel=1e-9)
    assert w["wavelength"] == pytest.approx(L)
    assert w["rho_min_rel"] == pytest.approx(-0.25, abs=1e-3)
    assert w["rho_max_rel"] == pytest.approx(0.25, abs=1e-3)
    assert w["t_saturation"] == pytest.approx(59.5, abs=1.0)
    # settled over the window (up to the sampling of the moving crest on 64 points: 6e-7)
    assert w["amplitude_growth"] == pytest.approx(0.0, abs=1e-5)
    # still growing (at d ln A/dt = 1/50: the amplitude 2a over the mean 1, up to the crest's
    # sampling: 3e-5), linear, decaying
    grow = wave_measures(t, _wave(t, x, L, c, 1e-3 * np.exp(t / 50)), L, 0.0)
    assert grow["verdict"] == "growing"
    assert grow["amplitude_growth"] == pytest.approx(1 / 50, rel=1e-4)
    assert wave_measures(t, _wave(t, x, L, c, 1e-5 * np.exp(t / 50)), L, 0.0)["verdict"] == "growing"
    assert wave_measures(t, _wave(t, x, L, c, 1e-4 * np.exp(-t / 50)), L, 0.0)["verdict"] == "decaying"
    assert math.isnan(wave_measures(t, _wave(t, x, L, c, 0.1 * np.exp(t / 50)), L, 0.0)["t_saturation"])
    # two waves merging into one: the dominant mode changes at the end
    two = _wave(t, x, L, c, np.full_like(t, 0.2), m=2)
    one = _wave(t, x, L, c, np.full_like(t, 0.2), m=1)
    merge = np.where((t > 180)[:, None], one, two)
    w = wave_measures(t, merge, L, 0.0)
    assert w["verdict"] == "coarsening"
    assert w["wavelength"] == pytest.approx(L)
    # the run's status decides first
    assert wave_measures(t, rho, L, 0.0, status="left_family")["verdict"] == "left_validity"
    bad = "stopped at t = 3: non-finite fields (the flow left the closures' range)"
    assert wave_measures(t, rho, L, 0.0, status=bad)["verdict"] == "left_validity"
    assert wave_measures(t, rho, L, 0.0, status="stopped at t = 3: Newton")["verdict"] == "stopped"


def test_resolution_tails_of_a_known_spectrum(p1):
    """Modes m of amplitude 10^−m: the x tail is 10^−M / 10^−1 (the top eighth is mode M
    alone at M ≤ 15); no wave: 0."""
    d = Discretisation(16.0, MODEL, 1000.0, p1.y_max, 24, 6)
    C = np.zeros(d.shape, complex)
    C[0, :, 0] = np.log(p1.profiles(d.grid.y)["nu"])
    C[3, :, 0] = 1.0
    assert resolution_tails(d, C)["x_tail"] == 0.0
    for m in range(1, 7):
        C[0, :, m] = 10.0**-m
    assert resolution_tails(d, C)["x_tail"] == pytest.approx(1e-5, rel=1e-12)
    # y: a profile with a Chebyshev coefficient 1e-3 of the largest in the top tenth
    C2 = np.zeros(d.shape, complex)
    C2[3, :, 0] = 1.0 + 1e-3 * np.cos(24 * np.arccos(-(2 * d.grid.y / p1.y_max - 1)))
    assert resolution_tails(d, C2)["y_tail"] == pytest.approx(1e-3, rel=1e-9)


def test_driver_is_what_simulate_returns(p1):
    """DnsSimulation(flow, L).run(trackers) and simulate(flow, L) are one run: bit for bit;
    the shared trackers (chuteflow.trackers) see every step."""
    ref = simulate(p1, 1000.0, **SMALL)
    sim = DnsSimulation(p1, 1000.0, **SMALL)
    snaps, seen = SnapshotTracker(count=5), []
    state = sim.run([snaps, ProgressTracker(lambda t, te: seen.append((t, te)))])
    ds = sim.dataset(state)
    assert state.status == "ok"
    assert state.t == pytest.approx(40.0)
    assert np.array_equal(ds["rho_bar"].values, ref["rho_bar"].values)
    assert len(seen) == state.step == 10
    assert {te for _, te in seen} == {40.0}
    assert np.allclose(snaps.times, [0, 10, 20, 30, 40])
    assert np.array_equal(snaps.states[-1], state.C)

    # a user tracker may stop the run; the data so far is the result
    class Stop(Tracker):
        def handle(self, sim, step):
            return "enough" if step.t >= 20 else None

    st = DnsSimulation(p1, 1000.0, **SMALL).run([Stop()])
    assert st.status == "enough"
    assert st.t == pytest.approx(20.0)


def test_saturation_stop_and_resolution_monitor(p1):
    """SaturationStop samples sim.wave_amplitude at its times (the run, 40 time units of a
    wave of 1e-4 at P1, is far too short to settle, so it ends at its time); the monitor
    warns, or stops the run, when the tails exceed its (here absurdly tight) tolerance."""
    sim = DnsSimulation(p1, 1000.0, **SMALL)
    stop = SaturationStop(count=11)
    mon = ResolutionMonitor(1e-12, every=1)
    with pytest.warns(ResolutionWarning, match="highest x modes"):
        state = sim.run([stop, mon])
    assert len(stop.amplitudes) == 11
    assert stop.amplitudes[-1] == pytest.approx(sim.wave_amplitude(state.C), rel=1e-12)
    assert mon.x_tail > 1e-12
    st = DnsSimulation(p1, 1000.0, **SMALL).run([ResolutionMonitor(1e-12, action="stop", every=1)])
    assert st.status == "under-resolved"


def test_state_saves_and_loads_itself(tmp_path, p1):
    sim = DnsSimulation(p1, 1000.0, **SMALL)
    st = sim.initial_state()
    snaps = SnapshotTracker(count=3)
    snaps.initialize(sim, st, 40.0)
    st.save(tmp_path / "s.npz", sim.key(), [snaps])
    other = SnapshotTracker(count=3)
    back = DnsState.load(tmp_path / "s.npz", sim.key(), [other])
    assert back is not None
    assert np.array_equal(back.C, st.C)
    assert back.amplitude == st.amplitude
    assert len(other.states) == 1
    assert np.array_equal(other.states[0], st.C)
    assert DnsState.load(tmp_path / "s.npz", "another-run") is None
    assert DnsState.load(tmp_path / "absent.npz", sim.key()) is None


_CHILD = """
import os, sys
sys.path.insert(0, {src!r})
os.environ["OMP_NUM_THREADS"] = "1"
from chuteflow.closures import ChuteModel
from chuteflow.dns import simulate
from chuteflow.steady import solve_steady
flow = solve_steady(16.0, 0.05, ChuteModel(roughness=0.05))
simulate(flow, 1000.0, checkpoint={ck!r}, checkpoint_every=0.0, **{kw!r})
"""


def test_resume_after_sigkill_is_exact(tmp_path, p1):
    """A run killed with SIGKILL after a checkpoint continues, with the same call, to the
    uninterrupted run's result (to 1e-13: the stepper's preconditioner is rebuilt)."""
    kw = dict(SMALL, time=400.0)
    ref = simulate(p1, 1000.0, **kw)
    ck = tmp_path / "run.ck.npz"
    src = str(Path(__file__).resolve().parents[2] / "src")
    code = textwrap.dedent(_CHILD.format(src=src, ck=str(ck), kw=kw))
    proc = subprocess.Popen([sys.executable, "-c", code], start_new_session=True)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        if ck.exists():
            with np.load(ck) as z:
                if z["scalars"][1] >= 20:  # some steps done, far from the 100 of the run
                    break
        time.sleep(0.05)
    if proc.poll() is not None:
        pytest.skip("the child finished before it could be killed (machine too fast)")
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    assert proc.returncode == -signal.SIGKILL
    ds = simulate(p1, 1000.0, checkpoint=ck, **kw)
    assert not ck.exists()
    assert np.array_equal(ds["time"].values, ref["time"].values)
    assert np.allclose(ds["rho_bar"].values, ref["rho_bar"].values, rtol=0, atol=1e-13)


def test_wall_limit_pauses_and_the_same_call_continues(tmp_path, p1):
    """simulate(..., wall_limit=) pauses after that much wall time (here after every step),
    keeps the checkpoint and judges the wave so far; the same call again continues, and the
    pieces give the uninterrupted run (to 1e-13, as the SIGKILL resume: the preconditioner is
    rebuilt at each piece)."""
    ref = simulate(p1, 1000.0, **SMALL)
    ck = tmp_path / "run.ck.npz"
    pieces = []
    for _ in range(20):
        ds = simulate(p1, 1000.0, checkpoint=ck, wall_limit=1e-9, **SMALL)
        pieces.append(str(ds.attrs["status"]))
        if not pieces[-1].startswith("paused"):
            break
        assert ck.exists()
        assert ds.attrs["verdict"] in ("growing", "decaying")  # judged, not "stopped"
    assert pieces[0].startswith("paused at t = 4:")
    assert "wall-time limit" in pieces[0]
    assert len(pieces) == 10  # one step a piece; the last one ends the run
    assert pieces[-1] == "ok"
    assert not ck.exists()
    assert np.array_equal(ds["time"].values, ref["time"].values)
    assert np.allclose(ds["rho_bar"].values, ref["rho_bar"].values, rtol=0, atol=1e-13)
    with pytest.raises(ParameterError, match="wall_limit"):
        simulate(p1, 1000.0, wall_limit=0.0, **SMALL)


def test_bad_input(p1):
    with pytest.raises(ParameterError, match="flow"):
        DnsSimulation((16.0, 0.05), 1000.0)  # type: ignore[arg-type]
    with pytest.raises(ParameterError, match="length"):
        DnsSimulation(p1, float("nan"))
    with pytest.raises(ParameterError, match="snapshots"):
        DnsSimulation(p1, 1000.0, snapshots=0, **SMALL)
    # a mode whose amplitude takes ν past ν_m at the floor
    with pytest.raises(ParameterError, match="amplitude"):
        DnsSimulation(p1, 1000.0, time=8.0, dt=4.0, amplitude=0.45, n=24).initial_state()


def test_summary_has_the_wave_keys(p1):
    s = summary(simulate(p1, 1000.0, **SMALL))
    for key in ("verdict", "rho_min_rel", "rho_max_rel", "wave_speed", "wavelength", "t_saturation"):
        assert key in s
    assert s["verdict"] in ("growing", "decaying")  # a wave of 1e-4: the linear phase
    assert s["resolved"] is (max(s["x_tail"], s["y_tail"]) <= 1e-4)


def test_cli_dns_and_waves_json_keys_are_documented(tmp_path):
    """``chuteflow dns --json`` has the wave keys; every key of it and of ``chuteflow waves
    --json`` is in docs/cli.md; a map run again reads its finished runs back (same numbers)."""
    import json

    from typer.testing import CliRunner

    from chuteflow.cli import app
    from tests.cli.test_cli_reference import documented, undocumented

    runner = CliRunner()
    flow = ["--theta", "16", "--nu0", "0.05", "--roughness", "0.05", "--length", "1000"]
    grid = ["--time", "40", "--dt", "4", "--nx", "5", "--ny", "24", "--amplitude", "1e-4"]
    r = runner.invoke(app, ["dns", *flow, *grid, "--init", "noise", "--json"])
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout.strip().splitlines()[-1])
    for key in (
        "verdict",
        "rho_min_rel",
        "rho_max_rel",
        "wave_speed",
        "wavelength",
        "t_saturation",
        "mass_drift",
    ):
        assert key in d
    docs = documented()
    assert not undocumented("dns", d, docs)
    args = ["waves", *flow, *grid, "--out-dir", str(tmp_path), "--json"]
    r = runner.invoke(app, args)
    assert r.exit_code == 0, r.output
    w = json.loads(r.stdout.strip().splitlines()[-1])
    assert not undocumented("waves", w, docs)
    assert w["points"][0]["verdict"] in ("growing", "decaying")
    again = json.loads(runner.invoke(app, args).stdout.strip().splitlines()[-1])
    assert again["points"] == w["points"]  # read back: even the wall time is the first run's
    r = runner.invoke(app, ["waves", "--points", "P1", "--theta", "16", "--json"])
    assert r.exit_code == 2
    assert "points" in r.output
    # one period per flow, or a one-line error naming the parameter
    two = ["--theta", "16", "--nu0", "0.05,0.06", "--roughness", "0.05"]
    r = runner.invoke(app, ["waves", *two, "--length", "1000,1500", *grid, "--json"])
    assert r.exit_code == 0, r.output
    w2 = json.loads(r.stdout.strip().splitlines()[-1])
    assert w2["length"] == [1000.0, 1500.0]
    assert [p["length"] for p in w2["points"]] == [1000.0, 1500.0]
    r = runner.invoke(app, ["waves", *two, "--length", "1000,1500,2000", *grid])
    assert r.exit_code == 2
    assert "length" in r.output
    assert "one per flow" in r.output
    assert "Traceback" not in r.output


def test_cli_waves_reduced_runs_the_1d_model_as_long_as_the_full_one():
    """``chuteflow waves --reduced``: the 1D model (§5.1.2) gets the same ``--time`` as the full
    equations. At P1 it is unstable at every wavenumber (k_c = ∞, tests/reduced/test_model.py)
    and its noise leaves the steady family's range by t ≈ 40 (ρ̄ −36 … +22 %); stopped at
    t = 20 it is still a small, growing wave (|ρ̄/⟨ρ̄⟩ − 1| ≈ 4e-3 from noise of 1e-3: fastest
    discrete growth 0.22, e^{0.22·20}·1e-3 ≈ 0.08 is its bound). Before, the 1D run ignored
    ``--time`` and always ran until it left (``left_validity``)."""
    import json

    from typer.testing import CliRunner

    from chuteflow.cli import app
    from tests.cli.test_cli_reference import documented, undocumented

    flow = ["--theta", "16", "--nu0", "0.05", "--roughness", "0.05", "--length", "1000"]
    grid = ["--time", "20", "--dt", "4", "--nx", "3", "--ny", "24", "--reduced", "--json"]
    r = CliRunner().invoke(app, ["waves", *flow, *grid])
    assert r.exit_code == 0, r.output
    w = json.loads(r.stdout.strip().splitlines()[-1])
    assert not undocumented("waves", w, documented())
    p = w["points"][0]
    assert p["reduced_verdict"] == "growing"
    assert 1e-3 < max(-p["reduced_rho_min_rel"], p["reduced_rho_max_rel"]) < 0.08
    assert p["reduced_short_wave_unstable"] is True


# -- the x grid that follows the wave (max_modes, DnsSimulation.refine) ----------------------------
# P1 (L = 1000) from its mode at 1 % on a grid of M = 2: the second harmonic carries ≈ 0.1 of the
# first at once, so with a tolerance of 1e-2 the grid must double twice (M = 2 → 4 → 8) to stay
# resolved; M = 8 from the start is the reference.
# (n = 24 leaves y under-resolved at this amplitude: these tests are about x)
Y_COARSE = pytest.mark.filterwarnings("ignore:the highest y modes")
REFINE = dict(time=120.0, dt=4.0, init="mode", amplitude=0.01, n=24, resolution_tol=1e-2)


@Y_COARSE
def test_refine_keeps_the_state_and_its_mass(p1):
    """refine() pads the coefficients with zeros (the same function: modes ≤ M unchanged but
    for a uniform shift of ln ν of the coarse quadrature's aliasing error, here 6e-14) and
    keeps the total mass the run conserved to round-off; the records move to the finer grid."""
    sim = DnsSimulation(
        p1, 1000.0, time=40.0, dt=4.0, init="mode", amplitude=0.01, n=24, modes=2, max_modes=8
    )
    st = sim.run()
    C, prev = st.C.copy(), st.prev.copy()
    mass = sim.disc.total_mass(prev[0], prev[3][-1])
    rho_old = np.asarray(st.records["rho"][-1])
    sim.refine(st)
    assert sim.disc.modes == 4
    assert st.C.shape[-1] == 5
    assert sim.can_refine()
    assert np.array_equal(st.C[1:, :, :3], C[1:])  # u, v, T: the same coefficients
    assert np.array_equal(st.C[0, :, 1:3], C[0, :, 1:])
    assert np.abs(st.C[0, :, 0] - C[0, :, 0]).max() < 1e-12  # the mass shift
    assert not st.C[..., 3:].any()
    nu, _, _, T = st.prev
    assert abs(sim.disc.total_mass(nu, T[-1]) / mass - 1) < 1e-14  # the history level too
    rho = st.records["rho"]
    assert all(len(r) == sim.disc.nxp for r in rho)
    # the last record, interpolated, is ρ̄ of the refined state on the finer grid up to what the
    # coarse samples of ρ̄ = ∫e^s dy (not band-limited) miss: 1.4e-7 here
    assert np.allclose(rho[-1], sim.disc.depth_integrals(st.C)[0], rtol=1e-6, atol=0)
    assert abs(np.mean(rho[-1]) - np.mean(rho_old)) < 1e-13
    sim.refine(st)
    assert sim.disc.modes == 8
    assert not sim.can_refine()
    with pytest.raises(ParameterError, match="max_modes"):
        sim.refine(st)


@Y_COARSE
def test_a_refining_run_stays_resolved_and_matches_the_fine_grid(p1):
    """On M = 2 the run is not resolved (x tail 0.37 at the end); with max_modes = 8 it doubles
    twice — after the first step (the monitor looks then too) and at t = 40 — and ends with
    the tail of the M = 8 run (3.0e-4 against 3.1e-4), ρ̄ within 1.6e-4 of it (the
    difference is the coarse grid's first steps; 1e-3 while the monitor first looked at
    step 10, refining at t = 40 and 80), mass to 1e-13."""
    with pytest.warns(ResolutionWarning, match="x modes"):
        coarse = simulate(p1, 1000.0, modes=2, **REFINE)
    fine = simulate(p1, 1000.0, modes=8, **REFINE)
    ds = simulate(p1, 1000.0, modes=2, max_modes=8, **REFINE)
    a = ds.attrs
    assert (a["nx_initial"], a["nx"], a["nx_max"], a["refinements"]) == (5, 17, 17, 2)
    assert a["refined_at"].startswith("t = 4 (nx 9), t = 40 (nx 17)")
    assert ds["rho_bar"].shape == fine["rho_bar"].shape
    assert coarse.attrs["x_tail_end"] > 0.3
    assert a["x_tail_end"] < 1e-3
    assert a["x_tail_end"] == pytest.approx(fine.attrs["x_tail_end"], rel=0.3)
    # the run's tail is that of the grid it ends on (the monitor's series after the last
    # refinement, t > 40): the M = 2 and M = 4 records before carry their own grids' tails
    tails, t = ds["x_tail"].values, ds["time"].values
    assert a["x_tail"] == run_tail(tails[t > 40])
    assert a["x_tail"] < 1e-3 < run_tail(tails)
    err = np.abs(ds["rho_bar"].values[-1] - fine["rho_bar"].values[-1]).max() / float(p1.rho_bar)
    assert err < 3e-4
    assert a["mass_drift"] < 1e-13
    assert "not resolved in x" not in a["resolution_warnings"]
    s = summary(ds)
    assert (s["nx_initial"], s["nx"], s["refinements"]) == (5, 17, 2)
    with pytest.raises(ParameterError, match="max_modes"):
        simulate(p1, 1000.0, modes=4, max_modes=2, **REFINE)


class _PauseAt(Tracker):
    """Pause the run after step ``at`` (None: never)."""

    def __init__(self, at):
        self.at = at

    def handle(self, sim, step):
        return f"paused at step {step.number}" if step.number == self.at else None


@Y_COARSE
def test_a_refined_run_resumes_exactly(tmp_path, p1):
    """Paused after the first refinement (step 5; M = 4), the same call continues from the
    checkpoint on the refined grid and refines once more: the uninterrupted run to 1e-13."""
    ref = simulate(p1, 1000.0, modes=2, max_modes=8, **REFINE)
    ck = tmp_path / "run.ck.npz"
    first = simulate(p1, 1000.0, modes=2, max_modes=8, checkpoint=ck, trackers=[_PauseAt(5)], **REFINE)
    assert first.attrs["status"] == "paused at step 5"
    assert first.attrs["nx"] == 9
    assert ck.exists()
    ds = simulate(p1, 1000.0, modes=2, max_modes=8, checkpoint=ck, trackers=[_PauseAt(None)], **REFINE)
    assert ds.attrs["status"] == "ok"
    assert not ck.exists()
    assert ds.attrs["refined_at"] == ref.attrs["refined_at"]
    assert np.array_equal(ds["time"].values, ref["time"].values)
    assert np.allclose(ds["rho_bar"].values, ref["rho_bar"].values, rtol=0, atol=1e-13)


# -- the y grid that follows the wave (max_n, DnsSimulation.refine(..., "y")) ------------------------
# P1 (L = 1000) from its mode at 1 %, M = 8: the first steps put structure near the dilute top into
# the highest Chebyshev coefficients (y tail at the end 3.6e-6 at N = 64, 8.9e-5 at N = 48, 7.8e-4
# at N = 40; measured 2026-12-06), so a y grid of N = 48 with a tolerance of 1e-4 must grow.
YREF = dict(time=120.0, dt=4.0, init="mode", amplitude=0.01, modes=8)


def test_refine_in_y_keeps_the_state_and_its_mass(p1):
    """refine(state, "y") evaluates the Chebyshev interpolant of every field at the finer nodes
    (N = 32 → 48 → 64 at most: ×1.5 to a multiple of 8): the coarse nodal values are recovered
    from the fine ones to round-off, ln ν up to the uniform shift (the coarse Clenshaw–Curtis
    error of ∫e^s dy) that keeps the total mass; the history level, C_init and the snapshots
    move to the finer nodes."""
    sim = DnsSimulation(p1, 1000.0, time=8.0, dt=4.0, init="mode", amplitude=0.01, n=32, modes=2, max_n=64)
    st = sim.run()
    old = sim.disc.grid
    C, prev = st.C.copy(), st.prev.copy()
    mass = sim.disc.total_mass(prev[0], prev[3][-1])
    sim.refine(st, "y")
    fine = sim.disc.grid
    assert sim.disc.n == 48
    assert st.C.shape == (4, 49, 3)
    assert st.C_init.shape == (4, 49, 3)
    back = np.moveaxis(fine.interpolate(np.moveaxis(st.C, 1, -1), old.y), -1, 1)
    np.testing.assert_allclose(back[1:], C[1:], rtol=0, atol=1e-12)  # u, v, T: the same polynomials
    np.testing.assert_allclose(back[0, :, 1:], C[0, :, 1:], rtol=0, atol=1e-12)
    shift = back[0, :, 0] - C[0, :, 0]
    assert np.ptp(shift.real) < 1e-12  # a uniform shift of ln ν …
    assert abs(shift[0]) < 1e-6  # … of the coarse quadrature's size
    nu, _, _, T = st.prev
    assert abs(sim.disc.total_mass(nu, T[-1]) / mass - 1) < 1e-14  # the history level too
    assert all(np.shape(v) == (4, 49, sim.disc.nxp) for v in st.records["snaps"])
    assert sim.can_refine("y")
    assert not sim.can_refine("x")
    sim.refine(st, "y")
    assert sim.disc.n == 64  # 72, capped
    assert not sim.can_refine("y")
    with pytest.raises(ParameterError, match="max_ny"):
        sim.refine(st, "y")
    with pytest.raises(ParameterError, match="max_ny"):
        DnsSimulation(p1, 1000.0, n=32, modes=2, max_n=24)


def test_a_run_refining_in_y_is_closer_to_the_fine_grid(p1):
    """From N = 48 with a tolerance of 1e-4 (checked every step) the y grid grows to 64 after the
    first step; at t = 120 its ρ̄ is within 1.5e-5 of ⟨ρ̄⟩ of the N = 64 run's (N = 48 kept: 5.1e-5;
    the wave itself is 2.9e-3), the y tail at the end 3.7e-5 (N = 48 kept: 8.9e-5), mass to 1e-14.
    What the first step made on the coarse grid stays (the refinement is exact, not a restart),
    so the refined run does not reach the fine run's own error; bounds from those numbers."""

    def run(n, max_n=None):
        sim = DnsSimulation(p1, 1000.0, n=n, max_n=max_n, **YREF)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", ResolutionWarning)
            st = sim.run([ResolutionMonitor(1e-4, every=1, action="refine" if max_n else "warn")])
        return sim.dataset(st), caught

    fine, _ = run(64)
    coarse, warned = run(48)
    ds, caught = run(48, 64)
    a = ds.attrs
    assert any("y modes" in str(w.message) for w in warned)
    assert not any("y modes" in str(w.message) for w in caught)
    assert (a["ny_initial"], a["ny"], a["ny_max"], a["refinements"]) == (48, 64, 64, 1)
    assert a["refined_at"] == "t = 4 (ny 64)"
    assert ds["nu"].shape[1] == 65
    assert np.array_equal(ds["y"].values, fine["y"].values)

    def err(d):
        return float(np.abs(d["rho_bar"].values[-1] - fine["rho_bar"].values[-1]).max() / p1.rho_bar)

    assert err(coarse) > 4e-5
    assert err(ds) < 2.5e-5
    assert a["y_tail_end"] < 6e-5 < coarse.attrs["y_tail_end"]
    # the run's y tail is the N = 64 grid's (the records after the refinement at t = 4)
    t = ds["time"].values
    assert a["y_tail"] == run_tail(ds["y_tail"].values[t > 4]) < run_tail(ds["y_tail"].values)
    assert a["mass_drift"] < 1e-13


@pytest.mark.filterwarnings("ignore:the highest x modes")
def test_a_run_refined_in_y_resumes_exactly(tmp_path, p1):
    """N = 32 → 48 at t = 4 (the y tail past 1e-2 / 4 after the first step, where the monitor
    looks too); paused after it (step 5) and continued from the checkpoint on the finer y grid:
    the uninterrupted run to round-off (measured 2.0e-13 of ρ̄ ≈ 0.26; 1.0e-13 paused at step 15)."""
    kw = dict(modes=2, n=32, max_n=64, **{k: v for k, v in REFINE.items() if k != "n"})
    ref = simulate(p1, 1000.0, **kw)
    assert ref.attrs["refined_at"].startswith("t = 4 (ny 48)")
    ck = tmp_path / "run.ck.npz"
    first = simulate(p1, 1000.0, checkpoint=ck, trackers=[_PauseAt(5)], **kw)
    assert first.attrs["ny"] == 48
    ds = simulate(p1, 1000.0, checkpoint=ck, trackers=[_PauseAt(None)], **kw)
    assert ds.attrs["refined_at"] == ref.attrs["refined_at"]
    assert np.allclose(ds["rho_bar"].values, ref["rho_bar"].values, rtol=0, atol=1e-12)
    # (the pause took a snapshot of its own; the last ones are the same time's)
    assert np.allclose(ds["nu"].values[-1], ref["nu"].values[-1], rtol=0, atol=1e-12)


def test_resample_is_trigonometric_interpolation():
    """spectral.fourier_resample (the refined grid's records, the wave map's shapes, the wave's
    extrema): a trigonometric polynomial of degree 3 sampled on 7 (odd) or 8 (even, with its
    Nyquist term) points is reproduced exactly on 13 points."""
    from chuteflow.spectral import fourier_resample as _resample

    def f(x):
        return 1.0 + 0.3 * np.cos(x) - 0.2 * np.sin(2 * x) + 0.1 * np.cos(3 * x + 0.4)

    for n in (7, 8):
        x = 2 * np.pi * np.arange(n) / n
        xf = 2 * np.pi * np.arange(13) / 13
        np.testing.assert_allclose(_resample(f(x), 13), f(xf), rtol=0, atol=1e-14)
    # the Nyquist term cos(4x) on 8 points: split between ±4 on the finer grid
    x8 = 2 * np.pi * np.arange(8) / 8
    x17 = 2 * np.pi * np.arange(17) / 17
    np.testing.assert_allclose(_resample(np.cos(4 * x8), 17), np.cos(4 * x17), rtol=0, atol=1e-14)


def test_wave_speed_now_measures_a_travelling_wave(p1):
    """DnsSimulation.wave_speed_now on records of ρ̄ = 1 + a cos(2π m (ξ − v t)/L) in the
    run's first frame: the lab speed frame + v exactly (a pure mode's phase is linear in t);
    None while the wave is below FOLLOW_AMPLITUDE, with fewer than FOLLOW_WINDOW records, or
    with a change of frame inside the window."""
    from chuteflow.dns.simulation import FOLLOW_AMPLITUDE, FOLLOW_WINDOW

    sim = DnsSimulation(p1, 1000.0, frame_speed=7.5, **SMALL)
    x = np.arange(16) * 1000.0 / 16
    t = 100.0 + 4.0 * np.arange(FOLLOW_WINDOW)
    st = sim.initial_state()

    def records(amp, m=1, v=0.21):
        st.records["t"] = list(t)
        st.records["rho"] = list(_wave(t, x, 1000.0, v, np.full(len(t), amp), m))
        st.records["frame_t"] = []

    records(0.1)
    assert sim.wave_speed_now(st) == pytest.approx(7.5 + 0.21, abs=1e-9)
    records(0.1, m=2, v=-0.4)  # the dominant mode's
    assert sim.wave_speed_now(st) == pytest.approx(7.5 - 0.4, abs=1e-9)
    records(0.45 * FOLLOW_AMPLITUDE)  # max − min = 0.9 FOLLOW_AMPLITUDE: still linear
    assert sim.wave_speed_now(st) is None
    records(0.1)
    st.records["frame_t"] = [t[3]]
    assert sim.wave_speed_now(st) is None
    st.records["frame_t"] = [t[0] - 1.0]
    assert sim.wave_speed_now(st) is not None
    st.records["t"], st.records["rho"] = st.records["t"][1:], st.records["rho"][1:]
    assert sim.wave_speed_now(st) is None


def _reframed_run(p1, speed, at, time, shift_history=True, **kw):
    """A run in frame 0 to ``at``, then in the frame ``speed`` (DnsSimulation.reframe) to
    ``time``; with ``shift_history`` False the BDF2 history is left unshifted (the mistake
    the shift prevents)."""
    from dataclasses import replace

    sim = DnsSimulation(p1, 1000.0, time=at, **kw)
    st = sim.run()
    if shift_history:
        sim.reframe(st, speed)
    else:
        prev = st.prev.copy()
        sim.reframe(st, speed)
        st.prev = prev
    sim.setup = replace(sim.setup, time=time)
    return sim, sim.run(state=st)


def test_a_change_of_frame_continues_the_same_solution(p1):
    """reframe() mid-run: the run goes on in the frame of the eigenmode's phase velocity, and
    its records (in the first frame) converge to the frame-0 run's at second order in Δt — the
    two frames' BDF2 errors (eigenmode at amplitude 0.01, nx 17, the frame changed at t = 20,
    compared at t = 40: 1.56e-5 of ⟨ρ̄⟩ at Δt 0.5, 4.5e-6 at 0.25). Without shifting the
    history level into the new frame the error is first order (8.4e-5, 4.2e-5): the shift is
    what makes the change exact."""
    errs = {}
    for dt in (0.5, 0.25):
        kw = dict(dt=dt, init="mode", amplitude=0.01, n=24, modes=8)
        ref_sim = DnsSimulation(p1, 1000.0, time=40.0, **kw)
        ref = np.asarray(ref_sim.run().records["rho"])
        c = ref_sim.mode.wave_speed
        mean = np.mean(ref[-1])
        for shift in (True, False) if dt == 0.25 else (True,):
            sim, st = _reframed_run(p1, c, 20.0, 40.0, shift_history=shift, **kw)
            errs[dt, shift] = np.abs(np.asarray(st.records["rho"]) - ref).max() / mean
    assert sim.disc.frame == c
    assert st.frame == c
    assert st.records["frame_t"] == [20.0]
    assert st.records["frame_speed"] == [c]
    assert st.frame_shift == pytest.approx(20.0 * c, rel=1e-12)
    assert errs[0.25, True] < 1e-5
    assert errs[0.5, True] / errs[0.25, True] > 3.0  # second order
    assert errs[0.25, False] > 5 * errs[0.25, True]
    ds = sim.dataset(st)
    assert ds.attrs["frame_speed"] == 0.0
    assert ds.attrs["frame_speed_end"] == c
    assert ds.attrs["reframes"] == 1


def test_the_frame_survives_a_checkpoint(tmp_path, p1):
    sim = DnsSimulation(p1, 1000.0, **SMALL)
    st = sim.initial_state()
    st.save(tmp_path / "a.npz", sim.key())
    assert DnsState.load(tmp_path / "a.npz", sim.key()).frame is None  # (the run's own)
    st.frame, st.frame_shift = 7.25, -12.5
    st.records["frame_t"], st.records["frame_speed"] = [8.0], [7.25]
    st.save(tmp_path / "b.npz", sim.key())
    back = DnsState.load(tmp_path / "b.npz", sim.key())
    assert (back.frame, back.frame_shift) == (7.25, -12.5)
    assert back.records["frame_speed"] == [7.25]
    sim._follow(back)
    assert sim.disc.frame == 7.25


def test_a_run_that_follows_its_wave(p1):
    """follow_wave (the default from noise): P1, L = 1000, from noise in a frame 2.6 % slower
    than the wave (7.6): once ρ̄ varies by FOLLOW_AMPLITUDE (t ≈ 17400 here) the frame moves,
    once, to the wave's speed (7.8075; the run's own wave_speed, over the last tenth, to 1e-5),
    and the records are the run's that stayed in 7.6 to the time-step control's error (4.5e-6
    of ⟨ρ̄⟩ measured; the tolerance ten times that). The whole run in its first frame: mass to
    round-off."""
    from chuteflow.dns import NewtonSettings

    kw = dict(
        time=18000.0, dt=4.0, n=32, modes=8, init="noise", amplitude=1e-3, frame_speed=7.6, snapshots=2,
        settings=NewtonSettings(dt_tol=1e-3, preconditioner="coupled"),
    )  # fmt: skip
    plain = DnsSimulation(p1, 1000.0, follow_wave=False, **kw)
    ref = plain.run()
    sim = DnsSimulation(p1, 1000.0, **kw)  # (from noise the frame follows by default)
    st = sim.run()
    ds = sim.dataset(st)
    assert len(st.records["frame_t"]) == 1
    assert ds.attrs["reframes"] == 1
    assert ds.attrs["frame_speed"] == 7.6
    assert ds.attrs["follow_wave"] == 1
    assert ds.attrs["frame_speed_end"] == pytest.approx(ds.attrs["wave_speed"], rel=1e-4)
    a, b = np.asarray(st.records["rho"][-1]), np.asarray(ref.records["rho"][-1])
    assert st.t == ref.t
    assert np.abs(a - b).max() / b.mean() < 5e-5
    assert ds.attrs["mass_drift"] < 1e-12
    assert ds.attrs["rho_max_rel"] > 0.025  # (the wave was nonlinear: FOLLOW_AMPLITUDE = 0.05 max − min)

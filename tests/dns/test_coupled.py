"""Tests of the mode-coupling preconditioner (docs/dns.md, *Where a nonlinear step's time goes*).

References: the per-mode linearisation :meth:`Discretisation.linear_blocks` (built from
:func:`chuteflow.equations.compiled_equations`, checked against the finite-difference Jacobian
in test_dns.py) at an x-independent state, a sparse LU of the assembled matrix for the block
elimination, and the step of the x-mean preconditioner for the Newton solution.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.sparse.linalg import splu

from chuteflow.closures import ChuteModel
from chuteflow.dns import Discretisation, Stepper
from chuteflow.dns.columns import jet_coefficients
from chuteflow.dns.coupled import CoupledPreconditioner, coupled_blocks, coupled_matrix
from chuteflow.dns.discretisation import BDF2
from chuteflow.dns.stepper import NewtonSettings
from chuteflow.errors import ConvergenceError
from chuteflow.steady import solve_steady

from .test_columns import _steady, _wave

MODEL = ChuteModel(roughness=0.05)


@pytest.fixture(scope="module")
def p1():
    return solve_steady(16.0, 0.05, MODEL)


def test_coupled_blocks_at_uniform_state_are_the_mode_jacobian(p1):
    """At an x-independent state only the diagonal blocks are non-zero, and the block of mode
    m is the per-mode Jacobian of linear_blocks (x-derivatives exact: ik)."""
    d = Discretisation(16.0, MODEL, 1000.0, p1.y_max, 20, 3, frame=7.8)
    C = _steady(d, p1)
    st = Stepper(d)
    hist = (st.physical(C), st.physical(C))
    dt = 3.0
    B = coupled_blocks(d, jet_coefficients(d, C, hist, dt, BDF2), np.arange(d.modes + 1), 1)
    blocks = d.linear_blocks(C)
    for mode in range(d.modes + 1):
        ik = 1j * d.k[mode]
        ref = (
            blocks["K"] * d.k[mode]
            + blocks["Bt"] * (1.5 / dt - d.frame * ik)
            + blocks["pieces"].get(0, 0)
            + ik * blocks["pieces"].get(1, 0)
            + ik**2 * blocks["pieces"].get(2, 0)
        )
        scale = np.abs(ref).max()
        assert np.abs(B[mode, 0]).max() <= 1e-9 * scale
        assert np.abs(B[mode, 2]).max() <= 1e-9 * scale
        # one-sided differences of step 1e-7 × max|jet| in the coefficients; the density top
        # row drops the O(ν(y_max)) term of the linear problem's condition (as test_columns)
        # (v at the floor node, v = 0 by its floor row, is skipped: the floor rows of the
        # simulation keep their ∂_t v term, linear_blocks drops it)
        for j in (j for j in range(ref.shape[1]) if j != 2 * (d.n + 1)):
            s = np.abs(ref[:, j]).max()
            assert np.abs(B[mode, 1][:, j] - ref[:, j]).max() <= 1e-5 * s + 1e-6, (mode, j)


def test_block_elimination_solves_the_coupled_matrix(p1):
    """apply(R) equals a sparse LU solve of the assembled matrix of modes −M … M (with
    R_{−m} = conj R_m) at a finite-amplitude state, and the solution is that of a real field."""
    d = Discretisation(16.0, MODEL, 1000.0, p1.y_max, 16, 4, frame=7.8)
    C = _wave(d, p1, 0.2)
    st = Stepper(d)
    hist = (st.physical(C), st.physical(C))
    P = CoupledPreconditioner.build(d, C, hist, 4.0, BDF2)
    J = coupled_matrix(d, jet_coefficients(d, C, hist, 4.0, BDF2), 1)
    rng = np.random.default_rng(1)
    R = rng.normal(size=d.shape) + 1j * rng.normal(size=d.shape)
    R[..., 0] = R[..., 0].real
    M = d.modes
    full = np.concatenate([np.conj(R[..., :0:-1]), R], axis=-1)
    y = splu(J.tocsc()).solve(np.ascontiguousarray(full.transpose(2, 0, 1)).ravel())
    y = y.reshape(2 * M + 1, 4, d.n + 1).transpose(1, 2, 0)
    x = P.apply(R)
    scale = np.abs(x).max()
    assert np.abs(y[..., M:] - x).max() <= 1e-9 * scale
    assert np.abs(y[..., :M][..., ::-1] - np.conj(y[..., M + 1 :])).max() <= 1e-9 * scale
    assert np.all(x[..., 0].imag == 0)


def test_newton_with_coupled_reaches_the_same_steps(p1):
    """Three BDF2 steps at a finite wave: the coupled and the x-mean preconditioners give the
    same solution to the Newton tolerance, the coupled one (from the first step,
    ``coupled_krylov=0``) with fewer GMRES iterations."""
    d = Discretisation(16.0, MODEL, 1000.0, p1.y_max, 24, 6, frame=7.8)
    C0 = _wave(d, p1, 0.1)
    out = {}
    for name in ("mean", "coupled"):
        st = Stepper(d, NewtonSettings(preconditioner=name, coupled_krylov=0))
        C, first = C0.copy(), True
        hist = (st.physical(C), st.physical(C))
        krylov = 0
        for _ in range(3):
            C_new, info = st.step(C, hist, 4.0, first=first)
            assert info.residual < 1e-10
            krylov += info.krylov
            hist = (st.physical(C_new), hist[0])
            C, first = C_new, False
        out[name] = (C, krylov)
        assert st.coupled == (name == "coupled")
    assert np.abs(out["mean"][0] - out["coupled"][0]).max() <= 1e-8
    assert out["coupled"][1] <= out["mean"][1]


def test_coupled_falls_back_to_columns_where_fresh_blocks_do_not_serve(p1):
    """Where a GMRES solve right after the coupled blocks were built still needs more than
    ``switch_krylov`` iterations (``switch_krylov=0`` forces it here; in a run, a wave of
    ±40 … 80 %, docs/dns.md), ``"coupled"`` goes over to the columns and the step reaches the
    x-mean preconditioner's solution to the Newton tolerance."""
    d = Discretisation(16.0, MODEL, 1000.0, p1.y_max, 24, 6, frame=7.8)
    C = _wave(d, p1, 0.1)
    hist = None
    out = {}
    for name, extra in (("mean", {}), ("coupled", dict(coupled_krylov=0, switch_krylov=0))):
        st = Stepper(d, NewtonSettings(preconditioner=name, **extra))
        hist = (st.physical(C), st.physical(C))
        C_new, info = st.step(C, hist, 4.0, first=True)
        assert info.residual < 1e-10
        out[name] = (C_new, st)
    st = out["coupled"][1]
    assert st.columns
    assert not st.coupled
    assert np.abs(out["mean"][0] - out["coupled"][0]).max() <= 1e-8
    # and without the forcing the coupled blocks stay (the test above)
    st = Stepper(d, NewtonSettings(preconditioner="coupled", coupled_krylov=0))
    st.step(C, hist, 4.0, first=True)
    assert st.coupled
    assert not st.columns


def test_coupled_returns_from_columns_that_serve_worse(p1):
    """The rule of ``Stepper._escalation`` between the coupled blocks and the columns, by the
    GMRES iterations of the first solve after each build (at P5's steepening bore, L = 2000,
    257 × 96, Δt = 8, measured 77 a step with the coupled blocks against 259 … 286 with the
    columns, docs/dns.md): fresh coupled blocks above ``switch_krylov`` go over to the
    columns; fresh columns that need more than those coupled blocks did go back; the
    coupled blocks go to the columns again only once they need more than the columns did;
    and a step whose Newton solve fails forgets the comparison."""
    d = Discretisation(16.0, MODEL, 1000.0, p1.y_max, 24, 6, frame=7.8)
    st = Stepper(d, NewtonSettings(preconditioner="coupled", coupled_krylov=0))
    st.switch_dt = 4.0

    def fresh(kind):
        st.kind, st._age, st._base_krylov = kind, 1, None

    fresh("coupled")
    assert st._escalation(40, 4.0) is None  # below switch_krylov = 60
    assert st._escalation(77, 8.0) is None  # Δt above the run's: no columns
    assert st._escalation(77, 4.0) == "columns"
    fresh("columns")
    assert st._escalation(70, 4.0) is None  # better than the coupled blocks' 77: kept
    assert st._escalation(270, 4.0) == "coupled"
    fresh("coupled")
    assert st._escalation(77, 4.0) is None  # the columns needed 270
    assert st._escalation(300, 4.0) == "columns"
    st._age = 5  # not fresh: no switch either way
    st.kind = "columns"
    assert st._escalation(1000, 4.0) is None
    # a failed Newton solve forgets the comparison (the coupled blocks may not converge)
    st = Stepper(d, NewtonSettings(preconditioner="coupled", coupled_krylov=0, max_iter=1))
    st.fresh_krylov["columns"] = 270
    C = _wave(d, p1, 0.1)
    hist = (st.physical(C), st.physical(C))
    with pytest.raises(ConvergenceError, match="Newton residual"):
        st.step(C, hist, 64.0, first=True)
    assert st.fresh_krylov == {}


def test_cli_preconditioner_coupled():
    """``chuteflow dns --preconditioner coupled`` runs from noise with the step control and
    conserves mass as the default does; an unknown name is a one-line error."""
    import json

    from typer.testing import CliRunner

    from chuteflow.cli import app

    runner = CliRunner()
    args = ["dns", "--theta", "16", "--nu0", "0.05", "--length", "1000", "--init", "noise"]
    args += ["--nx", "9", "--ny", "32", "--time", "2000", "--dt", "4", "--dt-tol", "1e-3", "--json"]
    r = runner.invoke(app, [*args, "--preconditioner", "coupled"])
    assert r.exit_code == 0, r.output
    d = json.loads(r.stdout.strip().splitlines()[-1])
    assert d["mass_drift"] < 1e-12
    r = runner.invoke(app, [*args, "--preconditioner", "ilu"])
    assert r.exit_code == 2
    assert "preconditioner" in r.output
    assert "Traceback" not in r.output


def test_a_diverging_iterate_fails_the_step_without_warnings(p1):
    """An iterate that overflows (ln ν = 800: ν = e^800) makes a non-finite residual, which
    fails the step with a ConvergenceError (the run's control repeats it with a shorter Δt);
    the overflow itself is not reported as a RuntimeWarning (a P5 run printed 19 of them)."""
    import warnings

    d = Discretisation(16.0, MODEL, 1000.0, p1.y_max, 16, 4, frame=7.8)
    C = _wave(d, p1, 0.1)
    st = Stepper(d, NewtonSettings(preconditioner="mean"))
    hist = (st.physical(C), st.physical(C))
    bad = C.copy()
    bad[0, :, 0] = 800.0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(ConvergenceError):
            st.step(C, hist, 4.0, guess=bad)


def test_a_dear_preconditioner_is_rebuilt_once_its_excess_iterations_cost_a_build(p1):
    """``NewtonSettings.refresh_excess``: the columns or coupled blocks are dropped (rebuilt at
    the next step) once the GMRES iterations of the steps since their build, above the first
    step's count, add up (signed) to more than it: a drift from 40 to 80 a step (P1, L = 2000,
    225 × 96: 44 → 110 over 25 steps) triggers it after the excess passes 100; counts that
    wander about the first do not; the x-mean blocks are never dropped by this rule. The
    counters survive a snapshot and restore (a resumed run rebuilds where the run would),
    and a snapshot of before the rule (five counters) restores with none."""
    d = Discretisation(16.0, MODEL, 1000.0, p1.y_max, 8, 2, frame=7.8)
    st = Stepper(d, NewtonSettings(refresh_excess=100))
    st.kind, st._lus = "columns", object()
    for k in (40, 45, 50, 60, 70):  # excess 5 + 10 + 20 + 30 = 65
        st._count_excess(k)
    assert st._lus is not None
    assert st._excess == 65
    snap = st.snapshot()
    back = Stepper(d, NewtonSettings(refresh_excess=100))
    back.restore(snap)
    assert (back._excess, back._base_step) == (65, 40)
    st._count_excess(80)  # 65 + 40 > 100
    assert st._lus is None
    wander = Stepper(d, NewtonSettings(refresh_excess=100))
    wander.kind, wander._lus = "columns", object()
    for k in [40] + [30, 50] * 20:
        wander._count_excess(k)
    assert wander._lus is not None
    mean = Stepper(d, NewtonSettings(refresh_excess=0))
    mean._lus = object()
    for k in (10, 500, 500):
        mean._count_excess(k)
    assert mean._lus is not None
    old = dict(snap, counters=snap["counters"][:5])
    again = Stepper(d, NewtonSettings(refresh_excess=100))
    again.restore(old)
    assert (again._excess, again._base_step) == (0, None)
    with pytest.raises(ValueError, match="refresh_excess = -1"):
        NewtonSettings(refresh_excess=-1)

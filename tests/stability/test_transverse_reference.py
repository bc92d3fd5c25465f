"""The fast transverse path gives the answers of the code before its speed-up (issue 10,
"Performance"): ``transverse(flow, num=25)`` and the 50-k_z dispersion past the branch
(``beyond=True``) at P1 and at T2 (θ = 17.5°, ν0(0) = 0.06, φ = 0.05, transverse growth
4.27e-4), against the values that code computed (tests/stability/_transverse_reference.py).

The speed-up changes how the same eigenpairs are computed (real LU for real shifts on the
real form of the k_x = 0 pencil, the real form's pieces taken from the operator, the check
α(N') of a rung reused from the rung below, the seeds of the candidates past the branch by
the dense eigenproblem of (A' − σB')⁻¹B'), not which: the solver of each point, its N and
its verdict are the same, and every value agrees within its own convergence estimate.

Tolerance of Re α and |Im α| at each k_z: the larger of the two drifts |α(N) − α(N')| (the
stated estimate) plus a round-off floor 5e-11 (1 + |α|). On the tracked branch at P1 the
drifts (1e-16 to 4e-13) are themselves round-off: two computations that differ only by
round-off move α by up to 6.3e-13 there and 8.2e-12 past it, where |α| reaches 39 (the same
A' assembled in another order, measured when the fast path came). A steady flow that
differs only by round-off (relative 5e-12: Newton's solves with a second right-hand side,
or another machine's BLAS kernels) moves α past the branch by up to 4.6e-11 at |α| = 2.6
(T2, k_z = 1.07) and 1.2e-11 at |α| = 1.6 (P1, k_z = 0.38; measured), hence the floor.
The compiled rows of the steady Newton solver (issue 9, stop 31) changed T2's flow at that
level and moved α at k_z = 1.07 by 8.2e-11 = 2.3e-11 (1 + |α|); the same flow solved at
ν0(0) (1 + ε), ε = ±1e-15, ±3e-15, ±1e-14 (round-off of the input), moves it by up to
2.6e-11 (1 + |α|) against the reference, with the same solver, N and verdict at every k_z
(stop 32, measured): the floor is 5e-11 (1 + |α|), twice that spread.
The drifts and tails agree to half their value plus that floor (measured: the drifts of
resolved modes to 37 %, T2 at k_z = 2.3, |α| = 30).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from chuteflow.closures import ChuteModel
from chuteflow.longwave.spanwise import transverse, transverse_longwave
from chuteflow.stability.transverse import transverse_dispersion
from chuteflow.steady import solve_steady

from ._transverse_reference import REFERENCE, table

KZ50 = np.geomspace(1e-5, 3.0, 50)


def _floor(alpha_re):
    return 5e-11 * (1.0 + np.abs(np.nan_to_num(alpha_re)))


def _compare(got, stored):
    """A TransverseDispersion against a reference table (see the module docstring)."""
    ref = table(stored)
    assert list(got.method) == ref["method"]
    assert np.array_equal(got.n, ref["n"])
    assert np.array_equal(got.physical, ref["physical"])
    r_re, r_im, r_dr, r_tl = ref["alpha_re"], ref["alpha_im"], ref["drift"], ref["tail"]
    solved = np.isfinite(r_re)
    assert np.array_equal(np.isfinite(got.alpha_re), solved)
    floor = _floor(r_re)[solved]
    tol = np.maximum(r_dr[solved], got.drift[solved]) + floor
    assert np.all(np.abs(got.alpha_re[solved] - r_re[solved]) <= tol)
    assert np.all(np.abs(np.abs(got.alpha_im[solved]) - np.abs(r_im[solved])) <= tol)
    assert np.all(np.abs(got.drift[solved] - r_dr[solved]) <= 0.5 * r_dr[solved] + floor)
    assert np.all(np.abs(got.tail[solved] - r_tl[solved]) <= 0.5 * r_tl[solved] + 1e-13)


def _check_point(name):
    ref = REFERENCE[name]
    theta, nu0, phi = ref["flow"]
    flow = solve_steady(theta, nu0, ChuteModel(roughness=phi))
    r = transverse(flow, num=25)
    s, rs = r.to_dict(), ref["summary"]
    # α2z: bordered perturbation theory, not touched; its estimate is convergence_alpha2
    assert s["alpha2_z"] == pytest.approx(rs["alpha2_z"], rel=rs["convergence_alpha2"])
    # the estimate is a difference of two α2z values: a change of the steady tangent within
    # its own precision (2e-9, from Newton's last LU, tests/steady/test_solver.py) moves it
    # by 1.4e-4 relative at P1; 1e-2 still checks that it is the same estimate
    assert s["convergence_alpha2"] == pytest.approx(rs["convergence_alpha2"], rel=1e-2)
    # α at k_check = 1e-4 on the branch over k_check²: the floor 1e-12 over 1e-8
    assert s["alpha2_z_eigen"] == pytest.approx(rs["alpha2_z_eigen"], abs=1e-12 / rs["k_check"] ** 2)
    _compare(r.dispersion, ref["disp25"])
    # the refined maximum: a bounded search to 2 % in k_z, on branch points within the floor
    disp = table(ref["disp25"])
    j = int(np.nanargmax(disp["alpha_re"]))
    drift = disp["drift"][j]
    assert s["growth_max"] == pytest.approx(rs["growth_max"], abs=drift + 1e-12)
    assert s["kz_max"] == pytest.approx(rs["kz_max"], rel=0.02)
    assert s["stationary"] == rs["stationary"]
    # the cut-off: Brent's method to 0.1 %
    assert s["kz_cutoff"] == pytest.approx(rs["kz_cutoff"], rel=1e-3)
    # where the continuation could not step on: the end of its step halvings, 10 since
    # the tracker was made to cross the flat maximum of α(k_z) whatever the round-off (see
    # test_transverse.py::test_p1_branch_followed_past_its_maximum_whatever_the_round_off),
    # 6 in the reference code; the loss point moves by 0.41 % at P1 (measured)
    assert s["branch_lost_at"] == pytest.approx(rs["branch_lost_at"], rel=1e-2)
    a2 = float(transverse_longwave(flow).alpha2_z.real)
    _compare(transverse_dispersion(flow, KZ50, alpha2z=a2, beyond=True), ref["beyond50"])


def test_p1_same_answers_as_before_the_speed_up():
    """P1: α2z, k_z*, growth, cut-off and the 50-k_z dispersion past the branch."""
    _check_point("P1")


@pytest.mark.slow
def test_t2_same_answers_as_before_the_speed_up():
    """T2 (17.5°, 0.06, φ = 0.05): transversally unstable, k_z* = 5.77e-3, cut-off 8.89e-3."""
    assert math.isclose(REFERENCE["T2"]["summary"]["growth_max"], 4.2737e-4, rel_tol=1e-4)
    _check_point("T2")

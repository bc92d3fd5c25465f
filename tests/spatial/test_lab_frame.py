"""The lab-frame saddle across the branch cut (docs/spatial.md, "The lab frame: across the cut").

Fast tests: the continued sheet κ = k of the far-field root, and the collapse check of
``absolute._lab_pinch`` on analytic model dispersion relations whose answers are known in closed
form. Slow tests: the paper's points P1, P4, P5 (``lab_frame=True``), numbers measured at
N = 80 and checked at N = 100 (and 120 at P1, P5) in the convergence study of docs/spatial.md.
"""

import cmath
import math
import re
from types import SimpleNamespace

import pytest

from chuteflow.closures import ChuteModel
from chuteflow.errors import ParameterError
from chuteflow.spatial import DEFAULT_SPATIAL_POLICY, absolute_instability
from chuteflow.spatial.absolute import _half_line_crossings, _lab_pinch
from chuteflow.stability.complex_k import far_field_decay
from chuteflow.steady import solve_steady


def test_the_continued_sheet_is_k_itself():
    """κ = √(k²) with Re κ > 0 on the principal sheet; κ = k on the continued one (both agree
    on Re k > 0). Exact identities."""
    for k in (0.3 - 0.2j, 1e-3 + 5j):
        assert far_field_decay(k) == k
        assert far_field_decay(k, "continued") == k
    k = -0.3 - 0.2j
    assert far_field_decay(k) == -k
    assert far_field_decay(k, "continued") == k
    assert far_field_decay(-2j, "continued") == -2j  # no cut on the continued sheet
    with pytest.raises(ParameterError, match="branch cut"):
        far_field_decay(-2j)
    with pytest.raises(ParameterError, match="sheet"):
        far_field_decay(1.0, "third")


def test_crossings_of_the_real_axis_by_a_polyline():
    """Linear interpolation of the crossing of Im k = 0 on each segment (exact numbers)."""
    path = [(0.0, 1 - 1j), (1.0, 1 + 1j), (2.0, -3 + 1j), (3.0, -3 - 1j)]
    assert _half_line_crossings(path) == [(0, 1.0), (2, -3.0)]
    assert _half_line_crossings([(0.0, 1 - 1j), (1.0, 2 - 0.5j)]) == []


class _Model:
    """A Branch stand-in for the model dispersion relation α(k) = a (k − k*)² + α* (analytic):
    its saddle is k*, and the roots of α = α* + s w are k* ± √(s w/a)."""

    def __init__(self, a, k_star, alpha_star=0.0):
        self.a, self.ks, self.al = complex(a), complex(k_star), complex(alpha_star)

    def at(self, k, *, start=None, derivatives=2, sheet="principal"):
        k = complex(k)
        d = k - self.ks
        return SimpleNamespace(k=k, alpha=self.a * d * d + self.al, dalpha=2 * self.a * d, d2alpha=2 * self.a)


@pytest.mark.parametrize(
    ("a", "k_star", "expected"),
    [
        (-1.0, 1 - 1j, True),  # roots k* ± i√s: the upper one crosses the real axis at k = 1 > 0
        (-1.0, -1 - 1j, False),  # the same, crossing at k = −1: not through the contour [0, ∞)
        (1.0, 1 - 1j, False),  # roots k* ± √s: parallel to the real axis, no crossing
        (-1.0, 1 + 1j, True),  # the lower root crosses at k = 1
    ],
)
def test_the_collapse_check_on_the_half_line(a, k_star, expected):
    """Briggs' criterion for the half-line contour [0, ∞) (module docstring of
    chuteflow.spatial.absolute): a pinch exactly when the roots' joined path crosses [0, ∞) an
    odd number of times. Closed-form answers of the model; this must fail if the crossing's side
    or the parity is ignored."""
    model = _Model(a, k_star)
    e = model.at(k_star)
    pinch, why = _lab_pinch(model, e, 2.0, DEFAULT_SPATIAL_POLICY)
    assert pinch is expected, why
    assert (why == "") is expected


def _flow(theta, nu0):
    return solve_steady(theta, nu0, ChuteModel(roughness=0.05))


@pytest.mark.slow
def test_p5_lab_frame_saddle_is_undecided_and_decays():
    """P5 (17°, 0.10): the family leaves the principal sheet at V ≈ 14.3 (k* on the cut) and
    reaches V = 0 on the continued sheet at k* = −1.2952094159i (Re k* 2.4e-9), α* =
    −6.2272414856 + 1.80e-9i. Measured at N = 80, 100, 120: α* agrees to 1e-11 and Im α* to
    3e-4 relative (docs/spatial.md). The two tilted collapse checks disagree (the saddle lies
    within 1e-9 of a Stokes line through the end point k = 0): lab_pinch None, the growth stays
    NaN, and the verdict rests on V− > 0. Tolerance 1e-8 relative on α* (convergence 1e-11,
    round-off of the printed 10 digits 1e-10)."""
    res = absolute_instability(_flow(17.0, 0.10), lab_frame=True)
    assert res.verdict == "convective"
    assert res.lab_pinch is None
    assert math.isnan(res.absolute_growth)
    m = re.search(r"k\* = ([^,]+), alpha\* = (\S+) on the continued sheet", res.note)
    assert m, res.note
    k_star, alpha_star = complex(m.group(1)), complex(m.group(2))
    assert k_star.imag == pytest.approx(-1.2952094159, rel=1e-8)
    assert abs(k_star.real) < 1e-7
    assert alpha_star.real == pytest.approx(-6.2272414856, rel=1e-8)
    assert "cannot make the flow absolute" in res.note
    # the edges are those of the default analysis (tests/spatial/test_packet_edges.py)
    assert res.v_minus == pytest.approx(16.2018095, rel=1e-6)
    assert res.v_plus == pytest.approx(18.1392688, rel=1e-6)


@pytest.mark.slow
@pytest.mark.parametrize(("theta", "nu0"), [(16.0, 0.05), (14.0, 0.05)], ids=["P1", "P4"])
def test_p1_p4_lab_frame_saddle_does_not_pinch(theta, nu0):
    """P1: the family ends at the branch point k = 0 (V = c0 = 4.1525) and crosses it on the
    continued sheet; its V = 0 saddle near k = 0 (k* ≈ 4.5e-5i, Re α* ≈ +1.5e-4 at N = 80, but
    3.2e-5i, 1.2e-4 at N = 100 and 2.6e-5i, 9.6e-5 at N = 120: not converged) does not pinch at
    any of the three N: both roots end in the upper half-plane, no crossing of [0, ∞). P4: k* =
    −1.477e-3 − 7.69e-4i, Re α* = −3.490e-3 (−3.484e-3 at N = 100), both crossings on the negative
    real axis, at N = 80 and 100. So lab_pinch False, the growth NaN, the verdict convective from
    V− > 0."""
    res = absolute_instability(_flow(theta, nu0), lab_frame=True)
    assert res.lab_pinch is False, res.note
    assert math.isnan(res.absolute_growth)
    assert cmath.isnan(res.k_saddle)
    assert res.verdict == "convective"
    assert res.converged, res.note
    assert "does not pinch the contour" in res.note
    assert res.to_dict()["lab_pinch"] is False


def test_spatial_policy_coarse_is_checked():
    """A fraction of N outside [0.3, 1] is a one-line error naming the parameter."""
    import dataclasses

    with pytest.raises(ParameterError, match="coarse"):
        dataclasses.replace(DEFAULT_SPATIAL_POLICY, coarse=1.5)
    with pytest.raises(ParameterError, match="coarse"):
        dataclasses.replace(DEFAULT_SPATIAL_POLICY, coarse=0.0)
    assert DEFAULT_SPATIAL_POLICY.coarse == 0.6

"""``chuteflow dispersion --json`` and the Python API decide k_c by one rule (issue 40, item
5; :class:`chuteflow.stability.BranchScan`, paper §4.2, figures 7–9).

Measured (``chuteflow dispersion --theta T --nu0 N --json``, defaults k_max = 0.02, num =
50): P1 (16°, 0.05) k_c = 0.00712487; P4 (14°, 0.05, regime A) k_c = 0.00189515; P2 (16°,
0.08, long-wave stable, figure 7(b)) k_c null, no crossing.
"""

from __future__ import annotations

import json
import warnings

import pytest
from typer.testing import CliRunner

from chuteflow.cli import app
from chuteflow.papers.mitarai2004.points import POINTS

runner = CliRunner()


def _flow(name):
    from chuteflow.closures import ChuteModel
    from chuteflow.steady import solve_steady

    p = POINTS[name]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return solve_steady(p.theta, p.nu0, ChuteModel(roughness=p.roughness))


def _cli(name, *args) -> dict:
    p = POINTS[name]
    result = runner.invoke(
        app, ["dispersion", "--theta", f"{p.theta:g}", "--nu0", f"{p.nu0:g}", "--json", *args]
    )
    assert result.exit_code == 0, result.output
    return json.loads(result.stdout)


@pytest.mark.parametrize(
    ("name", "k_c"),
    [("P1", 0.00712487), ("P4", 0.00189515), ("P2", None)],
)
def test_dispersion_json_k_c_is_the_api_k_c(name, k_c):
    """The same grid gives the same number bit for bit; the API's own default grid (k_max =
    0.05, 40 points) the same k_c to its resolution (1e-6). P2 is long-wave stable: no k_c from
    either (the rule: the first sign change of Re α, when from + to −)."""
    from chuteflow.stability import branch_scan, critical_k

    out = _cli(name, "--k-max", "0.02", "--num", "15")
    flow = _flow(name)
    scan = branch_scan(flow, k_max=0.02, num=15)
    assert out["k_c"] == scan.k_c == critical_k(flow, k_max=0.02, num=15)
    assert out["crossings"] == list(scan.crossings)
    assert out["k_c_converged"] is scan.converged
    assert out["k_cutoff"] == scan.cutoff()
    assert out["peak_growth"] == scan.peak().growth
    if k_c is None:
        assert out["k_c"] is None
        assert out["lambda_c"] is None
        assert out["peak_growth"] < 0
        assert out["crossings"] == []
        return
    assert out["k_c"] == pytest.approx(k_c, rel=2e-6)
    # another grid climbs the resolution ladder elsewhere: k_c moves by its drift (P4: 1.7e-8)
    assert critical_k(flow) == pytest.approx(out["k_c"], rel=1e-6)

"""The reproduce stage ``steady`` (quick mode): figures, checkpoints, all passing."""

from __future__ import annotations

import pytest


@pytest.mark.slow
def test_steady_stage_quick(tmp_path):
    from chuteflow.report import run_reproduce

    rep = run_reproduce(tmp_path, quick=True, stages=["steady"], show_progress=False)
    ids = {cp.id: cp for cp in rep.checkpoints}
    for cid in (
        "steady.range_phi0.05",
        "steady.range_phi0.1",
        "steady.monotonic_theta16",
        "steady.flux_monotonic_phi0.05",
        "steady.flux_minimum_phi0.05",
        "steady.flux_monotonic_phi0.1",
        "steady.flux_minimum_phi0.1",
        "steady.separatrix_phi0.05",
        "steady.convergence",
    ):
        assert cid in ids, cid
        assert ids[cid].passed, (cid, ids[cid].computed)
    for name in ("steadyphase005.png", "steadyphase010.png", "steady.png", "steady01.png"):
        assert (tmp_path / "steady" / name).exists()
    assert (tmp_path / "report.md").exists()

"""The ``transverse`` reproduce stage in quick mode (issue 10): every checked statement holds,
the figures are written and the §5.3 answer is stated."""

from __future__ import annotations

import pytest


@pytest.mark.slow
def test_transverse_stage_quick(tmp_path):
    from chuteflow.report import run_reproduce

    rep = run_reproduce(tmp_path, quick=True, stages=["transverse"], show_progress=False)
    sec = rep.sections["transverse"]
    assert sec.status == "ok", [cp.computed for cp in sec.checkpoints]
    failed = [(cp.id, cp.computed) for cp in sec.checkpoints if cp.passed is False]
    assert not failed, failed
    ids = {cp.id for cp in sec.checkpoints}
    for cid in (
        "transverse.kz0_is_2d",
        "transverse.even_in_kz",
        "transverse.real_at_kx0",
        "transverse.alpha2z",
        "transverse.longitudinal_long_wave",
        "transverse.wavelength",
        "transverse.which_wins",
    ):
        assert cid in ids
    assert any("§5.3" in note for note in sec.notes)
    for fig in sec.figures:
        assert fig.path.stat().st_size > 5_000


def test_recorded_40x40_answer():
    """The §5.3 answer recorded from the 40 × 40 sweeps names the four classes for both
    roughnesses of the paper."""
    from chuteflow.papers.mitarai2004.stages.transverse import SWEEP_ANSWER_40x40

    assert set(SWEEP_ANSWER_40x40) == {0.05, 0.10}
    for text in SWEEP_ANSWER_40x40.values():
        for word in ("stable", "longitudinal only", "transverse only", "both", "faster"):
            assert word in text

"""Stage ``diagrams``: the stability diagrams for φ = 0.05 and φ = 0.10 (§4.2, figures 6,
12), computed with the sweep engine and checked against the paper's statements."""

from __future__ import annotations

from ....report.registry import StageContext, register_stage
from ..points import DIAGRAM_RANGES, DIAGRAM_SHAPE, figure, markers

#: Rows whose least dense flow is followed beyond the grid (every row in full mode).
QUICK_ROW_STEP = 2


def stage_config(roughness: float, quick: bool):
    """The sweep configuration of one diagram of this stage."""
    from ....sweep import SweepConfig

    shape = DIAGRAM_SHAPE[quick][roughness]
    theta_range, nu0_range = DIAGRAM_RANGES[roughness]
    metrics = [
        "steady",
        "kinematic",
        "longwave",
        {"name": "growth", "options": {"stride": 3 if quick else 8}},
    ]
    return SweepConfig.grid(
        roughness,
        shape=shape,
        theta_range=theta_range,
        nu0_range=nu0_range,
        metrics=tuple(metrics),
        markers=markers(roughness),
    )


@register_stage("diagrams", order=40, title="Stability diagrams (§4.2, figures 6 and 12)")
def diagrams(ctx: StageContext) -> None:
    """Stability diagrams in the (h, ν̄) plane for φ = 0.05 and 0.10."""
    import numpy as np

    from ....figures.diagram import save_diagram
    from ....sweep import STATUS, Sweep
    from ..checks import paper_checks
    from ..edges import row_ends

    for phi, fig in ((0.05, "phase005"), (0.10, "phase010")):
        cfg = stage_config(phi, ctx.quick)
        ctx.progress(f"diagram φ = {phi:g} ({cfg.shape[0]}×{cfg.shape[1]})")
        sweep = Sweep(cfg, ctx.path(f"diagram_phi{phi:g}.nc"), fresh=True)
        ds = sweep.run(progress=ctx.progress)
        png = save_diagram(ds, ctx.path(f"diagram_phi{phi:g}.png"))
        ctx.report.add_figure(
            png,
            f"Stability diagram for φ = {phi:g} on a {cfg.shape[0]}×{cfg.shape[1]} "
            f"(θ, ν0(0)) grid, θ ∈ [{cfg.theta[0]:g}, {cfg.theta[-1]:g}]°, ν0(0) ∈ "
            f"[{cfg.nu0[0]:g}, {cfg.nu0[-1]:g}]: unstable (Re α2 > 0) grey, regimes A, B, "
            "C, non-monotonic boundary dashed, θ contours thin, h < 1 hatched; right: "
            "the classification on the grid",
            source=figure(fig),
        )
        ctx.progress(f"φ = {phi:g}: least dense flow of each θ contour")
        rows = range(0, cfg.shape[0], QUICK_ROW_STEP if ctx.quick else 1)
        ends = row_ends(ds, rows=rows)
        for c in paper_checks(ds, ends):
            ctx.report.check(**c)
        st = ds["status"].values
        counts = ", ".join(f"{k} {int((st == v).sum())}" for k, v in STATUS.items())
        s = sweep.stats
        ctx.report.add_note(
            f"φ = {phi:g}: {cfg.size} grid points ({counts}); tasks computed {s.computed}, "
            f"reused {s.reused}; {s.seconds:.1f} s wall, {s.task_seconds:.1f} s in workers "
            f"({s.backend}, {s.workers}). Points without a steady flow lie outside the existence "
            "band of the (θ, ν0) plane; 'not_converged' points are where the steady or "
            "stability solver did not reach its tolerance, or which no continuation from the "
            "row's flows reached ('not attempted'); they are kept out of the diagram and "
            f"listed in the file's message variable. Data: "
            f"{ctx.path(f'diagram_phi{phi:g}.nc').name}."
        )
        if "alpha2_convergence" in ds:
            c = ds["alpha2_convergence"].values
            c = c[np.isfinite(c)]
            if c.size:
                ctx.report.add_note(
                    f"φ = {phi:g}: relative change of α2 between the two finest resolutions: "
                    f"median {np.median(c):.2g}, max {c.max():.2g} (below 1 the sign of Re α2 "
                    "is the same at both)."
                )

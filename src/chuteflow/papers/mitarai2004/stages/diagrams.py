"""Stage ``diagrams``: the stability diagrams for φ = 0.05 and φ = 0.10 (§4.2, figures 6,
12), computed with the sweep engine and checked against the paper's statements."""

from __future__ import annotations

from typing import ClassVar

from ....reduced import Reduced1D
from ....report.registry import StageContext, register_stage
from ....sweep import register_point_function
from ..points import DIAGRAM_RANGES, DIAGRAM_SHAPE, LONGWAVE_STRIDE, figure, markers

#: About this many rows have their least dense flow followed beyond the grid in quick mode
#: (every second row in full mode).
QUICK_ROWS = 6


@register_point_function
class DiagramReduced1D(Reduced1D):
    """The 1D model's criterion (eqs (5.13), (5.14)) at every flow of the full model's
    diagram, for stage ``reduced`` (figure 15 beside figures 6/12, point by point on the
    same grid). It costs one family tangent per flow (~10 ms) instead of a second sweep
    of steady flows; not critical: where it fails, the full model's point is unaffected
    and its ``r1d_*`` values stay missing (the message says why)."""

    name = "reduced1d_diagram"
    critical: ClassVar[bool] = False


def stage_config(roughness: float, quick: bool):
    """The sweep configuration of one diagram of this stage."""
    from ....sweep import SweepConfig
    from .. import adaptive  # registers the point function longwave_strided

    shape = DIAGRAM_SHAPE[quick][roughness]
    theta_range, nu0_range = DIAGRAM_RANGES[roughness]
    metrics = [
        "steady",
        "kinematic",
        DiagramReduced1D(),
        adaptive.StridedLongWave(stride=LONGWAVE_STRIDE[quick]),
        adaptive.StridedGrowth(stride=10 if quick else 12),
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
    import time

    import numpy as np

    from ....figures.diagram import save_diagram
    from ....sweep import STATUS, Sweep
    from ..adaptive import refine_longwave
    from ..checks import paper_checks
    from ..edges import row_ends

    for phi, fig in ((0.05, "phase005"), (0.10, "phase010")):
        cfg = stage_config(phi, ctx.quick)
        ctx.progress(f"diagram φ = {phi:g} ({cfg.shape[0]}×{cfg.shape[1]})")
        # the sweep's own store; the refined diagram (what the figure, the checks and later
        # stages use) is diagram_phi….nc
        sweep = Sweep(cfg, ctx.path(f"diagram_phi{phi:g}_sweep.nc"), fresh=True)
        ds = sweep.run(progress=ctx.progress, keep_flows=True)
        t0 = time.perf_counter()
        ds, counts = refine_longwave(ds, cfg, progress=ctx.progress, flows=sweep.flows)
        t_refine = time.perf_counter() - t0
        ds.to_netcdf(ctx.path(f"diagram_phi{phi:g}.nc"))
        # the refined diagram is what later stages (reduced: point-by-point comparison) use
        ctx.shared.setdefault("diagrams", {})[phi] = ds
        png = save_diagram(ds, ctx.path(f"diagram_phi{phi:g}.png"))
        ctx.report.add_figure(
            png,
            f"Stability diagram for φ = {phi:g} on a {cfg.shape[0]}×{cfg.shape[1]} "
            f"(θ, ν0(0)) grid, θ ∈ [{cfg.theta[0]:g}, {cfg.theta[-1]:g}]°, ν0(0) ∈ "
            f"[{cfg.nu0[0]:g}, {cfg.nu0[-1]:g}]: unstable (Re α2 > 0, filled contour of the "
            "gridded field) grey, regimes A, B, "
            "C, non-monotonic boundary dashed, θ contours thin, h < 1 hatched; right: "
            "the classification on the grid",
            source=figure(fig),
        )
        ctx.progress(f"φ = {phi:g}: least dense flow of each θ contour")
        rows = range(0, cfg.shape[0], max(1, cfg.shape[0] // QUICK_ROWS) if ctx.quick else 2)
        ends = row_ends(ds, rows=rows, flows=sweep.flows)
        sweep.flows = {}
        for c in paper_checks(ds, ends):
            ctx.report.check(**c)
        st = ds["status"].values
        status_counts = ", ".join(f"{k} {int((st == v).sum())}" for k, v in STATUS.items())
        s = sweep.stats
        ctx.report.add_note(
            f"φ = {phi:g}: {cfg.size} grid points ({status_counts}); tasks computed {s.computed}, "
            f"reused {s.reused}; {s.seconds:.1f} s wall, {s.task_seconds:.1f} s in workers "
            f"({s.backend}, {s.workers}). Points without a steady flow lie outside the existence "
            "band of the (θ, ν0) plane (decided by continuation or by the shooting scan); "
            "'not_converged' points are where the steady or stability solver did not reach "
            "its tolerance; they are kept out of the diagram and listed in the file's "
            f"message variable. Data: {ctx.path(f'diagram_phi{phi:g}.nc').name}."
        )
        ctx.report.add_note(
            f"φ = {phi:g}: Re α2 computed by the sweep on every {LONGWAVE_STRIDE[ctx.quick]}rd "
            f"row and column ({counts['coarse']} flows), then exactly at {counts['refined']} "
            "fine points where the coarse values do not decide its sign (cells with a sign "
            f"change or without a computed corner, and each row's least dense flow; "
            f"{counts['failed']} failed) in {t_refine:.1f} s; interpolated between agreeing "
            f"corners at {counts['inferred']} points (variable alpha2_inferred)."
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

"""Stage ``reduced``: the stability diagrams of the 1D model of §5.1.2 (figure 15) beside
the full model's (its nonlinear density waves, §5.2, are stage ``waves``)."""

from __future__ import annotations

import math
from pathlib import Path

from ....report.registry import StageContext, register_stage
from ..points import REDUCED_SHAPE

#: At quick, the 1D diagram is compared on every QUICK_SUBGRID-th row and column of the full one.
QUICK_SUBGRID = 2


def _full_diagram(ctx: StageContext, phi: float):
    """The full model's diagram of stage ``diagrams`` (same run), if there is one."""
    shared = ctx.shared.get("diagrams")
    if isinstance(shared, dict) and phi in shared:
        return shared[phi]
    path = Path(ctx.out) / "diagrams" / f"diagram_phi{phi:g}.nc"
    if path.exists():
        from ....sweep import load_sweep

        return load_sweep(path)
    return None


@register_stage("reduced", order=50, title="Reduced 1D model: stability diagrams (§5.1.2, figure 15)")
def reduced(ctx: StageContext) -> None:
    """The 1D model's stability diagrams beside the full model's."""
    _diagrams(ctx)


def _diagrams(ctx: StageContext) -> None:
    from ....figures.reduced import plot_phase_diagrams, save
    from ....reduced import agreement, reduced_diagram

    shape = REDUCED_SHAPE[ctx.quick]
    reds, fulls, agrs = [], [], []
    for phi in (0.05, 0.10):
        full = _full_diagram(ctx, phi)
        if full is not None and "r1d_margin" in full:
            # the diagram stage computed the 1D criterion at each of its flows
            # (DiagramReduced1D): the 1D diagram on the full model's whole grid, free
            ctx.progress(f"1D diagram φ = {phi:g}: from the full model's diagram")
            ds = _from_full(full)
            ds.to_netcdf(ctx.path(f"reduced_diagram_phi{phi:g}.nc"))
        else:
            grid = None
            if full is not None:
                # the full model's own grid, point by point; at quick every other row and
                # column of it (the 1D diagram costs a steady family per row: 40 x 40 took
                # 11 minutes), which still leaves about a hundred unstable points
                if ctx.quick:
                    full = full.isel(
                        theta=slice(None, None, QUICK_SUBGRID), nu0=slice(None, None, QUICK_SUBGRID)
                    )
                grid = (full["theta"].values, full["nu0"].values)
                shape = (len(grid[0]), len(grid[1]))
            ctx.progress(f"1D diagram φ = {phi:g} ({shape[0]}×{shape[1]})")
            ds = reduced_diagram(
                phi, shape=shape, grid=grid, fresh=True, out=ctx.path(f"reduced_diagram_phi{phi:g}.nc")
            )
        agr = None
        if full is not None and "unstable" in full:
            try:
                agr = agreement(ds, full)
            except ValueError as exc:  # grids do not match: say so
                ctx.report.add_note(f"φ = {phi:g}: no point-by-point comparison ({exc})")
        reds.append(ds)
        fulls.append(full if agr is not None else None)
        agrs.append(agr)
        ok = ds["status"].values == 0
        n_u = int((ds["r1d_unstable"].values[ok] == 1).sum())
        n_sw = int((ds["r1d_short_wave"].values[ok] == 1).sum())
        ctx.report.add_note(
            f"φ = {phi:g}: 1D model on {int(ok.sum())} of {ok.size} grid points with a steady "
            f"flow: {n_u} unstable, {n_sw} of them with (ρ̄T̄)' < 0 (every wavelength grows, "
            "no k_c: the depth-integrated pressure ρ̄T̄ decreases with ρ̄ because T̄ falls "
            "steeply along the family)."
        )
        src = "§5.1.2: 'the stability diagrams are qualitatively similar to those of the original model'"
        if agr is None:
            ctx.report.check(
                f"reduced.agreement_phi{phi:g}",
                source="§5.1.2, figure 15 vs figures 6/12",
                statement=src,
                passed=None,
                computed="not compared: no full-model diagram of stage 'diagrams' in this run "
                "(run it first: chuteflow reproduce --stage diagrams --stage reduced)",
            )
        else:
            frac = agr["fraction"]
            n_full = agr["both_unstable"] + agr["only_full_unstable"]
            recall = agr["both_unstable"] / n_full if n_full else math.nan
            n_stable = agr["both_stable"] + agr["only_1d_unstable"]
            ctx.report.check(
                f"reduced.agreement_phi{phi:g}",
                source="§5.1.2, figure 15 vs figures 6/12",
                statement=src + " (taken as: the 1D criterion finds ≥ 90 % of the full model's "
                "unstable grid points)",
                computed=f"{100 * frac:.0f} % of {agr['compared']} common grid points "
                f"classified alike; the 1D model finds {agr['both_unstable']} of the "
                f"{n_full} unstable points of the full model ({100 * recall:.0f} %) and "
                f"calls {agr['only_1d_unstable']} of its {n_stable} "
                f"stable points unstable ({agr['short_wave']} compared points have "
                f"(ρ̄T̄)' < 0); {agr['thin_excluded']} points with h < 1 left out "
                "(not examined in the paper)",
                passed=bool(recall >= 0.9),
                detail=str(agr),
            )
    png = save(
        plot_phase_diagrams(
            reds, [f for f in fulls if f is not None] or None, agreement=agrs if any(agrs) else None
        ),
        ctx.path("phaseoned.png"),
    )
    ctx.report.add_figure(
        png,
        "Stability diagrams of the 1D model in the (h, ν̄) plane for φ = 0.05 (left) and "
        "0.10 (right): unstable by the criterion (ρ̄U')² > (ρ̄T̄)' grey, unstable at every "
        "wavelength ((ρ̄T̄)' < 0) dark grey, non-monotonic boundary dashed; second row "
        "(when stage 'diagrams' ran): the full model, Re α₂ > 0; red ×: classified "
        "differently.",
        source="figure 15",
    )


def _from_full(full):
    """The 1D diagram from a full-model diagram that carries the ``r1d_*`` variables of
    :class:`~chuteflow.papers.mitarai2004.stages.diagrams.DiagramReduced1D`: the steady
    quantities and the 1D criterion, with ``status`` 0 where the 1D model was evaluated
    (a steady flow exists, whatever the full model's stability solver did there)."""
    import numpy as np

    keep = [v for v in full.data_vars if v.startswith("r1d_")]
    keep += [v for v in ("h", "nu_mean", "rho_bar", "Q", "T_mean", "monotonic") if v in full]
    ds = full[keep].copy()
    has = np.isfinite(full["r1d_margin"].values)
    status = np.where(has, 0, np.where(full["status"].values == 0, 2, full["status"].values))
    ds["status"] = (
        ("theta", "nu0"),
        status.astype(np.int8),
        {
            "long_name": "0: steady flow with the 1D criterion; otherwise the full diagram's "
            "status (1 no steady flow, 2 not converged, 3 error)",
            "flag_values": np.array([0, 1, 2, 3], dtype=np.int8),
            "flag_meanings": "ok no_steady_flow not_converged error",
        },
    )
    ds.attrs["title"] = "1D model stability diagram (Mitarai & Nakanishi figure 15)"
    ds.attrs["engine"] = "from the full model's diagram sweep (metric reduced1d_diagram)"
    return ds

"""Stage ``closures`` (full run only): the paper's points with other kinetic-theory closures.

The paper uses Lun et al. (1984) without their density-gradient heat flux κ_h∇ν (footnote
to eq. (2.7): "its influence on the steady solutions is small in the considered parameter
region"). This stage recomputes the paper's named flows P1–P5 and Q1–Q3 with

* ``lun`` — the paper's closures (reference);
* ``lun_full`` — Lun et al. with κ_h (:class:`~chuteflow.closures.LunFullClosure`);
* ``mfix-lun`` — MFiX's ``KT_TYPE = LUN_1984`` (viscosity × (2 + α)/3, α = 1.6,
  Carnahan–Starling g0; :meth:`~chuteflow.closures.ChuteModel.preset`);
* ``garzo_dufty`` — Garzó & Dufty (1999) (:class:`~chuteflow.closures.GarzoDuftyClosure`),

and reports, for each, the steady flow (h, Q0), the long-wave coefficients α1, α2 (eq. 4.4;
regime and verdict) and the transverse long-wave coefficient α2z (k_x = 0). The footnote's
statement is checked with ``lun_full``. In quick mode the stage only says that it is a
full-run stage, so the quick run's time is unchanged.
"""

from __future__ import annotations

from ....report.registry import StageContext, register_stage

#: The closure sets compared: (label, ChuteModel keyword arguments or a preset name).
CLOSURE_SETS = (
    ("lun", {"transport": "lun"}),
    ("lun_full", {"transport": "lun_full"}),
    ("mfix-lun", "mfix-lun"),
    ("garzo_dufty", {"transport": "garzo_dufty"}),
)
#: "small" of the footnote, taken as: h and Q0 change by less than this fraction.
SMALL = 0.05


@register_stage(
    "closures", order=80, title="Other closures: κ_h, MFiX's Lun, Garzó–Dufty (full run)", independent=True
)
def closures(ctx: StageContext) -> None:
    """The paper's points with lun, lun_full, mfix-lun and garzo_dufty (full run only)."""
    if ctx.quick:
        ctx.report.add_note("Full-run stage (chuteflow reproduce --full): nothing computed in quick mode.")
        return
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        _run(ctx)


def _model(spec, roughness):
    from ....closures import ChuteModel

    if isinstance(spec, str):
        return ChuteModel.preset(spec, roughness=roughness)
    return ChuteModel(roughness=roughness, **spec)


def _point(spec, p) -> dict:
    from ....errors import ChuteflowError
    from ....longwave import longwave, transverse_longwave
    from ....steady import solve_steady

    rec: dict = {}
    try:
        flow = solve_steady(theta=p.theta, nu0=p.nu0, model=_model(spec, p.roughness), strict=True)
    except ChuteflowError as exc:
        rec["error"] = str(exc).split(":")[0]
        return rec
    rec["flow"] = flow
    rec["h"], rec["Q"] = float(flow.h), float(flow.Q)
    try:
        lw = longwave(flow, rtol=0.2, strict=False)
        rec["alpha1"], rec["alpha2"] = float(lw.alpha1.imag), float(lw.alpha2.real)
        rec["alpha2_conv"], rec["unstable"] = float(lw.alpha2_convergence), bool(lw.unstable)
    except ChuteflowError as exc:
        rec["lw_error"] = str(exc)[:80]
    try:
        tz = transverse_longwave(flow, rtol=1e-3)
        rec["alpha2z"], rec["alpha2z_conv"] = float(tz.alpha2_z.real), float(tz.convergence_alpha2)
    except ChuteflowError as exc:
        rec["tz_error"] = str(exc)[:80]
    return rec


def _run(ctx: StageContext) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from ...._threads import limit_blas_threads
    from ..points import POINTS

    limit_blas_threads(1)
    rep = ctx.report
    results: dict[str, dict[str, dict]] = {}
    for label, spec in CLOSURE_SETS:
        results[label] = {}
        for p in POINTS.values():
            ctx.progress(f"{label} at {p.name}")
            results[label][p.name] = _point(spec, p)

    rows = ["| closure | point | h | Q0 | Im α1 | Re α2 (unstable?) | α2z |", "|---|---|---|---|---|---|---|"]
    for label, by_point in results.items():
        for name, r in by_point.items():
            if "error" in r:
                rows.append(f"| {label} | {name} | no steady flow | | | | |")
                continue
            a2 = f"{r['alpha2']:.4g} ({'yes' if r['unstable'] else 'no'})" if "alpha2" in r else "—"
            a1 = f"{r['alpha1']:.4g}" if "alpha1" in r else "—"
            az = f"{r['alpha2z']:.4g}" if "alpha2z" in r else "—"
            rows.append(f"| {label} | {name} | {r['h']:.4g} | {r['Q']:.4g} | {a1} | {a2} | {az} |")
    rep.add_note("\n".join(rows))

    # the footnote: κ_h∇ν changes the steady flows little (lun_full against lun)
    changes = []
    for name in POINTS:
        a, b = results["lun"][name], results["lun_full"][name]
        if "h" in a and "h" in b:
            changes.append((max(abs(b["h"] / a["h"] - 1), abs(b["Q"] / a["Q"] - 1)), name))
    worst = max(changes) if changes else (float("nan"), "none")
    rep.check(
        "closures.footnote_kappa_h",
        source="footnote to eq. (2.7)",
        statement="the influence of the term κ_h∇ν on the steady solutions is small "
        f"(taken as: h and Q0 change by less than {100 * SMALL:g} % at P1–P5, Q1–Q3)",
        computed=f"largest relative change {100 * worst[0]:.2f} % (at {worst[1]}; "
        f"{len(changes)} points with a steady flow under both closures)",
        passed=bool(changes) and worst[0] < SMALL,
    )
    verdict_changes = [
        f"{label} at {name}"
        for label in ("lun_full", "mfix-lun", "garzo_dufty")
        for name in POINTS
        if "unstable" in results[label][name]
        and "unstable" in results["lun"][name]
        and results[label][name]["unstable"] != results["lun"][name]["unstable"]
    ]
    rep.add_note(
        "Long-wave verdicts that differ from the paper's closure: "
        + (", ".join(verdict_changes) if verdict_changes else "none")
        + ". garzo_dufty: "
        + str(sum("error" in r for r in results["garzo_dufty"].values()))
        + " of 8 points without a steady flow (its heat flux μ∇n = Tκ0μ*∇ln n stays finite in the"
        " dilute atmosphere and drains energy through the top; see the docs' closures page)."
    )

    fig, axes = plt.subplots(1, 3, figsize=(11, 3.8), layout="constrained")
    y = np.linspace(0.0, 40.0, 300)
    for label, _spec in CLOSURE_SETS:
        r = results[label]["P1"]
        if "flow" not in r:
            continue
        prof = r["flow"].profiles(y)
        for ax, key in zip(axes, ("nu", "u", "T")):
            ax.plot(prof[key], y, label=label)
    for ax, key in zip(axes, ("ν0", "u0", "T0")):
        ax.set(xlabel=key, ylabel="y")
    axes[0].legend()
    fig.suptitle("P1 (θ = 16°, ν0(0) = 0.05, φ = 0.05) with other closures")
    path = ctx.stage_dir / "closures_P1_profiles.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    rep.add_figure(path, "Steady profiles at P1 with the closures that have a steady flow there.")

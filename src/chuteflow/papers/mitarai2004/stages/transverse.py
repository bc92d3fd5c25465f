"""Stage ``transverse``: three-dimensional perturbations and the question of §5.3.

The paper studies perturbations uniform across the slope and asks (§5.3) whether its
longitudinal long-wave instability and the transverse instability of Forterre & Pouliquen
(2002) "interfere or not by the full three dimensional analysis". This stage checks the 3D
operator (k_z = 0 is the 2D problem, α is even in k_z, the problem is real at k_x = 0), the
transverse long-wave coefficient α2z against eigenvalues, whether the transverse instability
is long-wave or at finite wavelength (computed, not assumed), and draws the cross-section of
the transverse mode, the growth rate over (k_x, k_z) and a small "which instability wins"
diagram from the sweep metric ``transverse``.
"""

from __future__ import annotations

import math

from ....report.registry import StageContext, register_stage

#: P1 of the paper (θ = 16°, ν0(0) = 0.05, φ = 0.05).
P1 = (16.0, 0.05, 0.05)
#: The "which wins" grid: quick, full (θ in degrees, ν0(0)); φ = 0.05.
WINNER_GRID = {
    True: ((15.0, 16.0, 17.0), (0.03, 0.05, 0.08, 0.12)),
    False: (
        (14.0, 14.5, 15.0, 15.5, 16.0, 16.5, 17.0, 17.5),
        (0.02, 0.03, 0.04, 0.05, 0.06, 0.08, 0.1, 0.12, 0.15),
    ),
}
#: The answer to §5.3 on the 40 × 40 diagrams over the paper's ranges (DIAGRAM_RANGES), from
#: ``chuteflow diagram --roughness PHI --grid 40x40 --theta-range … --nu0-range …
#: --metrics steady,longwave,transverse`` (metric ``transverse`` version 5); recorded here,
#: not recomputed by this stage (179.4 s and 150.7 s wall on 2 cores). Version 4 lost the
#: (real) transverse branch at its flat maximum in 3 flows at φ = 0.05 (growth ~1e-8 instead
#: of 4e-4 … 3e-3; TransverseTracker.advance's step halvings, 6 then, 10 now). Version 3 lost
#: the longitudinal branch at k ~ 1e-5 in thick dilute flows (the tracker's first step from
#: k = 0 off α1 k, TrackingPolicy.first_step_min) and named no winner at 55
#: (φ = 0.05) and 15 (φ = 0.10) of the points unstable both ways; every one has a verdict
#: now. Counts are of the grid points with a steady flow.
SWEEP_ANSWER_40x40 = {
    0.05: "φ = 0.05 (θ 12–18°, ν0(0) 0.01–0.25; 1168 flows): stable 681, longitudinal only 299, "
    "transverse only 10, both 178. Where both occur the longitudinal instability grows faster "
    "at 141 points (median 7.6×, 1.03× to ~3e8×; λx = 2750–32000 σ, 64–1830 h; h = 12–147) and "
    "the transverse one at 37 thick dilute flows (θ = 16.9–18°, ν̄ = 0.003–0.025, h = 21–159; by "
    "1.0–44×, median 1.8×, growth 1.6e-4–4.0e-3, λz = 750–2970 σ ≈ 16–71 h). The 10 "
    "transverse-only points lie on a line θ = 16.8–18°, ν0(0) = 0.047–0.072 (h = 19–31) just "
    "outside the longitudinal unstable region (Re α2 < 0, α2z > 0). At 10 longitudinal-only "
    "points (θ = 16.3–17.8°, ν0(0) = 0.10–0.24, h = 8–11) the longitudinal growth rate is not "
    "known (its eigenvector is not resolved at N = 48, 60 and 75).",
    0.10: "φ = 0.10 (θ 16.5–22.5°, ν0(0) 0.01–0.30; 1039 flows): stable 721, longitudinal only 256, "
    "transverse only 2, both 60. Where both occur the longitudinal instability grows faster at "
    "54 points (median 8.5×, 1.06× to 4e4×; λx = 5770–32600 σ, 89–1670 h; h = 19–142) and the "
    "transverse one at 6 thick dilute flows (θ = 22.0–22.5°, ν̄ = 0.007–0.012, h = 37–64; by "
    "1.01–395×, median 2.4×, growth 1.4e-4–1.1e-3, λz = 1200–1890 σ ≈ 23–51 h). The 2 "
    "transverse-only points: θ = 22.3–22.5°, ν0(0) = 0.040 (h = 42–44). At 12 "
    "longitudinal-only points (θ = 20.3–22.0°, ν0(0) = 0.12–0.30, h = 9–15) the longitudinal "
    "growth rate is not known.",
}
#: Round-off of the assembled operator, relative to its largest entry.
OPERATOR_TOL = 1e-12
#: α2z from eigenvalues at k_z = 1e-5, 3e-5 extrapolated to 0: 9e-5 relative measured
#: (tests/stability/test_transverse.py), with margin.
A2Z_RTOL = 3e-4


@register_stage(
    "transverse", order=60, title="Three dimensions: transverse perturbations and §5.3", independent=True
)
def transverse_stage(ctx: StageContext) -> None:
    """Verification of the 3D operator, α2z, the transverse band and which instability wins."""

    _run(ctx)


def _run(ctx: StageContext) -> None:
    import numpy as np

    from ....closures import ChuteModel
    from ....figures.transverse import cross_section_figure, winner_figure
    from ....longwave.spanwise import transverse
    from ....stability import OperatorCache, RejectionPolicy, least_stable, stability_operator
    from ....stability.modes import nearest_eigenpair
    from ....stability.realform import real_form
    from ....stability.transverse import least_stable_3d
    from ....stability.transverse_tracking import TransverseTracker
    from ....steady import solve_steady
    from ....sweep import SweepConfig, run_sweep

    rep = ctx.report
    th, nu0, phi = P1
    flow = solve_steady(th, nu0, ChuteModel(roughness=phi), strict=True)
    ctx.progress("3D operator identities")
    n = 48 if ctx.quick else 80
    # both on the plain Chebyshev grid (3D operators always are; 2D ones default to the
    # sinh-mapped grid), so that the matrices compare entry by entry
    plain = OperatorCache(mapped=False)
    op2, op3 = stability_operator(flow, n, cache=plain), stability_operator(flow, n, True, cache=plain)
    m = n + 1
    A2 = op2.matrix(0.002)
    A3 = op3.matrix(0.002, 0.0)
    idx = np.r_[0 : 3 * m, 4 * m : 5 * m]  # (ν, u, v, T) of the 3D field order (ν, u, v, w, T)
    wblk = slice(3 * m, 4 * m)
    scale = np.abs(A3).max()
    d2 = float(np.abs(A3[np.ix_(idx, idx)] - A2).max() / scale)
    cpl = float(
        max(np.abs(A3[wblk][:, idx]).max(), np.abs(A3[np.ix_(idx, range(3 * m, 4 * m))]).max()) / scale
    )
    rep.check(
        "transverse.kz0_is_2d",
        source="the 3D operator; paper eq. (4.4)",
        statement="At k_z = 0 the 3D operator is the 2D one and ŵ decouples.",
        computed=f"P1, k_x = 0.002, N = {n}: max |A3 − A2| = {d2:.1e}, ŵ coupling {cpl:.1e} (relative)",
        passed=bool(d2 < OPERATOR_TOL and cpl < OPERATOR_TOL),
    )
    a_p, _ = nearest_eigenpair(op3.pencil(0.002, 0.002), 9.4e-4 - 0.015j)
    a_m, _ = nearest_eigenpair(op3.pencil(0.002, -0.002), a_p)
    rep.check(
        "transverse.even_in_kz",
        source="z → −z symmetry of the base flow",
        statement="α(k_x, −k_z) = α(k_x, k_z).",
        computed=f"(0.002, ±0.002): α = {a_p:.10g} and {a_m:.10g}, |Δ| = {abs(a_p - a_m):.1e}",
        passed=bool(abs(a_p - a_m) <= 1e-10 * abs(a_p)),
    )
    Ar, _, _ = real_form(op3.pencil(0.0, 0.002))
    rep.check(
        "transverse.real_at_kx0",
        source="the 3D operator at k_x = 0",
        statement="At k_x = 0 the problem is real (after ŵ → iŵ): eigenvalues real or in pairs.",
        computed=f"P1, k_z = 0.002: the pencil is real after ŵ → iŵ ({Ar.shape[0]} unknowns)",
        passed=True,
    )

    ctx.progress("α2z and the transverse band at P1")
    res = transverse(flow, num=30)
    tr = TransverseTracker(flow, alpha2z=res.alpha2_z)
    k1, k3 = 1e-5, 3e-5
    m1, m3 = tr.mode(k1), tr.mode(k3)
    if m1 is None or m3 is None or res.kz_max is None:
        raise RuntimeError("the transverse branch at P1 was lost at small k_z")
    f1 = m1.alpha.real / k1**2
    f3 = m3.alpha.real / k3**2
    kz_star = float(res.kz_max)
    lam = 2 * math.pi / kz_star
    cut = math.nan if res.kz_cutoff is None else float(res.kz_cutoff)
    f0 = f1 - (f3 - f1) * k1 / (k3 - k1)
    rep.check(
        "transverse.alpha2z",
        source="analogue of Appendix B",
        statement="α(0, k_z) = α2z k_z² + O(|k_z|³), α2z from perturbation theory at k = 0.",
        computed=f"P1: α2z = {res.alpha2_z:.6g} (bordered solve), {f0:.6g} from Re α/k_z² at "
        f"k_z = 1e-5, 3e-5 extrapolated to 0; lubrication formula {res.alpha2_z_lubrication:.6g}",
        passed=bool(abs(f0 - res.alpha2_z) <= A2Z_RTOL * abs(res.alpha2_z)),
    )
    # the longitudinal instability: long-wave (Re α ∝ k² as k → 0, band 0 < k < k_c)
    lo = [least_stable(flow, k).alpha.real for k in (1e-5, 2e-5)]
    expo = math.log(lo[1] / lo[0]) / math.log(2.0)
    rep.check(
        "transverse.longitudinal_long_wave",
        source="§4.2, §5.3",
        statement="The longitudinal instability is long-wave: Re α ∝ k² from k = 0.",
        computed=f"P1: d ln Re α / d ln k = {expo:.3f} at k = 1e-5 … 2e-5",
        passed=bool(abs(expo - 2.0) < 0.05),
    )
    # the transverse one: computed — the band, and the least-stable modes at k_z ~ 1/h
    pol = RejectionPolicy(n_max=125 if ctx.quick else 256)
    kzs = (1.0 / flow.h,) if ctx.quick else (1.0 / flow.h, 3.0 / flow.h)
    rolls = [(kz, least_stable_3d(flow, 0.0, kz, policy=pol, strict=False)) for kz in kzs]
    roll_txt = "; ".join(
        f"k_z = {kz:.3g} (≈ {kz * flow.h:.0f}/h): Re α = {mm.alpha.real:.3g}"
        + ("" if mm.physical else " (unresolved)")
        for kz, mm in rolls
    )
    finite = any(mm.alpha.real > 0 for _, mm in rolls)
    rep.check(
        "transverse.wavelength",
        source="§5.3; Forterre & Pouliquen (2002)",
        statement="Forterre & Pouliquen's transverse instability is at finite wavelength (rolls, k_z ~ 1/h); "
        "here it is computed, not assumed.",
        computed=f"P1 (h = {flow.h:.3g}): transverse band 0 < k_z < {cut:.4g} with k_z* = "
        f"{kz_star:.4g} (λz = {lam:.4g} σ ≈ {lam / flow.h:.0f} h), "
        f"growth {res.growth_max:.3g}, stationary; {roll_txt}",
        passed=None,
        detail="This model's transverse instability is long-wave (lateral clustering, α2z > 0), not "
        "finite-wavelength rolls" + (" — but a growing mode was found at k_z ~ 1/h" if finite else ""),
    )
    ctx.progress("cross-section of the transverse mode")
    mode = tr.mode(kz_star)
    if mode is None:  # pragma: no cover - the branch reached k_z* in transverse() already
        raise RuntimeError("the transverse branch at P1 was lost before k_z*")
    png = cross_section_figure(mode, flow, ctx.path("transverse_mode.png"))
    rep.add_figure(
        png,
        f"The transverse mode at P1, k_z* = {kz_star:.3g}: density (a) and temperature (b) "
        "perturbations in the (z, y) cross-section over one wavelength, (ŵ, v̂) as arrows: "
        "denser columns are colder (lateral clustering), no closed roll cells.",
        source="paper §5.3 (the transverse question)",
    )

    ctx.progress("which instability wins")
    thetas, nus = WINNER_GRID[ctx.quick]
    cfg = SweepConfig(
        theta=thetas,
        nu0=nus,
        roughness=0.05,
        chunk=4,
        metrics=("steady", "kinematic", "longwave", "transverse"),
    )
    ds = run_sweep(cfg, workers=1)
    ds.to_netcdf(ctx.path("winner_phi0.05.nc"))
    png = winner_figure(ds, ctx.path("winner_phi0.05.png"))
    rep.add_figure(
        png,
        "Which instability wins over (h, ν̄), φ = 0.05: stable, longitudinal only (the paper's "
        "unstable regions), transverse only, both (sweep metric 'transverse').",
        source="§5.3",
    )
    w = np.asarray(ds.winner.values).ravel()
    fast = np.asarray(ds.fastest.values).ravel()
    both = w == 3
    counts = {
        name: int((w == c).sum()) for c, name in {0: "stable", 1: "long.", 2: "trans.", 3: "both"}.items()
    }
    if both.any():
        answer = _which_wins(ds, both, fast)
    else:
        answer = "no point of this grid is unstable in both directions"
    rep.add_note(
        "Answer to the question of §5.3 (this model, linear theory): the transverse instability "
        "is long-wave like the longitudinal one — lateral clustering of denser, colder columns "
        "where the depth-integrated lateral pressure falls with the mass (α2z > 0), not "
        f"finite-wavelength rolls; {answer}. Counts on the grid: {counts}."
    )
    recorded = [txt for txt in SWEEP_ANSWER_40x40.values() if txt]
    if recorded:
        rep.add_note(
            "§5.3 on the 40 × 40 diagrams (recorded from the sweep metric 'transverse', version 5, "
            "not recomputed here): " + " ".join(recorded)
        )
    rep.check(
        "transverse.which_wins",
        source="§5.3",
        statement="Where both instabilities occur, which grows faster and at what wavelength.",
        computed=answer,
        passed=None,
    )


def _which_wins(ds, both, fast) -> str:
    """Where both directions are unstable: which grows faster, by how much, at what λ."""
    import numpy as np

    def col(name):
        return np.asarray(ds[name].values, dtype=float).ravel()[both]

    gl, gt = col("longitudinal_growth_max"), col("transverse_growth_max")
    kx, kz, h = col("longitudinal_kx_max"), col("transverse_kz_max"), col("h")
    f = fast[both]
    parts = []
    for code, name, num, den, k in ((1, "longitudinal", gl, gt, kx), (2, "transverse", gt, gl, kz)):
        sel = f == code
        if sel.any():
            r = num[sel] / den[sel]
            lam = 2 * math.pi / k[sel]

            def rng(x, fmt):
                return f"{format(np.nanmin(x), fmt)}–{format(np.nanmax(x), fmt)}"

            parts.append(
                f"the {name} one grows faster at {int(sel.sum())} (by {rng(r, '.3g')}×, "
                f"λ = {rng(lam, '.4g')} σ, h = {rng(h[sel], '.3g')})"
            )
    unknown = int((f < 0).sum())
    if unknown:
        parts.append(f"{unknown} undecided (longitudinal branch not followed)")
    return f"where both occur ({int(both.sum())} points) " + "; ".join(parts)

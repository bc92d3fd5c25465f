"""The paper's statements about the stability diagrams (§4.2, §5), checked on a sweep Dataset.

Each check returns a dict with ``id``, ``source``, ``statement``, ``computed``, ``passed``
(the fields of :class:`chuteflow.report.Checkpoint`); :func:`paper_checks` runs those that
apply to the Dataset's roughness.
"""
from __future__ import annotations

import math

import numpy as np

from .classify import REGIMES, regime_summary

__all__ = ["paper_checks", "check_regimes_placed", "check_low_density_unstable",
           "check_C_monotonicity", "check_markers", "check_finite_k"]

#: Paper's stability of the marked points (§4.2: P1 in B, P4 in A, P5 in C are unstable,
#: P2 and P3 stable; Q3 unstable).
MARKER_EXPECT = {"P1": True, "P2": False, "P3": False, "P4": True, "P5": True, "Q3": True}


def _phi(ds):
    return float(ds.attrs.get("roughness", math.nan))


def check_regimes_placed(ds) -> dict:
    """Three unstable regimes: A at small h & small ν̄, B at large h & small ν̄, C at large
    h & large ν̄ (medians of each regime's grid points)."""
    s = regime_summary(ds)
    have = {k: s.get(k, {}).get("points", 0) for k in ("A", "B", "C")}
    txt = ", ".join(f"{k}: {have[k]} pts" + (
        f" (median h {s[k]['h_median']:.3g}, ν̄ {s[k]['nu_mean_median']:.3g})"
        if have[k] else "") for k in ("A", "B", "C"))
    ok = all(have.values())
    if ok:
        A, B, C = s["A"], s["B"], s["C"]
        ok = (A["h_median"] < B["h_median"] and A["h_median"] < C["h_median"]
              and C["nu_mean_median"] > A["nu_mean_median"]
              and C["nu_mean_median"] > B["nu_mean_median"])
    return {"id": f"diagrams.phi{_phi(ds):g}.regimes", "source": "§4.2, fig phase005/phase010",
            "statement": "three unstable regimes: A (small h, small ν̄), B (large h, small ν̄), "
                         "C (large h, large ν̄)",
            "computed": txt, "passed": ok}


def check_low_density_unstable(ds) -> dict:
    """Along each θ row, the least dense flow found is unstable in regime A or B."""
    reg = ds["regime"].values
    st = ds["status"].values
    rows, bad = 0, []
    for i, th in enumerate(ds["theta"].values):
        ok = np.nonzero(st[i] == 0)[0]
        if len(ok) == 0:
            continue
        rows += 1
        j = ok[0]
        if reg[i, j] not in (REGIMES["A"], REGIMES["B"]):
            bad.append(f"θ={th:.3g}° (ν0={ds['nu0'].values[j]:.3g}: "
                       f"{_regime_name(reg[i, j])})")
    return {"id": f"diagrams.phi{_phi(ds):g}.low_density",
            "source": "§4.2",
            "statement": "lowering the density along a fixed-θ contour always reaches regime "
                         "A or B (the flow with low enough density is always unstable)",
            "computed": f"{rows - len(bad)} of {rows} θ rows end in A or B at their lowest "
                        f"density" + (f"; not: {', '.join(bad[:6])}" if bad else ""),
            "passed": rows > 0 and not bad}


def _regime_name(code):
    return {-1: "unknown", 0: "stable", 1: "A", 2: "B", 3: "C"}.get(int(code), "?")


def check_C_monotonicity(ds) -> dict:
    """φ = 0.05: C inside the non-monotonic region; φ = 0.10: C covers part of the monotonic
    region too."""
    reg = ds["regime"].values
    mono = ds["monotonic"].values
    selC = reg == REGIMES["C"]
    n = int(selC.sum())
    nm = int((mono[selC] == 1).sum())
    phi = _phi(ds)
    if math.isclose(phi, 0.05):
        statement = "regime C lies inside the region of non-monotonic density profiles"
        passed = n > 0 and nm == 0
    else:
        statement = "regime C also covers part of the region of monotonic density profiles"
        passed = n > 0 and nm > 0
    return {"id": f"diagrams.phi{phi:g}.C_monotonic", "source": "§4.2, §5 (discussion)",
            "statement": statement,
            "computed": f"{nm} of {n} grid points of C have a monotonic ν0(y)",
            "passed": passed}


def check_markers(ds) -> list[dict]:
    """P1, P4, P5, Q3 unstable; P2, P3 stable (sign of Re α2 at the point itself)."""
    out = []
    if "marker" not in ds.dims or "marker_unstable" not in ds:
        return out
    for m, name in enumerate(ds["marker"].values):
        name = str(name)
        if name not in MARKER_EXPECT:
            continue
        want = MARKER_EXPECT[name]
        u = int(ds["marker_unstable"].values[m])
        a2 = float(ds["marker_alpha2_re"].values[m])
        reg = _regime_name(ds["marker_regime"].values[m]) if "marker_regime" in ds else "?"
        th, nu = float(ds["marker_theta"].values[m]), float(ds["marker_nu0"].values[m])
        extra = ""
        if "marker_growth_max" in ds and np.isfinite(ds["marker_growth_max"].values[m]):
            extra = (f", max Re α on the k grid {ds['marker_growth_max'].values[m]:.3g} at "
                     f"k = {ds['marker_k_growth_max'].values[m]:.3g}")
        out.append({"id": f"diagrams.{name}", "source": "§4.2, figs disp, disp-AC, disp01",
                    "statement": f"{name} (θ = {th:g}°, ν0(0) = {nu:g}) is "
                                 f"{'unstable' if want else 'stable'}",
                    "computed": (f"Re α2 = {a2:.4g} → {'unstable' if u == 1 else 'stable'}"
                                 f" (regime {reg}){extra}") if u >= 0 else
                                f"not computed: {ds['marker_message'].values[m]}",
                    "passed": u >= 0 and (u == 1) == want})
    return out


def check_finite_k(ds) -> dict | None:
    """Sampled dispersion relations agree with the long-wave criterion."""
    if "finite_k_disagrees" not in ds:
        return None
    d = ds["finite_k_disagrees"].values
    n = int((d >= 0).sum())
    failed = int(((ds["dispersion_sampled"].values == 1) & ~np.isfinite(ds["growth_max"].values)
                  & (ds["status"].values == 0)).sum())
    bad = np.argwhere(d == 1)
    where = [f"(θ={ds['theta'].values[i]:.3g}°, ν0={ds['nu0'].values[j]:.3g}: Re α2 "
             f"{ds['alpha2_re'].values[i, j]:.3g}, max Re α {ds['growth_max'].values[i, j]:.3g}"
             f" at k={ds['k_growth_max'].values[i, j]:.3g})" for i, j in bad[:8]]
    return {"id": f"diagrams.phi{_phi(ds):g}.finite_k",
            "source": "§4.2 (all unstable modes are long-wave), ERRATA numerical notes",
            "statement": "no finite-k instability missed by the sign of Re α2 (dispersion "
                         "relation sampled on a k grid at a subset of points)",
            "computed": f"{len(bad)} of {n} sampled points disagree" +
                        (": " + "; ".join(where) if where else "") +
                        (f"; {failed} sampled points where the branch could not be tracked "
                         "(listed in the file's message)" if failed else ""),
            "passed": n > 0 and len(bad) == 0}


def paper_checks(ds) -> list[dict]:
    """All checks that apply to this Dataset (needs the stability metrics)."""
    if "regime" not in ds:
        return []
    out = [check_regimes_placed(ds), check_low_density_unstable(ds)]
    phi = _phi(ds)
    if math.isclose(phi, 0.05) or math.isclose(phi, 0.10):
        out.append(check_C_monotonicity(ds))
    out += check_markers(ds)
    fk = check_finite_k(ds)
    if fk is not None:
        out.append(fk)
    return out

"""The paper's statements about the stability diagrams (§4.2, §5), checked on a sweep Dataset.

Each check returns a dict with ``id``, ``source``, ``statement``, ``computed``, ``passed``
(the fields of :class:`chuteflow.report.Checkpoint`); :func:`paper_checks` runs those that
apply to the Dataset's roughness.
"""

from __future__ import annotations

import math

import numpy as np

from ...sweep.regimes import REGIMES, regime_summary
from .points import PAPER_UNSTABLE

__all__ = [
    "paper_checks",
    "check_regimes_placed",
    "check_low_density_unstable",
    "check_C_monotonicity",
    "check_markers",
    "check_finite_k",
]

#: Paper's stability of the marked points (:data:`~.points.PAPER_UNSTABLE`).
MARKER_EXPECT = PAPER_UNSTABLE


def _phi(ds):
    return float(ds.attrs.get("roughness", math.nan))


def check_regimes_placed(ds) -> dict:
    """Three unstable regimes placed as in §4.2: A on the small-h side of B and C (median h);
    C at the large-ν̄ end of the diagram, above A and B (largest ν̄ reached)."""
    s = regime_summary(ds)
    have = {k: s.get(k, {}).get("points", 0) for k in ("A", "B", "C")}
    txt = ", ".join(
        f"{k}: {have[k]} pts"
        + (f" (median h {s[k]['h_median']:.3g}, ν̄ up to {s[k]['nu_mean_max']:.3g})" if have[k] else "")
        for k in ("A", "B", "C")
    )
    ok = all(have.values())
    if ok:
        A, B, C = s["A"], s["B"], s["C"]
        ok = (
            A["h_median"] < B["h_median"]
            and A["h_median"] < C["h_median"]
            and C["nu_mean_max"] > A["nu_mean_max"]
            and C["nu_mean_max"] > B["nu_mean_max"]
        )
    return {
        "id": f"diagrams.phi{_phi(ds):g}.regimes",
        "source": "§4.2, figures 6/12",
        "statement": "three unstable regimes: A (small h, small ν̄), B (large h, small ν̄), "
        "C (large h, large ν̄)",
        "computed": txt + " — tested: median h of A below those of B and C, largest ν̄ "
        "of C above those of A and B",
        "passed": ok,
    }


def check_low_density_unstable(ds, ends=None) -> dict:
    """Along each θ row, the least dense flow is unstable in regime A or B.

    ``ends`` (from :func:`chuteflow.papers.mitarai2004.edges.row_ends`) follows each contour beyond the
    grid to its least dense flow; without it the least dense grid flow of each row is used.
    Rows whose least dense flow has h < 1 are reported but not judged (paper, figure 6:
    "the region of h < 1 ... was not examined"), nor rows where the two estimates of the
    sign of Re α2 disagree (``longwave_consistent``: the sign is not determined there), nor
    rows stable down to the grid's lowest ν0 whose contour could not be followed further
    (no steady flow found below it): "eventually" cannot be tested there.
    """
    if ends is None:
        ends = []
        reg, st = ds["regime"].values, ds["status"].values
        for i, th in enumerate(ds["theta"].values):
            ok = np.nonzero(st[i] == 0)[0]
            if len(ok):
                j = ok[0]
                ends.append(
                    {
                        "theta": float(th),
                        "nu0": float(ds["nu0"].values[j]),
                        "h": float(ds["h"].values[i, j]),
                        "alpha2_re": float(ds["alpha2_re"].values[i, j]),
                        "kind": _regime_name(reg[i, j]),
                        "consistent": bool(ds["longwave_consistent"].values[i, j] != 0)
                        if "longwave_consistent" in ds
                        else True,
                    }
                )
    stuck = [e for e in ends if e["kind"] == "stable" and e.get("how") == "grid, no flow found below"]
    judged = [
        e
        for e in ends
        if e.get("h", 0) >= 1 and e.get("consistent", True) and e["kind"] != "error" and e not in stuck
    ]
    thin = [e for e in ends if e.get("h", 0) < 1 and e["kind"] != "error"]
    unsure = [
        e for e in ends if e.get("h", 0) >= 1 and not e.get("consistent", True) and e["kind"] != "error"
    ]
    bad = [e for e in judged if e["kind"] not in ("A", "B")]
    errors = [e for e in ends if e["kind"] == "error"]

    def fmt(e):
        return (
            f"θ={e['theta']:.3g}° (ν0={e['nu0']:.3g}, h={e['h']:.2g}, Re α2="
            f"{e['alpha2_re']:.2g}: {e['kind']})"
        )

    txt = (
        f"{len(judged) - len(bad)} of {len(judged)} θ rows with h ≥ 1 at their least dense flow end in A or B"
    )
    if bad:
        txt += "; not: " + ", ".join(fmt(e) for e in bad[:6])
    if thin:
        kinds = {k: sum(e["kind"] == k for e in thin) for k in ("A", "B", "stable")}
        txt += f"; {len(thin)} rows end at h < 1 (not judged, as in the paper): " + ", ".join(
            f"{v} {k}" for k, v in kinds.items() if v
        )
    if unsure:
        txt += "; sign of Re α2 undetermined (estimates disagree) at " + ", ".join(fmt(e) for e in unsure[:4])
    if stuck:
        txt += (
            "; not followed below the grid (no steady flow found there by continuation, "
            "stable down to the grid's lowest ν0): " + ", ".join(fmt(e) for e in stuck[:4])
        )
    if errors:
        txt += f"; {len(errors)} rows failed: " + "; ".join(e.get("error", "")[:80] for e in errors[:2])
    return {
        "id": f"diagrams.phi{_phi(ds):g}.low_density",
        "source": "§4.2",
        "statement": "lowering the density along a fixed-θ contour always reaches regime "
        "A or B (the flow with low enough density is always unstable)",
        "computed": txt,
        "passed": len(judged) > 0 and not bad and not errors,
    }


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
    return {
        "id": f"diagrams.phi{phi:g}.C_monotonic",
        "source": "§4.2, §5 (discussion)",
        "statement": statement,
        "computed": f"{nm} of {n} grid points of C have a monotonic ν0(y)",
        "passed": passed,
    }


def check_markers(ds) -> list[dict]:
    """P1, P4, P5, Q3 unstable; P2, P3 stable (sign of Re α2 at the point itself)."""
    out: list[dict] = []
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
            extra = (
                f", max Re α on the k grid {ds['marker_growth_max'].values[m]:.3g} at "
                f"k = {ds['marker_k_growth_max'].values[m]:.3g}"
            )
        out.append(
            {
                "id": f"diagrams.{name}",
                "source": "§4.2, figures 7, 9, 13",
                "statement": f"{name} (θ = {th:g}°, ν0(0) = {nu:g}) is {'unstable' if want else 'stable'}",
                "computed": (f"Re α2 = {a2:.4g} → {'unstable' if u == 1 else 'stable'} (regime {reg}){extra}")
                if u >= 0
                else f"not computed: {ds['marker_message'].values[m]}",
                "passed": u >= 0 and (u == 1) == want,
            }
        )
    return out


def check_finite_k(ds) -> dict | None:
    """Sampled dispersion relations (grid sample and marked points) agree with the long-wave
    criterion. Points with h < 1 are listed but not judged (paper: not examined there; the
    neutral curve of A runs through them, where Re α2 ≈ 0)."""
    if "finite_k_disagrees" not in ds:
        return None
    rows: list[tuple] = []  # (label, disagrees, alpha2, growth max, k, h)
    failed = 0
    for prefix in ("", "marker_"):
        if prefix and "marker_finite_k_disagrees" not in ds:
            continue
        d = ds[prefix + "finite_k_disagrees"].values.ravel()
        smp = ds[prefix + "dispersion_sampled"].values.ravel() == 1
        gm = ds[prefix + "growth_max"].values.ravel()
        okst = ds[prefix + "status"].values.ravel() == 0
        failed += int((smp & ~np.isfinite(gm) & okst).sum())
        a2 = ds[prefix + "alpha2_re"].values.ravel()
        kk = ds[prefix + "k_growth_max"].values.ravel()
        hh = ds[prefix + "h"].values.ravel()
        if prefix:
            labels = [str(m) for m in ds["marker"].values]
        else:
            T, N = np.meshgrid(ds["theta"].values, ds["nu0"].values, indexing="ij")
            labels = [f"θ={t:.3g}°, ν0={n:.3g}" for t, n in zip(T.ravel(), N.ravel())]
        rows.extend((labels[q], d[q] == 1, a2[q], gm[q], kk[q], hh[q]) for q in np.nonzero(d >= 0)[0])
    judged = [r for r in rows if r[5] >= 1]
    bad = [r for r in judged if r[1]]
    thin_bad = [r for r in rows if r[5] < 1 and r[1]]

    def fmt(r):
        lab, _, a, g, k, h = r
        return f"({lab}, h={h:.2g}: Re α2 {a:.3g}, max Re α {g:.3g} at k={k:.3g})"

    txt = f"{len(bad)} of {len(judged)} sampled points with h ≥ 1 disagree"
    if bad:
        txt += ": " + "; ".join(fmt(r) for r in bad[:8])
    if thin_bad:
        txt += f"; at h < 1 (not judged) {len(thin_bad)} of {len(rows) - len(judged)} disagree: " + "; ".join(
            fmt(r) for r in thin_bad[:4]
        )
    if failed:
        txt += (
            f"; {failed} sampled points where the branch could not be tracked (listed in the file's message)"
        )
    return {
        "id": f"diagrams.phi{_phi(ds):g}.finite_k",
        "source": "§4.2 (all unstable modes are long-wave), docs/errata.md, numerical notes",
        "statement": "no finite-k instability missed by the sign of Re α2 (dispersion "
        "relation of the α(0) = 0 branch sampled on a k grid at a subset of "
        "grid points and at the marked points)",
        "computed": txt,
        "passed": len(judged) > 0 and not bad,
    }


def paper_checks(ds, ends=None) -> list[dict]:
    """All checks that apply to this Dataset (needs the stability metrics); ``ends`` from
    :func:`chuteflow.papers.mitarai2004.edges.row_ends` refines the low-density check."""
    if "regime" not in ds:
        return []
    out = [check_regimes_placed(ds), check_low_density_unstable(ds, ends)]
    phi = _phi(ds)
    if math.isclose(phi, 0.05) or math.isclose(phi, 0.10):
        out.append(check_C_monotonicity(ds))
    out += check_markers(ds)
    fk = check_finite_k(ds)
    if fk is not None:
        out.append(fk)
    return out

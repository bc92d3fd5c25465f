"""Stability classification of a swept Dataset: unstable points, regimes A, B, C (§4.2).

- ``unstable``: Re α2 > 0, the long-wave criterion (§4.2: every unstable mode found by the paper
  has α(0) = 0 and Re α ∝ k² at small k); −1 (unknown) where Re α2 is missing or its sign is
  not resolved (``longwave_consistent`` = 0: the resolutions N and 0.8 N disagree on it, e.g.
  on the neutral curve, where Re α2 is at the round-off of the eigenvalue).
- ``finite_k_unstable`` and ``finite_k_disagrees``: where the dispersion relation was sampled
  (metric ``growth``), whether some k on its grid grows, and whether that contradicts the
  long-wave criterion (a finite-k instability it misses, or a long-wave instability the k grid
  does not see). Such points are reported, never hidden.
- ``regime``: 1 = A, 2 = B, 3 = C, 0 = stable, −1 = unknown. §4.2: in B the lighter flow is
  faster (dU/dρ̄0 < 0 with U = Q0/ρ̄0); in A and C the denser flow is faster (dU/dρ̄0 > 0). A lies
  on the fixed-θ contours that end at h → 0 (small h), C at the dense end of the contours that
  end in B-type flows (large h, large ν̄); see :func:`regimes`.
"""

from __future__ import annotations

import numpy as np

__all__ = ["classify", "regimes", "REGIMES", "regime_summary"]

#: Regime codes of the ``regime`` variable.
REGIMES = {"stable": 0, "A": 1, "B": 2, "C": 3}


def _flag(arr_bool, valid):
    out = np.full(arr_bool.shape, -1, dtype=np.int8)
    out[valid] = arr_bool[valid].astype(np.int8)
    return out


def _flag_attrs(long_name, source=""):
    a = {
        "units": "1",
        "long_name": long_name,
        "flag_values": np.array([-1, 0, 1], dtype=np.int8),
        "flag_meanings": "missing false true",
    }
    if source:
        a["source"] = source
    return a


def classify(ds):
    """Add ``unstable``, ``regime`` and the finite-k cross-check to ``ds`` (if computable).

    Needs ``alpha2_re`` (metric ``longwave``); the regimes also need ``dU_drho`` (metric
    ``kinematic``), the check needs ``growth_max`` (metric ``growth``). Marked points get the
    same variables (``marker_…``).
    """
    if "alpha2_re" not in ds:
        return ds
    ds = ds.copy()
    for prefix in ("", "marker_"):
        if prefix and "marker" not in ds.dims:
            continue
        a2 = ds[prefix + "alpha2_re"].values
        valid = np.isfinite(a2)
        if prefix + "longwave_consistent" in ds:
            # a sign that the two resolutions do not agree on labels nothing
            valid &= ds[prefix + "longwave_consistent"].values != 0
        ds[prefix + "unstable"] = (
            ds[prefix + "alpha2_re"].dims,
            _flag(a2 > 0, valid),
            _flag_attrs(
                "long-wave unstable, Re α2 > 0 (missing: not computed, or its sign not resolved)", "§4.2"
            ),
        )
        if "growth_max" in ds:
            g = ds[prefix + "growth_max"].values
            sampled = ds[prefix + "dispersion_sampled"].values == 1
            ok = sampled & np.isfinite(g)
            fk = _flag(g > 0, ok)
            dis = np.full(a2.shape, -1, dtype=np.int8)
            both = ok & valid
            dis[both] = ((g[both] > 0) != (a2[both] > 0)).astype(np.int8)
            dims = ds[prefix + "alpha2_re"].dims
            ds[prefix + "finite_k_unstable"] = (
                dims,
                fk,
                _flag_attrs("some sampled k has Re α > 0 (dispersion relation of the α(0) = 0 branch)"),
            )
            ds[prefix + "finite_k_disagrees"] = (
                dims,
                dis,
                _flag_attrs("sampled dispersion relation and long-wave criterion disagree"),
            )
    if "dU_drho" in ds:
        reg = regimes(ds["unstable"].values, ds["dU_drho"].values, ds["h"].values, ds["nu_mean"].values)
        ds["regime"] = (
            ("theta", "nu0"),
            reg,
            {
                "long_name": "unstable regime (§4.2): A small h & small ν̄, denser faster; B lighter "
                "faster; C large h & large ν̄, denser faster",
                "flag_values": np.array([-1, 0, 1, 2, 3], dtype=np.int8),
                "flag_meanings": "unknown stable A B C",
                "source": "§4.2, figure 6",
            },
        )
        if "marker" in ds.dims:
            ds["marker_regime"] = ("marker", _marker_regimes(ds, reg), dict(ds["regime"].attrs))
    return ds


def regimes(unstable, dU, h, nu_mean):
    """Regime codes (:data:`REGIMES`) on the (θ, ν0) grid (rows θ, columns ν0 ascending).

    B: unstable with dU/dρ̄0 < 0 (the lighter flow is faster). The other unstable points
    (denser flow faster) are A or C. §3.2 and §4.2 tell them apart by the fixed-θ contour
    they lie on: contours left of the separatrix (θ ≤ 14° for φ = 0.05) end at h → 0 as the
    density decreases, and their flows slow down as they get lighter all the way (A, small h);
    contours right of it end with h → ∞ in the B-type flows that get faster as they get
    lighter, and the denser-faster instability at the dense end of those contours is C. So a
    θ row is of the A kind when its least dense flow has dU/dρ̄0 ≥ 0; the rows are then split
    at the one θ (the separatrix) that agrees with the most rows, because a row whose least
    dense flows were not found would look A-kind (θ ascending). Each connected region
    (4-neighbour grid connectivity) of denser-faster unstable points takes the kind of the
    majority of its points, so that the label does not flicker near the separatrix.
    """
    from scipy import ndimage

    unstable = np.asarray(unstable)
    dU = np.asarray(dU, dtype=float)
    out = np.full(unstable.shape, -1, dtype=np.int8)
    known = (unstable >= 0) & np.isfinite(dU)
    out[known & (unstable == 0)] = REGIMES["stable"]
    isB = known & (unstable == 1) & (dU < 0)
    out[isB] = REGIMES["B"]
    faster = known & (unstable == 1) & (dU >= 0)
    # kind of each row from its least dense flow (+1: A kind, −1: B kind, 0: no flow); a row
    # whose low-density flows were not found can look A-kind, so the kinds are reduced to one
    # separatrix in θ (contours below it end at h → 0, §3.2) that misplaces the fewest rows
    raw = np.zeros(unstable.shape[0], dtype=int)
    for i in range(unstable.shape[0]):
        js = np.nonzero(np.isfinite(dU[i]))[0]
        if len(js):
            raw[i] = 1 if dU[i, js[0]] >= 0 else -1
    cost = [int((raw[:t] == -1).sum() + (raw[t:] == 1).sum()) for t in range(len(raw) + 1)]
    split = int(np.argmin(cost))
    row_A = np.arange(len(raw)) < split
    kindA = np.broadcast_to(row_A[:, None], unstable.shape)
    labels, nlab = ndimage.label(faster)
    for lab in range(1, nlab + 1):
        sel = labels == lab
        out[sel] = REGIMES["A"] if 2 * int(kindA[sel].sum()) >= int(sel.sum()) else REGIMES["C"]
    return out


def _marker_regimes(ds, reg):
    """Regime of each marked point from its own Re α2 and dU/dρ̄0; A or C (denser flow faster)
    from the nearest grid point (in scaled (θ, ν0)) of regime A or C."""
    out = np.full(ds.sizes["marker"], -1, dtype=np.int8)
    th = ds["theta"].values
    nu = ds["nu0"].values
    T, N = np.meshgrid(th, nu, indexing="ij")
    sth = max(np.ptp(th), 1e-12)
    snu = max(np.ptp(nu), 1e-12)
    for m in range(ds.sizes["marker"]):
        u = int(ds["marker_unstable"].values[m])
        if u < 0:
            continue
        if u == 0:
            out[m] = REGIMES["stable"]
            continue
        dU = float(ds["marker_dU_drho"].values[m])
        if not np.isfinite(dU):
            continue
        if dU < 0:
            out[m] = REGIMES["B"]
            continue
        cand = (reg == REGIMES["A"]) | (reg == REGIMES["C"])
        if not cand.any():
            continue
        d = ((T - ds["marker_theta"].values[m]) / sth) ** 2 + ((N - ds["marker_nu0"].values[m]) / snu) ** 2
        d = np.where(cand, d, np.inf)
        out[m] = reg.ravel()[int(np.argmin(d))]
    return out


def regime_summary(ds) -> dict:
    """Per regime: number of grid points, median (h, ν̄), largest ν̄, θ range; for reports."""
    out: dict[str, dict[str, float]] = {}
    if "regime" not in ds:
        return out
    reg = ds["regime"].values
    T = np.broadcast_to(ds["theta"].values[:, None], reg.shape)
    for name in ("A", "B", "C"):
        sel = reg == REGIMES[name]
        if not sel.any():
            out[name] = {"points": 0}
            continue
        out[name] = {
            "points": int(sel.sum()),
            "h_median": float(np.median(ds["h"].values[sel])),
            "nu_mean_median": float(np.median(ds["nu_mean"].values[sel])),
            "nu_mean_max": float(np.max(ds["nu_mean"].values[sel])),
            "theta_min": float(T[sel].min()),
            "theta_max": float(T[sel].max()),
        }
        if "monotonic" in ds:
            out[name]["monotonic_fraction"] = float(np.mean(ds["monotonic"].values[sel] == 1))
    return out

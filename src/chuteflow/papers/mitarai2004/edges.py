"""The least dense flow of each fixed-θ contour, located beyond the grid's resolution (§4.2).

The paper: "when we decrease the density with a constant inclination angle ... eventually we
will encounter either the regime A or the regime B". On a grid, the least dense flow found on a
θ row lies up to one grid step above the end of the contour (where the layer collapses, h → 0)
or at the grid's lowest ν0 (where h grows without bound). :func:`row_ends` goes further along
each contour by continuation from the row's least dense grid flow: bisection towards the first
failed density below it, or a family at ν0 halved repeatedly below the grid, and classifies the
least dense flow reached with the sweep's own point functions.
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

from ...errors import ChuteflowError
from ...steady import solve_steady, steady_family
from ...sweep.config import SweepConfig
from ...sweep.points import Point, point_function

__all__ = ["row_ends"]


def _classify_flow(flow, fns):
    point = Point(-1, 0, flow.theta, flow.nu0)
    for f in fns:
        point.values.update(f.compute(flow, point))
    v = point.values
    a2, dU = v["alpha2_re"], v["dU_drho"]
    if a2 is None or dU is None:
        # the long-wave metric left its value missing (no finite Re α/k²): the row's end is
        # not classified, and the check counts it as a failed row with the metric's reason
        why = "; ".join(point.notes) or "no finite value"
        return {
            "alpha2_re": math.nan if a2 is None else float(a2),
            "dU_drho": math.nan if dU is None else float(dU),
            "kind": "error",
            "error": f"the long-wave coefficient at the row's end (ν0 = {flow.nu0:.4g}) is missing: {why}",
            "consistent": False,
        }
    kind = ("B" if dU < 0 else "A") if a2 > 0 else "stable"
    return {
        "alpha2_re": float(a2),
        "dU_drho": float(dU),
        "kind": kind,
        "consistent": bool(v.get("longwave_consistent", True)),
    }


def row_ends(ds, *, rows=None, bisections: int = 5, halvings: int = 5, flows=None):
    """Least dense flow reached on each θ row and its stability (A, B or stable).

    Parameters
    ----------
    ds : xarray.Dataset
        A sweep with the ``steady``, ``kinematic`` and ``longwave`` point functions.
    rows : sequence of int, optional
        Row indices (default: every row with a steady flow).
    bisections : int
        Bisection steps towards the failed density below the least dense grid flow.
    halvings : int
        When the row's least dense grid flow is at the grid's lowest ν0 and stable: the
        contour is followed down to ν0_min / 2^halvings (steady family, continuation).
    flows : dict, optional
        The sweep's steady flows by grid index (i, j) (:attr:`chuteflow.sweep.Sweep.flows`,
        computed with the same settings): a row's least dense grid flow is taken from there
        instead of being solved again from the cold start.

    Returns
    -------
    list of dict
        Per row: ``theta``, ``nu0`` (of the least dense flow reached), ``h``, ``nu_mean``,
        ``alpha2_re``, ``dU_drho``, ``kind`` ("A", "B", "stable"), ``consistent`` (long-wave
        sign cross-check), ``how`` ("grid", "bisection", "below grid", or "grid, no flow found
        below": the contour could not be followed below the grid), and ``error`` if none.
    """
    cfg = SweepConfig.from_dict(json.loads(ds.attrs["config_json"]))
    specs = {json.loads(s)["name"]: json.loads(s) for s in cfg.metrics}
    if "longwave" not in specs and "longwave_strided" in specs:
        # a diagram of chuteflow.papers.mitarai2004.adaptive: the long-wave metric itself
        lw = dict(specs["longwave_strided"].get("options", {}))
        lw.pop("stride", None)
        specs["longwave"] = {"name": "longwave", "options": lw}
    fns = [point_function(specs[name]) for name in ("steady", "kinematic", "longwave")]
    model = cfg.model
    kw: dict[str, Any] = dict(
        nu_top=cfg.nu_top, rtol=cfg.steady_rtol, n_max=cfg.n_max, min_thickness=cfg.min_thickness
    )
    st = ds["status"].values
    nus = ds["nu0"].values
    out = []
    idx = range(len(ds["theta"])) if rows is None else rows
    for i in idx:
        theta = float(ds["theta"].values[i])
        ok = np.nonzero(st[i] == 0)[0]
        if len(ok) == 0:
            continue
        j = int(ok[0])
        rec: dict[str, Any] = {"theta": theta}
        reg = int(ds["regime"].values[i, j]) if "regime" in ds else -1
        if j == 0 and reg in (1, 2):
            # already unstable at the grid's lowest density: nothing to extend
            rec.update(
                nu0=float(nus[0]),
                h=float(ds["h"].values[i, 0]),
                nu_mean=float(ds["nu_mean"].values[i, 0]),
                alpha2_re=float(ds["alpha2_re"].values[i, 0]),
                dU_drho=float(ds["dU_drho"].values[i, 0]),
                kind="A" if reg == 1 else "B",
                consistent=bool(ds["longwave_consistent"].values[i, 0] != 0)
                if "longwave_consistent" in ds
                else True,
                how="grid",
            )
            out.append(rec)
            continue
        try:
            flow = (flows or {}).get((i, j))
            if flow is None:
                flow = solve_steady(theta, float(nus[j]), model, **kw, strict=True)
            how = "grid"
            if j > 0:
                lo, hi = float(nus[j - 1]), float(nus[j])  # no flow at lo, flow at hi
                for _ in range(bisections):
                    mid = 0.5 * (lo + hi)
                    try:
                        flow = solve_steady(theta, mid, model, guess=flow, **kw, strict=True)
                        hi = mid
                        how = "bisection"
                    except ChuteflowError:
                        lo = mid
            else:
                # below the grid: the family at ν0 = ν0_min / 2^q, q = halvings … 1, by
                # continuation down from the grid's least dense flow
                below = [float(nus[0]) * 0.5**q for q in range(halvings, 0, -1)]
                _, family = steady_family(
                    theta, below + [float(nus[0])], model, tangent=False, return_flows=True, **kw
                )
                lowest = next((f for f in family if f is not None), None)
                if lowest is not None and lowest.nu0 < flow.nu0:
                    flow, how = lowest, "below grid"
                else:
                    how = "grid, no flow found below"
            rec.update(nu0=flow.nu0, h=flow.h, nu_mean=flow.nu_mean, how=how)
            rec.update(_classify_flow(flow, fns))
        except ChuteflowError as exc:
            rec.update(nu0=math.nan, kind="error", error=str(exc))
        out.append(rec)
    return out

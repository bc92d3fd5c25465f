"""Maps of steady flows over a (θ, ν0(0)) grid and their image in the (h, ν̄) plane (§3.2).

Each θ row is solved by continuation along ν0 (:func:`~chuteflow.steady.family.continue_row`);
a row also starts from the converged points of the row before it (continuation in θ), which
reaches the non-monotonic branches that a cold start misses. Rows are swept outwards from a
middle row in two directions, which are independent: with ``workers=2`` they run in two
processes (one BLAS thread each).
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from .._threads import limit_blas_threads
from ..closures import ChuteModel
from ..errors import ParameterError
from .api import follow
from .family import SCALARS, Options, check_nu0, continue_row, dataset_attrs, row_arrays, variable_attrs
from .solver import validate_point


def _sweep(thetas, nus, model, opts, seed_row=None, proofs=None):
    """Rows in the given θ order, each seeded by the previous one; returns list of rows.
    ``proofs`` (shared by the rows) collects the shooting scan's verdicts."""
    rows = []
    prev = seed_row
    proofs = [] if proofs is None else proofs
    for th in thetas:
        row = continue_row(th, nus, model, opts, previous=prev, proofs=proofs)
        rows.append(row)
        if any(p.usable for p in row):
            prev = row
        # a row without any solution keeps the last useful one as seed (a gap of one row)
    return rows


def _start_row(ths, nus, model, opts, start_theta, proofs):
    """Row where both sweeps start: the first of a few candidates (middle of the range
    first) on which at least a quarter of the points converge, else the best of them."""
    if start_theta is not None:
        k = int(np.argmin(np.abs(ths - start_theta)))
        return k, continue_row(ths[k], nus, model, opts, proofs=proofs)
    fracs = (0.5, 0.65, 0.35, 0.8, 0.2)
    best = None
    for f in fracs:
        k = int(round(f * (len(ths) - 1)))
        if best is not None and k == best[0]:
            continue
        row = continue_row(ths[k], nus, model, opts, proofs=proofs)
        good = sum(p.status == "ok" for p in row)
        if best is None or good > best[2]:
            best = (k, row, good)
        if good >= 0.25 * len(nus):
            break
    return best[0], best[1]


def _sweep_back(thetas, nus, model, opts, rows, k, proofs):
    """Second pass towards the start row ``k``: each row also continues from the row on
    its outer side, which reaches pieces of the branch first found further out."""
    for i in list(range(len(rows) - 2, k - 1, -1)) + list(range(1, k)):
        j = i + 1 if i >= k else i - 1
        if any(p.usable for p in rows[j]):
            rows[i] = continue_row(
                thetas[i],
                nus,
                model,
                opts,
                previous=rows[j],
                existing=rows[i],
                cold_starts=False,
                proofs=proofs,
            )
    return rows


def _sweep_worker(args):
    limit_blas_threads(1)
    thetas, nus, model, opts, seed_row, proofs = args
    return _sweep(thetas, nus, model, opts, seed_row, proofs), proofs


def steady_map(
    theta_values,
    nu0_values,
    model: ChuteModel | None = None,
    *,
    nu_top: float = 1e-9,
    n: int = 64,
    rtol: float = 1e-8,
    n_max: int = 384,
    min_thickness: float = 1.0,
    tangent: bool = False,
    workers: int | None = 1,
    start_theta: float | None = None,
    return_flows: bool = False,
    decide: bool = True,
):
    """Steady flows on a (θ, ν0(0)) grid.

    Parameters
    ----------
    theta_values : sequence of float
        Inclinations θ in degrees, strictly increasing.
    nu0_values : sequence of float
        Floor densities ν0(0), strictly increasing.
    model : ChuteModel, optional
        Closure parameters (paper defaults).
    nu_top, n, rtol, n_max, min_thickness
        As for :func:`~chuteflow.steady.solve_steady`; every point is converged to ``rtol``
        between two resolutions.
    tangent : bool
        Also compute dQ0/dρ̄0 etc. from the exact family tangent (about 2 ms per point).
    workers : int or None
        1: one process. 2: the two sweeps (θ upwards and downwards from the start row) in
        two processes. None: 2 if the machine has at least two cores.
    return_flows : bool
        Also return the converged flows (thin ones included) as a nested list [θ][ν0],
        None where there is none.
    start_theta : float, optional
        Row where the sweeps start (default: the middle row, or a row at 65 %, 35 %, 80 %,
        20 % of the range if fewer than a quarter of the middle row's points converge).
    decide : bool
        Decide every point that continuation does not reach by the shooting scan (or a
        scan's verdict that covers it: :func:`~chuteflow.steady.family.continue_row`).
        False: leave them 'unreached' (continuation only; for comparison).

    Returns
    -------
    xarray.Dataset
        Dims (theta, nu0): the variables of :func:`~chuteflow.steady.steady_family`
        (NaN and a status string where there is no physical steady flow).
    """
    import xarray as xr

    model = model or ChuteModel()
    ths = np.atleast_1d(np.asarray(theta_values, dtype=float))
    if ths.ndim != 1 or len(ths) == 0 or (len(ths) > 1 and not np.all(np.diff(ths) > 0)):
        raise ParameterError("theta_values: expected a strictly increasing 1-D sequence of angles in degrees")
    for th in ths:
        validate_point(th, 0.5 * model.nu_max, model, 1e-9)
    nus = check_nu0(nu0_values, model)
    validate_point(ths[0], nus[0], model, nu_top)
    # fail fast: beyond the existence boundary every attempt fails, and points past a
    # failure are usually reached again from the neighbouring row: no substeps, and one
    # cold start for rows that have a neighbouring row to continue from. (Fewer Newton
    # iterations from a continuation guess, 6 instead of 10 with 2 halvings instead of 4,
    # would save 30 % of the time but lose 6 % of the points, hard ones like θ = 17°,
    # ν0(0) = 0.12 among them: not done.)
    opts = Options(
        nu_top=nu_top,
        n=n,
        rtol=rtol,
        n_max=n_max,
        min_thickness=min_thickness,
        tangent=tangent,
        substeps=0,
        decide=decide,
    )
    proofs: list = []
    k, first = _start_row(ths, nus, model, opts, start_theta, proofs)
    up, down = list(ths[k + 1 :]), list(ths[:k][::-1])
    if workers is None:
        workers = 2 if (os.cpu_count() or 1) >= 2 else 1
    if workers >= 2 and up and down:
        import multiprocessing as mp
        from concurrent.futures import ProcessPoolExecutor

        ctx = mp.get_context("fork") if "fork" in mp.get_all_start_methods() else None
        # the sympy-compiled closures and equations are already built (start row):
        # forked children inherit them
        with ProcessPoolExecutor(max_workers=2, mp_context=ctx) as pool:
            fu = pool.submit(_sweep_worker, (up, nus, model, opts, first, list(proofs)))
            fd = pool.submit(_sweep_worker, (down, nus, model, opts, first, list(proofs)))
            (r_up, p_up), (r_down, p_down) = fu.result(), fd.result()
            rows_up = [first] + r_up
            rows_down = r_down
            proofs = p_up + [q for q in p_down if q not in p_up]
    else:
        # the same order of work as with two processes (identical statuses and numbers)
        p_up, p_down = list(proofs), list(proofs)
        rows_up = [first] + _sweep(up, nus, model, opts, first, p_up)
        rows_down = _sweep(down, nus, model, opts, first, p_down)
        proofs = p_up + [q for q in p_down if q not in p_up]
    rows = rows_down[::-1] + rows_up
    rows = _sweep_back(ths, nus, model, opts, rows, k, proofs)
    arrays = [row_arrays(r) for r in rows]
    data = {}
    for key in arrays[0]:
        data[key] = (("theta", "nu0"), np.stack([a[key] for a in arrays]), variable_attrs(key))
    ds = xr.Dataset(
        data,
        coords={
            "theta": ("theta", ths, {"long_name": "inclination θ", "units": "degree"}),
            "nu0": ("nu0", nus, {"long_name": "floor packing fraction ν0(0)", "units": "1"}),
        },
        attrs=dataset_attrs(model, opts),
    )
    if return_flows:
        return ds, [[p.flow for p in row] for row in rows]
    return ds


def existence_limit(
    flows,
    ds,
    side: str,
    *,
    columns: int = 1,
    min_step: float = 1.0 / 64,
    margin: float = 8.0,
    rtol: float = 1e-6,
    n_max: int = 256,
) -> dict:
    """Refine the lowest (``side='low'``) or highest (``'high'``) angle with a steady flow.

    From the map's extreme converged points (in the ``columns`` ν0 columns that reach
    furthest, and in the densest / most dilute column with a flow), the branch is followed
    beyond the map (:func:`~chuteflow.steady.api.follow`): in θ at fixed ν0(0) until it
    ends, then in ν0(0) towards the grid's extreme floor density, and in θ again (up to
    three times). Thin layers count. Only the angle where the branch ends is sought (to
    ~2·``min_step``), so the flows on the way are converged to ``rtol`` = 1e-6 with at most
    ``n_max`` intervals (dense thin layers near the end would otherwise need n ≈ 500).

    Returns
    -------
    dict
        ``theta`` (the extreme angle reached, to ~2·min_step), ``nu0`` where it is reached,
        ``h`` there, ``map_theta`` (the extreme row of the map) and ``ends`` (the branch
        ended before ``margin`` degrees beyond the map).
    """
    st = ds.status.values
    usable = (st == "ok") | (st == "thin")
    ths, nus = ds.theta.values, ds.nu0.values
    per_col = []
    for j in range(usable.shape[1]):
        rows = np.nonzero(usable[:, j])[0]
        if len(rows):
            i = rows[0] if side == "low" else rows[-1]
            per_col.append((ths[i], i, j))
    if not per_col:
        return {
            "theta": float("nan"),
            "nu0": float("nan"),
            "h": float("nan"),
            "map_theta": float("nan"),
            "ends": False,
        }
    # the columns reaching furthest, and the densest (low end) or most dilute (high end)
    # column with a flow: the limit is usually reached at the extreme floor density
    extreme = per_col[-1] if side == "low" else per_col[0]
    per_col.sort(reverse=(side == "high"))
    cand = per_col[:columns] + ([extreme] if extreme not in per_col[:columns] else [])
    nu_end = nus[-1] if side == "low" else nus[0]
    sign = -1.0 if side == "low" else 1.0
    best: tuple[Any, bool] | None = None
    for th, i, j in cand:
        g = flows[i][j]
        for _ in range(3):
            # along θ until the branch ends, then along ν0(0) towards the extreme floor
            # density (the end may move further there), and along θ again
            g, reached = follow(
                g, theta=th + sign * margin, min_step=min_step, max_steps=40, rtol=rtol, n_max=n_max
            )
            if reached:
                break
            g2, _ = follow(g, nu0=nu_end, min_step=0.01, max_steps=30, rtol=rtol, n_max=n_max)
            if abs(g2.nu0 - g.nu0) < 1e-12:
                break
            g = g2
        better = best is None or sign * (g.theta - best[0].theta) > 0
        if better:
            best = (g, reached)
    assert best is not None  # cand holds at least one column, and each sets best once
    g, reached = best
    return {
        "theta": float(g.theta),
        "nu0": float(g.nu0),
        "h": float(g.h),
        "map_theta": float(per_col[0][0]),
        "ends": not reached,
    }


__all__ = ["steady_map", "existence_limit", "SCALARS"]

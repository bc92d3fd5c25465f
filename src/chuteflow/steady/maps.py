"""Maps of steady flows over a (θ, ν0(0)) grid and their image in the (h, ν̄) plane (§3.2).

Each θ row is solved by continuation along ν0 (:func:`~chuteflow.steady.rows.continue_row`);
a row also starts from the converged points of the row before it (continuation in θ), which
reaches the non-monotonic branches that a cold start misses. Rows are swept in chains
outwards from start rows (solved on their own): from one middle row in two directions, or,
on maps of at least :data:`TWO_STARTS` rows, from rows near a quarter and three quarters of
the range in four (down to the first row, up to the middle between the two, down to it,
up to the last). The chains are independent: with ``workers=2`` they run in two processes
(one BLAS thread each); four chains share the two more evenly than two, because rows cost
very different amounts (near the upper existence boundary a row of the paper's φ = 0.05
map costs 10× one near the lower). The two start rows of a large map are searched for
independently (each search sees the shooting scan's proofs of its own rows only), so
the processes solve them at once too; the chain down from the lower start row needs
nothing from the upper search (it is given the lower search's proofs only), so it starts
as soon as that search is done, and the process that found the lower row does not wait
for the upper one (the 60 × 60 paper map: 1.1 s idle before). The calling process
imports xarray for the result while the chains run. A second pass then continues each
row from its other neighbour as well.
"""

from __future__ import annotations

import contextlib
import os
from typing import Any

import numpy as np

from .._imports import warm_xarray
from .._memory import keep_freed_memory
from .._threads import limit_blas_threads
from ..closures import ChuteModel
from ..errors import ParameterError
from .follow import follow
from .inputs import check_nu0, validate_point
from .options import Options
from .rows import continue_row
from .schema import SCALARS, dataset_attrs, row_arrays, variable_attrs


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


#: Maps with at least this many θ rows start from two rows instead of one (four chains).
TWO_STARTS = 12
#: A start row is good when at least this fraction of its points converge (physical or thin
#: flows are both seeds).
_GOOD_START = 0.25


def _row_index(n, f):
    return int(round(f * (n - 1)))


def _first_good(ths, nus, model, opts, fracs, proofs, cold):
    """The first row of the fractions ``fracs`` of the range on which at least
    :data:`_GOOD_START` of the points converge, else the best of them: (index, good).
    ``cold`` keeps the rows solved on their own (each at most once)."""
    best = None
    for f in fracs:
        k = _row_index(len(ths), f)
        if k not in cold:
            cold[k] = continue_row(ths[k], nus, model, opts, proofs=proofs)
        n_ok = sum(p.status == "ok" for p in cold[k])
        good = n_ok >= _GOOD_START * len(nus)
        if best is None or n_ok > best[2]:
            best = (k, good, n_ok)
        if good:
            return k, True
    assert best is not None  # fracs is not empty
    return best[0], best[1]


def _first_good_alone(args):
    """:func:`_first_good` on its own: (index, good, cold rows, proofs); the proofs are
    those of its own rows only."""
    ths, nus, model, opts, fracs = args
    proofs: list = []
    cold: dict = {}
    k, good = _first_good(ths, nus, model, opts, fracs, proofs, cold)
    return k, good, cold, proofs


def _first_good_worker(args):
    limit_blas_threads(1)
    keep_freed_memory()
    return _first_good_alone(args)


def _start_rows(ths, nus, model, opts, start_theta, proofs, pool=None):
    """Rows where the chains start, solved on their own: ({index: row}, first).

    ``start_theta``: that row alone. Maps of fewer than :data:`TWO_STARTS` rows: one row,
    the first good of the middle, 65 %, 35 %, 80 % and 20 % of the range (or the best of
    them). Larger maps: the first good of 25 %, 35 %, 15 % and of 75 %, 65 %, 85 % — two
    rows when both are good, otherwise the single start as for a small map. The two
    searches of a large map are independent (each sees only its own rows' proofs), so that
    ``pool`` (a process pool, or None: in line) runs them at once with the same results.
    ``proofs`` receives the proofs of every row solved here.

    ``first`` (two starts only, else None): (proofs, future). The chain from the lower start
    row down to the first row needs nothing from the upper search, so it is given the lower
    search's proofs only, and with a ``pool`` it is submitted as soon as that search is
    done (future: its :func:`_sweep_worker` result; None in line): the upper search (a row
    near the upper existence boundary) takes several times longer, and the process that
    found the lower row would otherwise wait for it. Where the two starts fail, that chain
    is dropped."""
    cold: dict = {}
    if start_theta is not None:
        k = int(np.argmin(np.abs(ths - start_theta)))
        return {k: continue_row(ths[k], nus, model, opts, proofs=proofs)}, None
    if len(ths) >= TWO_STARTS:
        tasks = [(ths, nus, model, opts, fracs) for fracs in ((0.25, 0.35, 0.15), (0.75, 0.65, 0.85))]
        early = None
        if pool is not None:
            futures = [pool.submit(_first_good_worker, t) for t in tasks]
            k1, good1, cold1, p1 = futures[0].result()
            if good1 and k1 > 0:
                down = _chains(len(ths), [k1])[0][1]  # the chain from k1 down to the first row
                early = pool.submit(_sweep_worker, _task(ths, down, nus, model, opts, cold1[k1], p1))
            found = [(k1, good1, cold1, p1), futures[1].result()]
        else:
            found = [_first_good_alone(t) for t in tasks]
        (k1, good1, cold1, p1), (k2, good2, cold2, p2) = found
        cold.update(cold1)
        cold.update(cold2)
        proofs += p1 + [q for q in p2 if q not in p1]
        if good1 and good2 and k1 < k2:
            return {k1: cold[k1], k2: cold[k2]}, (list(p1), early)
        if early is not None:
            early.cancel()
    k, _ = _first_good(ths, nus, model, opts, (0.5, 0.65, 0.35, 0.8, 0.2), proofs, cold)
    return {k: cold[k]}, None


def _task(ths, rows, nus, model, opts, seed, proofs):
    """Arguments of :func:`_sweep` (and :func:`_sweep_worker`) for the chain of ``rows``
    seeded by the row ``seed``, with a copy of ``proofs``."""
    return [ths[i] for i in rows], nus, model, opts, seed, list(proofs)


def _chains(n, starts):
    """Chains of row indices swept from the start rows: (start, [rows in order])."""
    out = [(starts[0], list(range(starts[0] - 1, -1, -1)))]
    for a, b in zip(starts, starts[1:]):
        mid = (a + b) // 2
        out += [(a, list(range(a + 1, mid + 1))), (b, list(range(b - 1, mid, -1)))]
    out.append((starts[-1], list(range(starts[-1] + 1, n))))
    return [c for c in out if c[1]]


def _sweep_back(thetas, nus, model, opts, rows, chains, proofs):
    """Second pass, each chain from its far end back towards its start row: each row also
    continues from the row on its outer side (for the chain's last row: the grid's end, or
    the last row of the chain it meets), which reaches pieces of the branch first found
    further out. The start row itself is continued from the row above it."""
    n = len(rows)
    for start, chain in reversed(chains):
        up = chain[0] > start
        back = chain[::-1] + ([start] if up else [])
        for i in back:
            j = i + 1 if up else i - 1
            if 0 <= j < n and any(p.usable for p in rows[j]):
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
    keep_freed_memory()
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
        1: one process. 2 or more: the start rows and then the chains of rows (θ upwards
        and downwards from each start row; two or four chains) in that many processes, the
        same numbers. None: 2 if the machine has at least two cores.
    return_flows : bool
        Also return the converged flows (thin ones included) as a nested list [θ][ν0],
        None where there is none.
    start_theta : float, optional
        Row where the sweeps start (its nearest row; one start). Default: on maps of at
        least :data:`TWO_STARTS` rows, two rows near 25 % and 75 % of the range (or 35 %,
        15 % and 65 %, 85 % where fewer than a quarter of a row's points converge);
        otherwise, or where either has no good candidate, the middle row, or a row at
        65 %, 35 %, 80 %, 20 % of the range.
    decide : bool
        Decide every point that continuation does not reach by the shooting scan (or a
        scan's verdict that covers it: :func:`~chuteflow.steady.rows.continue_row`).
        False: leave them 'unreached' (continuation only; for comparison).

    Returns
    -------
    xarray.Dataset
        Dims (theta, nu0): the variables of :func:`~chuteflow.steady.steady_family`
        (NaN and a status string where there is no physical steady flow).
    """
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
        # the map's flows are summarised, not kept: their exact dX/dβ only with ``tangent``
        beta_tangents=tangent,
    )
    proofs: list = []
    if workers is None:
        workers = 2 if (os.cpu_count() or 1) >= 2 else 1
    with contextlib.ExitStack() as stack:
        pool = None
        if workers >= 2 and len(ths) >= 2:
            import multiprocessing as mp
            from concurrent.futures import ProcessPoolExecutor

            from ..equations import warm_up

            # forked processes inherit the generated closures and equations (built here
            # once; a process forks at the first task submitted to it)
            warm_up(model)
            ctx = mp.get_context("fork") if "fork" in mp.get_all_start_methods() else None
            pool = stack.enter_context(ProcessPoolExecutor(max_workers=workers, mp_context=ctx))
        starts, first = _start_rows(ths, nus, model, opts, start_theta, proofs, pool=pool)
        chains = _chains(len(ths), sorted(starts))
        early = None
        own = [proofs] * len(chains)
        if first is not None and chains[0][1][0] < chains[0][0]:
            # the chain down from the lower start row: that search's proofs only (in both
            # roads, so that one process and several give the same numbers)
            own[0], early = first[0], first[1]
        tasks = [_task(ths, rows, nus, model, opts, starts[k], p) for (k, rows), p in zip(chains, own)]
        if pool is not None and len(chains) >= 2:
            # the chains go out from the top of the range first. Where the chain down from
            # the lower start row runs already (a short one, at the cheap end), the other
            # process takes the second chain from the top and that one the top chain (the
            # longest) when it is done: the first process has then started two chains and
            # the other two, and both finish about together
            order = list(reversed(range(1 if early else 0, len(tasks))))
            if early is not None and len(order) >= 2:
                order[0], order[1] = order[1], order[0]
            futures = {i: pool.submit(_sweep_worker, tasks[i]) for i in order}
            if early is not None:
                futures[0] = early
            # the map's Dataset needs xarray (~0.6 s for the import and the first Dataset):
            # now, while the chains run in the pool's processes (forked without it)
            warm_xarray()
            done = [futures[i].result() for i in range(len(tasks))]
        else:
            # the same work as with several processes (identical statuses and numbers)
            done = [(_sweep(*t), t[-1]) for t in tasks]
    rows: list = [None] * len(ths)
    for k, row in starts.items():
        rows[k] = row
    merged = list(done[-1][1]) if done else list(proofs)
    for (_k, chain), (chain_rows, _p) in zip(chains, done):
        for i, row in zip(chain, chain_rows):
            rows[i] = row
    for _rows, chain_proofs in reversed(done[:-1]):
        merged += [q for q in chain_proofs if q not in merged]
    rows = _sweep_back(ths, nus, model, opts, rows, chains, merged)
    import xarray as xr

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
    beyond the map (:func:`~chuteflow.steady.follow.follow`): in θ at fixed ν0(0) until it
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
    # thin layers count, where Newton resolved them (a thin layer only the shooting scan
    # found has no flow to follow)
    has_flow = np.array([[f is not None for f in row] for row in flows], dtype=bool).reshape(st.shape)
    usable = ((st == "ok") | (st == "thin")) & has_flow
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

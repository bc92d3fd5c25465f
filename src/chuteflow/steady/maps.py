"""Maps of steady flows over a (θ, ν0(0)) grid and their image in the (h, ν̄) plane (§3.2).

Each θ row is solved by continuation along ν0 (:func:`~chuteflow.steady.family.continue_row`);
a row also starts from the converged points of the row before it (continuation in θ), which
reaches the non-monotonic branches that a cold start misses. Rows are swept outwards from a
middle row in two directions, which are independent: with ``workers=2`` they run in two
processes (one BLAS thread each).
"""
from __future__ import annotations

import os

import numpy as np

from ..closures import ChuteModel
from ..errors import ParameterError
from .family import (SCALARS, Options, _check_nu0, _row_arrays, _var_attrs, continue_row,
                     dataset_attrs)
from .solver import _validate


def _sweep(thetas, nus, model, opts, seed_row=None):
    """Rows in the given θ order, each seeded by the previous one; returns list of rows."""
    rows = []
    prev = seed_row
    for th in thetas:
        row = continue_row(th, nus, model, opts, previous=prev)
        rows.append(row)
        if any(p.usable for p in row):
            prev = row
        # a row without any solution keeps the last useful one as seed (a gap of one row)
    return rows


def _sweep_worker(args):
    from .._threads import limit_blas_threads
    limit_blas_threads(1)
    thetas, nus, model, opts, seed_row = args
    return _sweep(thetas, nus, model, opts, seed_row)


def steady_map(theta_values, nu0_values, model: ChuteModel | None = None, *,
               nu_top: float = 1e-9, n: int = 64, rtol: float = 1e-8, n_max: int = 384,
               min_thickness: float = 1.0, tangent: bool = False, workers: int | None = 1,
               start_theta: float | None = None):
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
    start_theta : float, optional
        Row where the sweeps start (default: the θ closest to the middle of the range).

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
        raise ParameterError("theta_values: expected a strictly increasing 1-D sequence of "
                             "angles in degrees")
    for th in ths:
        _validate(th, 0.5 * model.nu_max, model, 1e-9)
    nus = _check_nu0(nu0_values, model)
    _validate(ths[0], nus[0], model, nu_top)
    # fail fast: beyond the existence boundary every attempt fails, and points past a
    # failure are usually reached again from the neighbouring row: no substeps, and one
    # cold start for rows that have a neighbouring row to continue from
    opts = Options(nu_top=nu_top, n=n, rtol=rtol, n_max=n_max, min_thickness=min_thickness,
                   tangent=tangent, substeps=0)
    if start_theta is None:
        start_theta = 0.5 * (ths[0] + ths[-1])
    k = int(np.argmin(np.abs(ths - start_theta)))
    up, down = list(ths[k:]), list(ths[:k][::-1])
    if workers is None:
        workers = 2 if (os.cpu_count() or 1) >= 2 else 1
    if workers >= 2 and down:
        import multiprocessing as mp
        from concurrent.futures import ProcessPoolExecutor

        from ..equations import compiled_equations
        compiled_equations()  # compile once before forking: children inherit it
        model.evaluate(0.1, 1.0)
        ctx = mp.get_context("fork") if "fork" in mp.get_all_start_methods() else None
        with ProcessPoolExecutor(max_workers=2, mp_context=ctx) as pool:
            # the downward sweep starts from the first row of the upward one: solve that
            # row here first so both directions share it
            first = continue_row(up[0], nus, model, opts)
            fu = pool.submit(_sweep_worker, (up[1:], nus, model, opts, first))
            fd = pool.submit(_sweep_worker, (down, nus, model, opts, first))
            rows_up = [first] + fu.result()
            rows_down = fd.result()
    else:
        rows_up = _sweep(up, nus, model, opts)
        rows_down = _sweep(down, nus, model, opts, rows_up[0])
    rows = rows_down[::-1] + rows_up
    arrays = [_row_arrays(r) for r in rows]
    data = {}
    for key in arrays[0]:
        data[key] = (("theta", "nu0"), np.stack([a[key] for a in arrays]), _var_attrs(key))
    ds = xr.Dataset(data, coords={
        "theta": ("theta", ths, {"long_name": "inclination θ", "units": "degree"}),
        "nu0": ("nu0", nus, {"long_name": "floor packing fraction ν0(0)", "units": "1"})},
        attrs=dataset_attrs(model, opts))
    return ds


__all__ = ["steady_map", "SCALARS"]

"""Stability diagrams on a fine grid at the cost of a coarse one.

The steady flow and its kinematic quantities cost milliseconds per point; the long-wave
coefficient α2, which decides stability (§4.2), costs 0.1–0.8 s. The diagrams of
``chuteflow reproduce`` therefore sweep a fine (θ, ν0(0)) grid with the cheap metrics
everywhere and α2 only on every ``stride``-th row and column (:class:`StridedLongWave`),
and :func:`refine_longwave` then computes α2 exactly wherever the coarse values do not
settle the sign:

* in every coarse cell whose computed corners disagree in the sign of Re α2 (the
  boundary of an unstable region passes through it), or that has flows but no computed
  corner: at each of its fine points;
* at the least dense flow of each θ row (the end of the contour that the checks of §4.2
  follow beyond the grid), and where the dispersion relation was sampled
  (:class:`StridedGrowth`, the finite-k cross-check).

Elsewhere all computed corners of the cell agree, and Re α2 is interpolated between them
(inverse-distance weights in index space: a convex combination, so the sign is that of
the corners) and flagged in ``alpha2_inferred``. The unstable regions of the figure are
then filled contours of this gridded field on the fine grid.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..._memory import keep_freed_memory
from ..._threads import limit_blas_threads
from ...errors import ChuteflowError, ParameterError
from ...steady import solve_steady
from ...sweep.metrics import GrowthMetric, LongWaveMetric
from ...sweep.points import Point, PointFunction, register_point_function
from ...sweep.regimes import classify

__all__ = ["StridedGrowth", "StridedLongWave", "refine_longwave"]


@register_point_function
class StridedLongWave(PointFunction):
    """The ``longwave`` metric on every ``stride``-th θ row and ν0(0) column (and at marked
    points); elsewhere its variables stay missing for :func:`refine_longwave`."""

    name = "longwave_strided"
    version = "2"  # 2: the inner longwave metric's version 5 (α1 from the steady tangent)
    requires = ("steady",)
    defaults = {"stride": 3, **LongWaveMetric.defaults}
    variables = LongWaveMetric.variables

    def validate(self):
        if int(self.options["stride"]) < 1:
            raise ParameterError("longwave_strided: stride must be >= 1 (1 = every point)")
        self.inner()  # validates the long-wave options

    def inner(self) -> LongWaveMetric:
        """The ``longwave`` metric with this one's long-wave options."""
        return LongWaveMetric(**{k: v for k, v in self.options.items() if k != "stride"})

    def compute(self, flow, point):
        s = int(self.options["stride"])
        if point.i >= 0 and (point.i % s or point.j % s):
            return {}
        return self.inner().compute(flow, point)


@register_point_function
class StridedGrowth(GrowthMetric):
    """The ``growth`` metric (sampled dispersion relation, the finite-k cross-check) in a
    diagram whose α2 comes from :class:`StridedLongWave`; :func:`refine_longwave` computes
    α2 exactly at every sampled point."""

    name = "growth_strided"
    requires = ("steady", StridedLongWave.name)


def _coarse(n: int, s: int) -> list[int]:
    idx = list(range(0, n, s))
    if idx[-1] != n - 1:
        idx.append(n - 1)
    return idx


def _fine_point(args) -> tuple[int, int, dict | None, str]:
    i, j, theta, nu0, model, kw, options, flow = args
    limit_blas_threads(1)
    try:
        if flow is None:
            flow = solve_steady(theta, nu0, model, **kw, strict=True)
        return i, j, dict(LongWaveMetric(**options).compute(flow, Point(i, j, theta, nu0))), ""
    except (ChuteflowError, ArithmeticError, ValueError, np.linalg.LinAlgError) as exc:
        return i, j, None, f"{type(exc).__name__}: {exc}"


def refine_longwave(ds, config, *, workers: int = 2, progress=None, flows=None) -> tuple[Any, dict]:
    """Complete Re α2 of a sweep made with :class:`StridedLongWave` (module docstring).

    Parameters
    ----------
    ds : xarray.Dataset
        The sweep (``status`` 0 where a steady flow was found).
    config : chuteflow.sweep.SweepConfig
        Its configuration (model, steady settings, the strided metric's options).
    workers : int
        Processes for the exact computations (fork; one BLAS thread each).
    flows : dict, optional
        The sweep's steady flows by grid index (i, j) (:attr:`chuteflow.sweep.Sweep.flows`
        after ``run(keep_flows=True)``): used where present instead of solving the steady
        flow again (the same settings; ~40 ms of the ~95 ms per fine point).

    Returns
    -------
    (xarray.Dataset, dict)
        The classified Dataset with α2 everywhere a flow is (``alpha2_inferred``: 1 where
        interpolated, 0 where computed), and counts: ``coarse`` (computed by the sweep),
        ``refined`` (computed here), ``inferred``, ``failed``.
    """
    import json

    spec = next(json.loads(m) for m in config.metrics if json.loads(m)["name"] == StridedLongWave.name)
    options = {k: v for k, v in spec.get("options", {}).items() if k != "stride"}
    s = int(spec.get("options", {}).get("stride", StridedLongWave.defaults["stride"]))
    ds = ds.load().copy()
    ok = ds["status"].values == 0
    a2 = ds["alpha2_re"].values.copy()
    have = np.isfinite(a2) & ok
    ni, nj = ok.shape
    I, J = _coarse(ni, s), _coarse(nj, s)
    todo: set[tuple[int, int]] = set()
    if "dispersion_sampled" in ds:  # the finite-k cross-check compares with α2 there
        sampled = (ds["dispersion_sampled"].values == 1) & ok & ~have
        todo.update((int(i), int(j)) for i, j in zip(*np.nonzero(sampled)))
    for i in range(ni):  # the least dense flow of each row (checks of §4.2)
        js = np.nonzero(ok[i])[0]
        if len(js) and not have[i, js[0]]:
            todo.add((i, int(js[0])))
    cells = []
    for a, b in zip(I[:-1], I[1:]):
        for c, d in zip(J[:-1], J[1:]):
            corners = [(p, q) for p in (a, b) for q in (c, d) if have[p, q]]
            signs = {bool(a2[p, q] > 0) for p, q in corners}
            fine = [(p, q) for p in range(a, b + 1) for q in range(c, d + 1) if ok[p, q] and not have[p, q]]
            if not fine:
                continue
            if len(signs) == 1:
                cells.append((corners, fine))
            else:
                todo.update(fine)
    counts = {"coarse": int(have.sum()), "refined": 0, "inferred": 0, "failed": 0}
    kw = dict(
        nu_top=config.nu_top, rtol=config.steady_rtol, n_max=config.n_max, min_thickness=config.min_thickness
    )
    th, nu = ds["theta"].values, ds["nu0"].values
    flows = flows or {}
    jobs = [
        (i, j, float(th[i]), float(nu[j]), config.model, kw, options, flows.get((i, j)))
        for i, j in sorted(todo)
    ]
    if progress:
        progress(f"long-wave coefficient at {len(jobs)} fine points where the coarse grid does not decide")
    if workers >= 2 and len(jobs) > 1:
        import multiprocessing as mp
        from concurrent.futures import ProcessPoolExecutor

        ctx = mp.get_context("fork") if "fork" in mp.get_all_start_methods() else None
        with ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=keep_freed_memory) as pool:
            results = list(pool.map(_fine_point, jobs, chunksize=max(1, len(jobs) // (8 * workers))))
    else:
        results = [_fine_point(job) for job in jobs]
    names = [v.name for v in LongWaveMetric.variables]
    arrays = {n: ds[n].values.copy() for n in names}
    msg = ds["message"].values.astype(object) if "message" in ds else None
    for i, j, values, err in results:
        if values is None:
            counts["failed"] += 1
            if msg is not None:
                msg[i, j] = "; ".join(x for x in (str(msg[i, j]), f"longwave: {err}"[:300]) if x)
            continue
        counts["refined"] += 1
        for n, v in values.items():
            if n in arrays and v is not None:
                arrays[n][i, j] = float(v)
    computed = np.isfinite(arrays["alpha2_re"]) & ok
    inferred = np.zeros(ok.shape, dtype=bool)
    for corners, fine in cells:
        for p, q in fine:
            if computed[p, q] or inferred[p, q]:
                continue
            w = np.array([1.0 / math.hypot(p - a, q - c) for a, c in corners])
            arrays["alpha2_re"][p, q] = float(np.dot(w, [a2[a, c] for a, c in corners]) / w.sum())
            inferred[p, q] = True
    counts["inferred"] = int(inferred.sum())
    for n in names:
        ds[n] = (ds[n].dims, arrays[n].astype(ds[n].dtype), ds[n].attrs)
    if msg is not None:
        ds["message"] = (ds["message"].dims, msg.astype(str), ds["message"].attrs)
    flag = np.where(ok & (computed | inferred), inferred.astype(np.int8), np.int8(-1)).astype(np.int8)
    ds["alpha2_inferred"] = (
        ("theta", "nu0"),
        flag,
        {
            "units": "1",
            "long_name": "Re α2 interpolated between computed coarse points of the same sign "
            "(1), computed (0)",
            "flag_values": np.array([-1, 0, 1], dtype=np.int8),
            "flag_meanings": "missing false true",
        },
    )
    ds.attrs["longwave_stride"] = s
    return classify(ds), counts

"""One task of a sweep: a chunk of a θ row, solved with continuation in ν0(0).

:func:`run_task` is what worker processes (local pool or Dask) execute. It is a pure function
of (configuration, task): with one BLAS thread it gives bit-identical numbers wherever it runs,
which is what makes resumed, local and Dask sweeps equal.
"""

from __future__ import annotations

import resource
import time
import traceback
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from .._memory import release_free_memory
from .._threads import limit_blas_threads
from ..equations import warm_up as _warm_up
from ..errors import ChuteflowError, ConvergenceError, NoSteadyFlowError
from ..steady import solve_steady, steady_row
from .points import Point

if TYPE_CHECKING:
    from ..steady import SteadyFlow

__all__ = ["STATUS", "TaskResult", "run_task", "warm_up"]

#: Per-point status codes (Dataset variable ``status``; ``flag_meanings`` in that order).
STATUS = {"ok": 0, "no_steady_flow": 1, "not_converged": 2, "error": 3}
#: Longest message kept per point.
MAX_MESSAGE = 400


@dataclass
class TaskResult:
    """Results of one task: per-variable arrays over the task's points, status and messages.

    ``seconds`` and ``max_rss_kib`` describe the run (statistics only; never stored in the
    Dataset, which must not depend on how it was computed).
    """

    key: str
    digest: str
    i: int
    j0: int
    j1: int
    values: dict[str, np.ndarray]
    status: np.ndarray
    message: np.ndarray
    seconds: float = 0.0
    max_rss_kib: int = 0
    point_seconds: np.ndarray = field(default_factory=lambda: np.zeros(0))
    metric_seconds: dict = field(default_factory=dict)
    #: The steady flows of the task's grid points, by column j (only with ``keep_flows``;
    #: never stored, for follow-up computations in the same run).
    flows: dict = field(default_factory=dict)


_THREADS_LIMITED = False


def _single_thread():
    global _THREADS_LIMITED
    if not _THREADS_LIMITED:
        limit_blas_threads(1)
        _THREADS_LIMITED = True


def warm_up(config=None) -> None:
    """Compile the symbolic equations and the configuration's closures once (forked workers
    inherit them): :func:`chuteflow.equations.warm_up`."""
    _warm_up(config.model if config is not None else None)


def _clip(msg: str) -> str:
    msg = " ".join(str(msg).split())
    return msg if len(msg) <= MAX_MESSAGE else msg[: MAX_MESSAGE - 1] + "…"


def _coerce(var, value):
    if value is None:
        return var.missing
    if var.kind == "flag":
        return np.int8(1 if bool(value) else 0)
    if var.kind == "int":
        return np.int32(int(value))
    return float(value)


#: steady_family status → sweep status
_FAMILY_STATUS = {
    "ok": "ok",
    "no_steady_flow": "no_steady_flow",
    "thin": "no_steady_flow",
    "not_converged": "not_converged",
    "unreached": "not_converged",
}


def _steady_chunk(config, theta: float, nus, model):
    """Steady flows along one chunk of a θ row: :func:`chuteflow.steady.steady_row`
    (continuation in ν0 along the exact family tangent, intermediate steps where a step fails,
    a few spread-out cold starts where there is nothing to continue from).

    Returns a list over the chunk of (flow or None, status name, message).
    """

    row = steady_row(
        theta,
        list(nus),
        model,
        nu_top=config.nu_top,
        rtol=config.steady_rtol,
        n_max=config.n_max,
        min_thickness=config.min_thickness,
    )
    out = []
    for st, flow, msg in row:
        if st == "unreached":
            msg = f"steady: not attempted: {msg}"
        elif st != "ok":
            msg = f"steady: {msg}"
        out.append((flow, _FAMILY_STATUS.get(st, "error"), "" if st == "ok" else msg))
    return out


def run_task(config, task, *, limit_threads: bool = True, keep_flows: bool = False) -> TaskResult:
    """Compute every point of ``task`` (see :class:`~chuteflow.sweep.config.Task`).

    Steady flows come from :func:`_steady_chunk` (continuation along ν0; each marked point
    from its own cold start). Errors at a point become its status and message;
    nothing here raises for a single point. ``keep_flows``: also return the grid points'
    steady flows (:attr:`TaskResult.flows`).
    """

    if limit_threads:
        _single_thread()
    t_start = time.perf_counter()
    fns = config.point_functions()
    variables = [v for f in fns for v in f.variables]
    byname = {v.name: v for v in variables}
    owner = {v.name: f.name for f in fns for v in f.variables}
    m = task.size
    values = {v.name: np.full(m, v.missing, dtype=v.dtype) for v in variables}
    status = np.zeros(m, dtype=np.int8)
    messages = [""] * m
    pt_seconds = np.zeros(m)
    model = config.model
    marker = task.i < 0
    msec = {"steady": 0.0}
    kw = dict(
        nu_top=config.nu_top, rtol=config.steady_rtol, n_max=config.n_max, min_thickness=config.min_thickness
    )
    t0 = time.perf_counter()
    if marker:
        # marked points are unrelated: each from the cold start
        pts = [(config.markers[j][1], config.markers[j][2]) for j in range(task.j0, task.j1)]
        steady: list[tuple[SteadyFlow | None, str, str]] = []
        for th, nu in pts:
            try:
                steady.append((solve_steady(th, nu, model, **kw, strict=True), "ok", ""))
            except NoSteadyFlowError as exc:
                steady.append((None, "no_steady_flow", str(exc)))
            except ConvergenceError as exc:
                steady.append((None, "not_converged", f"steady: {exc}"))
            except Exception as exc:
                steady.append((None, "error", f"steady: {type(exc).__name__}: {exc}"))
    else:
        th = config.theta[task.i]
        pts = [(th, config.nu0[j]) for j in range(task.j0, task.j1)]
        try:
            steady = _steady_chunk(config, th, [p[1] for p in pts], model)
        except Exception as exc:  # the whole chunk failed
            steady = [(None, "error", f"steady: {type(exc).__name__}: {exc}")] * len(pts)
    msec["steady"] += time.perf_counter() - t0
    # the steady solves of a chunk are shared: spread their time evenly
    pt_seconds[:] = (time.perf_counter() - t0) / max(m, 1)
    for k, j in enumerate(range(task.j0, task.j1)):
        theta, nu0 = pts[k]
        flow, st_name, msg = steady[k]
        point = Point(task.i, j, theta, nu0)
        if flow is None:
            status[k], messages[k] = STATUS[st_name], _clip(msg)
            continue
        t0 = time.perf_counter()
        for f in fns:
            tm = time.perf_counter()
            try:
                out = dict(f.compute(flow, point))
                bad = [n for n in out if n not in byname or owner[n] != f.name]
                if bad:
                    raise ValueError(f"point function {f.name!r} returned undeclared variable(s) {bad}")
                # all values of a metric or none: coerce first, then store
                coerced = {n: _coerce(byname[n], v) for n, v in out.items()}
                for name, val in coerced.items():
                    values[name][k] = val
                    point.values[name] = val
            except Exception as exc:  # recorded for this point
                code = STATUS["not_converged"] if isinstance(exc, ConvergenceError) else STATUS["error"]
                text = f"{f.name}: {exc}"
                if not isinstance(exc, ChuteflowError):
                    tb = traceback.extract_tb(exc.__traceback__)[-1]
                    text = (
                        f"{f.name}: {type(exc).__name__}: {exc} "
                        f"({tb.filename.rsplit('/', 1)[-1]}:{tb.lineno})"
                    )
                messages[k] = _clip("; ".join(x for x in (messages[k], text) if x))
                if f.critical:
                    status[k] = code
                    break
                # a non-critical metric (a cross-check) leaves its variables missing and
                # the point's status as it is; its message says why
            finally:
                msec[f.name] = msec.get(f.name, 0.0) + time.perf_counter() - tm
        if point.notes:
            messages[k] = _clip("; ".join([x for x in [messages[k]] if x] + point.notes))
        pt_seconds[k] += time.perf_counter() - t0
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    # the task's dense problems are freed: their pages go back now, so that the next task's
    # peak does not stack on what this one left in the heap (after every point instead, the
    # pages faulted in again cost the long-wave metric 12 %)
    release_free_memory()
    return TaskResult(
        key=task.key,
        digest=config.digest(),
        i=task.i,
        j0=task.j0,
        j1=task.j1,
        values=values,
        status=status,
        message=np.array(messages, dtype=str),
        seconds=time.perf_counter() - t_start,
        max_rss_kib=int(rss),
        point_seconds=pt_seconds,
        metric_seconds=msec,
        flows=(
            {j: steady[k][0] for k, j in enumerate(range(task.j0, task.j1)) if steady[k][0] is not None}
            if keep_flows and not marker
            else {}
        ),
    )

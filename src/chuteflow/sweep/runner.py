"""One task of a sweep: a chunk of a θ row, solved with continuation in ν0(0).

:func:`run_task` is what worker processes (local pool or Dask) execute. It is a pure function
of (configuration, task): with one BLAS thread it gives bit-identical numbers wherever it runs,
which is what makes resumed, local and Dask sweeps equal.
"""
from __future__ import annotations

import resource
import time
import traceback
import warnings
from dataclasses import dataclass, field

import numpy as np

from ..errors import ChuteflowError, ConvergenceError, NoSteadyFlowError

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
    steady_retries: int = 0
    point_seconds: np.ndarray = field(default_factory=lambda: np.zeros(0))
    metric_seconds: dict = field(default_factory=dict)


_THREADS_LIMITED = False


def _single_thread():
    global _THREADS_LIMITED
    if not _THREADS_LIMITED:
        from .._threads import limit_blas_threads
        limit_blas_threads(1)
        _THREADS_LIMITED = True


def warm_up(config=None) -> None:
    """Compile the symbolic equations and closures once (forked workers inherit them)."""
    from ..equations import compiled_equations
    compiled_equations()
    model = config.model() if config is not None else None
    if model is not None:
        model.evaluate(np.array([0.1]), np.array([1.0]))
        model.f(np.array([0.1]))


def _clip(msg: str) -> str:
    msg = " ".join(str(msg).split())
    return msg if len(msg) <= MAX_MESSAGE else msg[:MAX_MESSAGE - 1] + "…"


def _coerce(var, value):
    if value is None:
        return var.missing
    if var.kind == "flag":
        return np.int8(1 if bool(value) else 0)
    if var.kind == "int":
        return np.int32(int(value))
    v = float(value)
    return v


def _anchor_order(n: int) -> list[int]:
    """Cold-start candidates spread over a chunk: middle, quartiles, eighths, …"""
    order, seen, k = [], set(), 2
    while len(order) < n and k <= 4 * n:
        for j in range(1, k, 2):
            i = min(n - 1, (j * n) // k)
            if i not in seen:
                seen.add(i)
                order.append(i)
        k *= 2
    return order + [i for i in range(n) if i not in seen]


def _steady_chunk(config, theta: float, nus, model, kw):
    """Steady flows along one chunk of a θ row by continuation in ν0.

    Cold starts at anchors (middle of the chunk, then quartiles, …; at most
    ``config.max_cold``) until one converges; from there the flows are continued to both
    sides, each point from its converged neighbour (through intermediate densities when the
    direct step fails). A continued solve that still fails ends that walk (it is retried from
    the cold start if ``config.retry_cold``). Points beyond are not attempted: failed cold
    starts cost seconds each, continued ones milliseconds.

    Returns a list over the chunk of (flow or exception or None for not attempted,
    seconds), and the number of cold retries.
    """
    from ..steady import solve_steady

    n = len(nus)
    res: list = [None] * n
    secs = np.zeros(n)
    tried = [set() for _ in range(n)]
    retries = 0
    cold = 0

    def continued(guess, nu):
        """Solve at nu from the converged neighbour ``guess``; when that fails, walk there
        through 1, then 3 intermediate densities (a step too long for Newton is the usual
        reason, not the absence of a flow)."""
        try:
            return solve_steady(theta, nu, model, guess=guess, **kw)
        except (NoSteadyFlowError, ConvergenceError) as exc:
            first = exc
        for parts in (2, 4):
            cur = guess
            try:
                for q in range(1, parts):
                    cur = solve_steady(theta, guess.nu0 + (nu - guess.nu0) * q / parts, model,
                                       guess=cur, **kw)
                return solve_steady(theta, nu, model, guess=cur, **kw)
            except (NoSteadyFlowError, ConvergenceError):
                continue
        raise first

    def attempt(j, guess, tag):
        nonlocal retries
        tried[j].add(tag)
        t0 = time.perf_counter()
        try:
            try:
                out = (continued(guess, nus[j]) if guess is not None
                       else solve_steady(theta, nus[j], model, **kw))
            except (NoSteadyFlowError, ConvergenceError):
                if guess is None or not config.retry_cold:
                    raise
                retries += 1
                out = solve_steady(theta, nus[j], model, **kw)
        except Exception as exc:  # noqa: BLE001 - the point's outcome
            out = exc
        secs[j] += time.perf_counter() - t0
        if res[j] is None or not isinstance(out, Exception):
            res[j] = out

    def ok(j):
        return res[j] is not None and not isinstance(res[j], Exception)

    order = _anchor_order(n)
    while True:
        walked = True
        while walked:
            walked = False
            for j in range(1, n):
                if not ok(j) and ok(j - 1) and "below" not in tried[j]:
                    attempt(j, res[j - 1], "below")
                    walked = True
            for j in range(n - 2, -1, -1):
                if not ok(j) and ok(j + 1) and "above" not in tried[j]:
                    attempt(j, res[j + 1], "above")
                    walked = True
        if cold >= config.max_cold or any(ok(j) for j in range(n)):
            break
        # no flow yet: next anchor, spread out over the chunk
        cand = [j for j in order if res[j] is None]
        if not cand:
            break
        cold += 1
        attempt(cand[0], None, "cold")
    return list(zip(res, secs)), retries


def run_task(config, task, *, limit_threads: bool = True) -> TaskResult:
    """Compute every point of ``task`` (see :class:`~chuteflow.sweep.config.Task`).

    Steady flows come from :func:`_steady_chunk` (anchors and continuation along ν0; each
    marked point from its own cold start). Errors at a point become its status and message;
    nothing here raises for a single point.
    """
    from ..steady import solve_steady

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
    model = config.model()
    marker = task.i < 0
    retries = 0
    msec = {"steady": 0.0}
    kw = dict(nu_top=config.nu_top, rtol=config.steady_rtol, n_max=config.n_max,
              min_thickness=config.min_thickness)
    from .points import Point
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        # overflow in trial Newton steps is expected and handled by the solvers
        warnings.simplefilter("ignore", RuntimeWarning)
        if marker:
            # marked points are unrelated: each from the cold start
            pts = [(config.markers[j][1], config.markers[j][2]) for j in range(task.j0, task.j1)]
            steady = []
            for th, nu in pts:
                t0 = time.perf_counter()
                try:
                    out = solve_steady(th, nu, model, **kw)
                except Exception as exc:  # noqa: BLE001
                    out = exc
                steady.append((out, time.perf_counter() - t0))
        else:
            th = config.theta[task.i]
            pts = [(th, config.nu0[j]) for j in range(task.j0, task.j1)]
            steady, retries = _steady_chunk(config, th, [p[1] for p in pts], model, kw)
        for k, j in enumerate(range(task.j0, task.j1)):
            theta, nu0 = pts[k]
            flow, t_steady = steady[k]
            msec["steady"] += t_steady
            pt_seconds[k] = t_steady
            t0 = time.perf_counter()
            point = Point(task.i, j, theta, nu0)
            if flow is None:
                status[k] = STATUS["not_converged"]
                messages[k] = _clip(
                    "steady: not attempted: beyond a failed continuation, or no flow at the "
                    f"cold-start anchors of this chunk of the theta = {theta:g} row (max_cold = "
                    f"{config.max_cold})")
                continue
            if isinstance(flow, NoSteadyFlowError):
                status[k], messages[k] = STATUS["no_steady_flow"], _clip(flow)
                continue
            if isinstance(flow, ConvergenceError):
                status[k], messages[k] = STATUS["not_converged"], _clip(f"steady: {flow}")
                continue
            if isinstance(flow, Exception):
                status[k] = STATUS["error"]
                messages[k] = _clip(f"steady: {type(flow).__name__}: {flow}")
                continue
            for f in fns:
                tm = time.perf_counter()
                try:
                    out = dict(f.compute(flow, point))
                    bad = [n for n in out if n not in byname or owner[n] != f.name]
                    if bad:
                        raise ValueError(f"point function {f.name!r} returned undeclared "
                                         f"variable(s) {bad}")
                    # all values of a metric or none: coerce first, then store
                    coerced = {n: _coerce(byname[n], v) for n, v in out.items()}
                    for name, val in coerced.items():
                        values[name][k] = val
                        point.values[name] = val
                except Exception as exc:  # noqa: BLE001 - recorded for this point
                    code = (STATUS["not_converged"] if isinstance(exc, ConvergenceError)
                            else STATUS["error"])
                    text = f"{f.name}: {exc}"
                    if not isinstance(exc, ChuteflowError):
                        tb = traceback.extract_tb(exc.__traceback__)[-1]
                        text = (f"{f.name}: {type(exc).__name__}: {exc} "
                                f"({tb.filename.rsplit('/', 1)[-1]}:{tb.lineno})")
                    messages[k] = _clip("; ".join(x for x in (messages[k], text) if x))
                    if f.critical:
                        status[k] = code
                        break
                    # a non-critical metric (a cross-check) leaves its variables missing and
                    # the point's status as it is; its message says why
                finally:
                    msec[f.name] = msec.get(f.name, 0.0) + time.perf_counter() - tm
            if point.notes:
                messages[k] = _clip("; ".join([m for m in [messages[k]] if m] + point.notes))
            pt_seconds[k] += time.perf_counter() - t0
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return TaskResult(key=task.key, digest=config.digest(), i=task.i, j0=task.j0, j1=task.j1,
                      values=values, status=status, message=np.array(messages, dtype=str),
                      seconds=time.perf_counter() - t_start, max_rss_kib=int(rss),
                      steady_retries=retries, point_seconds=pt_seconds, metric_seconds=msec)


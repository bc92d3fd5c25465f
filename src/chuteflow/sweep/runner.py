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


def run_task(config, task, *, limit_threads: bool = True) -> TaskResult:
    """Compute every point of ``task`` (see :class:`~chuteflow.sweep.config.Task`).

    Steady flows are continued along ν0 from the last successful point of the task; if a
    continued solve fails and ``config.retry_cold``, it is retried from the cold start, so a
    bad guess never decides that a flow does not exist. Errors at a point become its status
    and message; nothing here raises for a single point.
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
    guess = None
    retries = 0
    kw = dict(nu_top=config.nu_top, rtol=config.steady_rtol, n_max=config.n_max,
              min_thickness=config.min_thickness)
    from .points import Point
    with warnings.catch_warnings(), np.errstate(all="ignore"):
        # overflow in trial Newton steps is expected and handled by the solvers
        warnings.simplefilter("ignore", RuntimeWarning)
        for k, j in enumerate(range(task.j0, task.j1)):
            t0 = time.perf_counter()
            if marker:
                # marked points are unrelated: each from the cold start
                _, theta, nu0 = config.markers[j]
                guess = None
            else:
                theta, nu0 = config.theta[task.i], config.nu0[j]
            point = Point(task.i, j, theta, nu0)
            try:
                try:
                    flow = solve_steady(theta, nu0, model, guess=guess, **kw)
                except (NoSteadyFlowError, ConvergenceError):
                    if guess is None or not config.retry_cold:
                        raise
                    retries += 1
                    flow = solve_steady(theta, nu0, model, **kw)
            except NoSteadyFlowError as exc:
                status[k], messages[k] = STATUS["no_steady_flow"], _clip(exc)
                pt_seconds[k] = time.perf_counter() - t0
                continue
            except ConvergenceError as exc:
                status[k], messages[k] = STATUS["not_converged"], _clip(f"steady: {exc}")
                pt_seconds[k] = time.perf_counter() - t0
                continue
            except Exception as exc:  # noqa: BLE001 - recorded as the point's status
                status[k] = STATUS["error"]
                messages[k] = _clip(f"steady: {type(exc).__name__}: {exc}")
                pt_seconds[k] = time.perf_counter() - t0
                continue
            guess = flow
            for f in fns:
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
                except ConvergenceError as exc:
                    status[k], messages[k] = STATUS["not_converged"], _clip(f"{f.name}: {exc}")
                    break
                except ChuteflowError as exc:
                    status[k], messages[k] = STATUS["error"], _clip(f"{f.name}: {exc}")
                    break
                except Exception as exc:  # noqa: BLE001
                    tb = traceback.extract_tb(exc.__traceback__)[-1]
                    status[k] = STATUS["error"]
                    messages[k] = _clip(f"{f.name}: {type(exc).__name__}: {exc} "
                                        f"({tb.filename.rsplit('/', 1)[-1]}:{tb.lineno})")
                    break
            pt_seconds[k] = time.perf_counter() - t0
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return TaskResult(key=task.key, digest=config.digest(), i=task.i, j0=task.j0, j1=task.j1,
                      values=values, status=status, message=np.array(messages, dtype=str),
                      seconds=time.perf_counter() - t_start, max_rss_kib=int(rss),
                      steady_retries=retries, point_seconds=pt_seconds)


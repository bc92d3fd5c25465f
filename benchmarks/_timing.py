"""The one timing rule of the benchmarks: the fastest of ``repeat`` calls.

The minimum over repeats is the least disturbed measurement on a shared machine; the
baseline of every row is timed by the same rule in the same run.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import Any


def best_of(fn: Callable[[], Any], repeat: int, *, cpu: dict | None = None) -> tuple[float, Any]:
    """(wall seconds of the fastest of ``repeat`` calls of ``fn``, the last call's result).

    With ``cpu`` (a dict), ``cpu["last"]`` is set to the CPU time of this process
    (``time.process_time``) during the fastest call: the wall time is that of a shared
    machine, the CPU time what the code itself costs.
    """
    best, out = math.inf, None
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        wall = time.perf_counter() - t0
        if wall < best:
            best = wall
            if cpu is not None:
                cpu["last"] = time.process_time() - c0
    return best, out

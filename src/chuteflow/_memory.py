"""glibc malloc settings for the solvers' processes: free memory handed back between sweep
tasks (:func:`release_free_memory`) and reused within them (:func:`keep_freed_memory`).

A sweep worker solves dense problems of a few MiB each (M × M at M = 644 for N = 160) in
varying sizes. glibc's malloc serves them from its heap once the first ones are freed (its
mmap threshold rises to the largest freed block) and keeps the freed pages: the worker's
resident memory then grows with every differently sized problem and peaks at the sum of the
retained pages and the next point's working set. :func:`release_free_memory` calls glibc's
``malloc_trim(0)``, which hands every free page of the heap back. Elsewhere (macOS, musl,
Windows) it does nothing.
"""

from __future__ import annotations

import ctypes
import functools
import sys
from collections.abc import Callable


@functools.cache
def _glibc(name: str, *argtypes) -> Callable[..., int] | None:
    """The C library function ``name`` (returning int, taking ``argtypes``) of this
    process, or None where it has none (not Linux, or not glibc: e.g. musl)."""
    if not sys.platform.startswith("linux"):
        return None
    try:
        fn = getattr(ctypes.CDLL(None), name)
    except (OSError, AttributeError):
        return None
    fn.argtypes = list(argtypes)
    fn.restype = ctypes.c_int
    return fn


def release_free_memory() -> bool:
    """Return the heap's free pages to the operating system (glibc ``malloc_trim(0)``).

    Returns whether anything could be asked (False where the C library has no
    ``malloc_trim``). Costs about a millisecond; live objects are untouched.
    """
    fn = _glibc("malloc_trim", ctypes.c_size_t)
    if fn is None:
        return False
    fn(0)
    return True


#: glibc ``mallopt`` parameters (malloc.h): M_TRIM_THRESHOLD, M_MMAP_THRESHOLD.
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3
#: Blocks up to this size come from the heap (glibc's largest allowed value on 64-bit).
MMAP_THRESHOLD = 32 * 2**20
#: Free memory at the top of the heap kept for the next allocations (not returned to the
#: operating system before it exceeds this; :func:`release_free_memory` returns it anyway).
TRIM_THRESHOLD = 256 * 2**20


def keep_freed_memory() -> bool:
    """Let glibc's malloc reuse freed memory instead of asking the kernel for fresh pages.

    The solvers allocate and free dense matrices of 0.1–10 MiB many times a second (the
    steady Jacobian, the stability pencils and their LU factors). By default glibc gives a
    block above its mmap threshold back to the kernel on ``free`` and hands freed memory at
    the top of the heap back once it exceeds the trim threshold: the next matrix of that
    size then costs a page fault (and the kernel's zeroing) per 4 KiB. With blocks up to
    :data:`MMAP_THRESHOLD` served from the heap and up to :data:`TRIM_THRESHOLD` of it
    kept, the same numbers bit for bit: in one process the long-wave metric at 295 flows
    of the 60 × 60 diagram took 17–20 % less CPU (page faults 525 000 → 40 000, peak
    memory unchanged), the growth metric's 73 flows 6 % less, 20 rows of the diagram's
    steady stage 3.5 % less (processes side by side). A sweep worker still hands its free
    pages back after each task (:func:`release_free_memory`, for its peak memory), so there
    the gain is smaller: the 60 × 60 diagram's workers fault 0.61 instead of 1.33 million
    times, ~1 % of their time.

    Called in the worker processes chuteflow starts (sweeps, steady maps, the paper's
    adaptive refinement) and by its command line, never on a caller's own process. Returns
    whether glibc took both settings (False elsewhere: macOS, musl, Windows).
    """
    fn = _glibc("mallopt", ctypes.c_int, ctypes.c_int)
    if fn is None:
        return False
    return bool(fn(_M_MMAP_THRESHOLD, MMAP_THRESHOLD)) & bool(fn(_M_TRIM_THRESHOLD, TRIM_THRESHOLD))


def brentq(f: Callable[[float], float], a: float, b: float, **kwargs) -> float:
    """:func:`scipy.optimize.brentq` without keeping ``f`` alive afterwards.

    scipy wraps ``f`` in a closure that refers to itself (its NaN check counts the calls on
    the closure), a reference cycle: ``f`` and everything it captures — a solver's
    operators and factorisations, a shooting scan's trajectories — then stay in memory
    until Python's cyclic garbage collector runs, which it does by object counts, not by
    size. Here scipy is handed a forwarder whose target is dropped on return, so those
    objects are freed as soon as the caller lets go of them (on the 60 × 60 diagram's
    growth rows, up to ~28 MiB of stability operators at N = 160 per worker). Arguments
    and result as :func:`scipy.optimize.brentq`.
    """
    from scipy.optimize import brentq as _brentq

    target = [f]

    def forward(x, *args):
        return target[0](x, *args)

    try:
        return _brentq(forward, a, b, **kwargs)
    finally:
        target.clear()

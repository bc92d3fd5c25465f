"""Give the heap's free memory back to the operating system between sweep tasks.

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
def _malloc_trim() -> Callable[[int], int] | None:
    """glibc's ``malloc_trim`` from the process's C library, or None (not Linux, not glibc)."""
    if not sys.platform.startswith("linux"):
        return None
    try:
        fn = ctypes.CDLL(None).malloc_trim
    except (OSError, AttributeError):  # not glibc (e.g. musl)
        return None
    fn.argtypes = [ctypes.c_size_t]
    fn.restype = ctypes.c_int
    return fn


def release_free_memory() -> bool:
    """Return the heap's free pages to the operating system (glibc ``malloc_trim(0)``).

    Returns whether anything could be asked (False where the C library has no
    ``malloc_trim``). Costs about a millisecond; live objects are untouched.
    """
    fn = _malloc_trim()
    if fn is None:
        return False
    fn(0)
    return True

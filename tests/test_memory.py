"""chuteflow._memory: handing the heap's free pages back between sweep points (issue 9)."""

from __future__ import annotations

import gc
import platform
import sys
import weakref

import numpy as np
import pytest

from chuteflow._memory import brentq, release_free_memory


def _rss_kib() -> int:
    with open("/proc/self/status") as fh:
        for line in fh:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    raise AssertionError("no VmRSS line")  # pragma: no cover


def test_release_free_memory_answers_whether_it_could_trim():
    glibc = sys.platform.startswith("linux") and platform.libc_ver()[0] == "glibc"
    assert release_free_memory() is glibc
    assert release_free_memory() is glibc  # idempotent


def test_release_free_memory_returns_freed_heap_pages_and_keeps_live_data():
    if not (sys.platform.startswith("linux") and platform.libc_ver()[0] == "glibc"):
        return  # nothing to trim: checked by the test above
    # a heap like a worker's after a point: blocks of a few MiB, every other one freed (the
    # first free raises glibc's mmap threshold, so the rest come from the heap)
    first = np.ones(3 * 2**20 // 8)
    del first
    blocks = [np.full(3 * 2**20 // 8, float(i)) for i in range(40)]
    del blocks[::2]
    release_free_memory()
    before = _rss_kib()
    keep = blocks
    blocks = [np.full(3 * 2**20 // 8, -1.0) for _ in range(20)]
    del blocks  # 60 MiB freed on top of the heap's live blocks
    freed_kept = _rss_kib()
    release_free_memory()
    after = _rss_kib()
    assert freed_kept - after > 30 * 1024, (before, freed_kept, after)
    assert all(np.all(b == float(2 * i + 1)) for i, b in enumerate(keep))


_FAULTS = """
import resource, sys
import numpy as np
from chuteflow._memory import keep_freed_memory
if sys.argv[1] == "keep":
    assert keep_freed_memory()
def work():  # a solver's pattern: several matrices of a few MiB at once, then all freed
    mats = [np.ones((512, 512)) for _ in range(10)]
    del mats
work()
f0 = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for _ in range(30):
    work()
print(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - f0)
"""


def test_keep_freed_memory_reuses_freed_pages_in_its_own_process():
    """keep_freed_memory: matrices allocated and freed again and again come from the pages
    already held instead of fresh ones (a page fault each 4 KiB); run in subprocesses, as
    it changes malloc for the whole process."""
    import subprocess

    if not (sys.platform.startswith("linux") and platform.libc_ver()[0] == "glibc"):
        from chuteflow._memory import keep_freed_memory

        assert keep_freed_memory() is False
        return
    faults = {}
    for mode in ("default", "keep"):
        out = subprocess.run(
            [sys.executable, "-c", _FAULTS, mode], capture_output=True, text=True, check=True, timeout=120
        )
        faults[mode] = int(out.stdout.split()[-1])
    # 30 rounds of 10 × 2 MiB = 153 600 pages of 4 KiB: glibc's defaults fault on every
    # one (measured 152 660), kept pages on none (measured 0)
    assert faults["default"] > 100_000, faults
    assert faults["keep"] < 2_000, faults


def _captured():
    class Big:
        pass

    obj = Big()

    def f(x):
        return x - 0.25 if obj is not None else x

    return f, weakref.ref(obj)


def test_brentq_does_not_keep_the_function_alive():
    """scipy's brentq wraps f in a closure that refers to itself (a reference cycle), so
    what f captures outlives the call until the cyclic garbage collector runs;
    chuteflow._memory.brentq gives the same root and frees it at once (with the
    collector off, as between its runs)."""
    import scipy.optimize

    gc.collect()
    gc.disable()
    try:
        f, ref = _captured()
        root = brentq(f, 0.0, 1.0, xtol=1e-14)
        del f
        assert ref() is None
        assert root == pytest.approx(0.25, abs=1e-13)
        # the reason: scipy's own keeps it
        f, ref = _captured()
        assert scipy.optimize.brentq(f, 0.0, 1.0, xtol=1e-14) == root
        del f
        assert ref() is not None
    finally:
        gc.enable()
        gc.collect()

"""One BLAS thread per process.

chuteflow parallelises over parameter points (processes or dask workers), never
inside a dense eigenvalue solve, so a multi-threaded BLAS only oversubscribes the
cores. Stages and worker initialisers call :func:`limit_blas_threads` first.
"""

from __future__ import annotations

import os

#: Environment variables read by OpenMP, OpenBLAS, MKL, BLIS and Accelerate at load time.
BLAS_ENV_VARS = (
    "OMP_NUM_THREADS",
    "OPENBLAS_NUM_THREADS",
    "MKL_NUM_THREADS",
    "BLIS_NUM_THREADS",
    "VECLIB_MAXIMUM_THREADS",
    "NUMEXPR_NUM_THREADS",
)


def limit_blas_threads(n: int = 1, *, set_env: bool = True):
    """Limit BLAS/OpenMP thread pools of this process to ``n`` threads.

    Parameters
    ----------
    n : int
        Threads per pool (default 1).
    set_env : bool
        Also export the ``*_NUM_THREADS`` variables of :data:`BLAS_ENV_VARS`, so that
        child processes (multiprocessing, dask workers) start limited too.

    Returns
    -------
    threadpoolctl.threadpool_limits
        The limiter, already in effect. Use it as a context manager (``with
        limit_blas_threads(): ...``) to restore the previous limits on exit, or
        ignore it to keep the limit for the life of the process. Suitable as a
        process-pool ``initializer``.
    """
    if n < 1:
        raise ValueError(f"n = {n!r}: need at least one thread")
    if set_env:
        for var in BLAS_ENV_VARS:
            os.environ[var] = str(n)
    import numpy  # noqa: F401  -- load numpy's BLAS so that threadpoolctl can see it
    from threadpoolctl import threadpool_limits

    return threadpool_limits(limits=n)

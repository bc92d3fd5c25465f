"""The sweep engine: tasks → workers (local processes or Dask) → parts on disk → one Dataset.

Scheduling is left to :class:`concurrent.futures.ProcessPoolExecutor` (local, default) or to
``dask.distributed`` (``client=`` or ``scheduler=ADDRESS``). The calling process alone writes
results: each finished task goes to ``<out>.parts/`` at once (atomically), and when all tasks
are there they are assembled into the final NetCDF file (h5netcdf), again atomically. Run the
same sweep again after Ctrl-C or SIGKILL and only the missing tasks are computed; the final
file is the same as that of an uninterrupted run.
"""

from __future__ import annotations

import json
import multiprocessing as mp
import os
import sys
import time
from collections.abc import Callable
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .._imports import warm_xarray
from .._memory import keep_freed_memory
from .._threads import limit_blas_threads
from .._version import __version__
from ..errors import ParameterError
from .config import SweepConfig
from .regimes import classify
from .runner import STATUS, TaskResult, run_task, warm_up
from .store import ConfigMismatchError, PartStore, atomic_target

if TYPE_CHECKING:
    from ..steady import SteadyFlow

__all__ = [
    "Sweep",
    "SweepStats",
    "run_sweep",
    "assemble",
    "load_sweep",
    "write_dataset",
    "markers",
    "dask_client",
]


@dataclass
class SweepStats:
    """How a run went (not stored in the Dataset: it must not depend on how it was run).

    Attributes
    ----------
    tasks, computed, reused : int
        Tasks in the sweep, computed in this run, taken from saved parts (or the final file).
    points : int
        Grid points.
    seconds : float
        Wall time of :meth:`Sweep.run`.
    task_seconds : float
        Sum of the tasks' own compute times (CPU-bound: ≈ core-seconds).
    max_rss_mib : float
        Largest peak resident memory of any process that computed a task.
    metric_seconds : dict
        Compute time per point function (``steady``: the steady solves, failed ones
        included), summed over the tasks computed in this run.
    backend : str
        ``"serial"``, ``"processes"`` or ``"dask"``.
    workers : int
        Worker processes (or Dask threads in total).
    """

    tasks: int = 0
    computed: int = 0
    reused: int = 0
    points: int = 0
    seconds: float = 0.0
    task_seconds: float = 0.0
    max_rss_mib: float = 0.0
    backend: str = ""
    workers: int = 0
    point_seconds: list = field(default_factory=list, repr=False)
    metric_seconds: dict = field(default_factory=dict)


ProgressFn = Callable[..., None]


class Sweep:
    """A sweep of ``config``, optionally persisted to ``out`` (NetCDF) with resume.

    Parameters
    ----------
    config : SweepConfig
        What to compute.
    out : path, optional
        Final NetCDF file. Finished tasks are kept in ``<out>.parts/`` until assembly.
        Without it, nothing is written and nothing can be resumed.
    fresh : bool
        Discard saved results of a *different* configuration (parts or final file) instead
        of refusing with :class:`~chuteflow.sweep.store.ConfigMismatchError`. Results of
        the same configuration are always reused.
    keep_parts : bool
        Keep ``<out>.parts/`` after the final file is written.
    """

    def __init__(self, config: SweepConfig, out=None, *, fresh: bool = False, keep_parts: bool = False):
        if not isinstance(config, SweepConfig):
            raise ParameterError("config: expected a chuteflow.sweep.SweepConfig")
        self.config = config
        self.out = Path(out) if out is not None else None
        self.fresh = fresh
        self.keep_parts = keep_parts
        self.stats = SweepStats()
        #: The steady flows computed by the last :meth:`run` with ``keep_flows=True``, by
        #: grid index (i, j) (tasks reused from the store contribute none).
        self.flows: dict[tuple[int, int], SteadyFlow] = {}

    # ------------------------------------------------------------------ public
    def run(
        self,
        *,
        workers: int | None = None,
        client=None,
        scheduler: str | None = None,
        progress: bool | ProgressFn = False,
        keep_flows: bool = False,
    ):
        """Compute (or resume) the sweep and return the assembled :class:`xarray.Dataset`.

        Parameters
        ----------
        workers : int, optional
            Local worker processes (default: all cores). ``1`` runs in this process.
        client : dask.distributed.Client, optional
            Run the tasks on this Dask cluster instead.
        scheduler : str, optional
            Address of a Dask scheduler (``tcp://host:8786``); a client is opened and
            closed here. Needs the ``chuteflow[dask]`` extra.
        progress : bool or callable
            ``True``: a rich progress bar with ETA on stderr. A callable is called as
            ``progress(message, advance=n, total=N)`` (as a report stage's ``ctx.progress``).
        keep_flows : bool
            Keep the steady flows of the grid points computed in this run in
            :attr:`flows` (about 4 kB each; for follow-up computations at the same points,
            e.g. :func:`chuteflow.papers.mitarai2004.adaptive.refine_longwave`).
        """
        cfg = self.config
        self.flows = {}
        t0 = time.perf_counter()
        tasks = cfg.tasks()
        self.stats = st = SweepStats(tasks=len(tasks), points=cfg.npoints)
        if workers is not None and int(workers) < 1:
            raise ParameterError(f"workers = {workers!r}: need at least 1 worker process")
        if client is not None and scheduler is not None:
            raise ParameterError("scheduler: give either a Dask client or a scheduler address, not both")
        digest = cfg.digest()
        if self.out is not None:
            ds = self._existing_final(digest)
            if ds is not None:
                st.reused, st.seconds, st.backend = len(tasks), time.perf_counter() - t0, "none"
                return ds
        store = PartStore(self.out, cfg, fresh=self.fresh) if self.out is not None else None
        results: dict[str, TaskResult] = {}
        done = store.done() if store is not None else set()
        st.reused = sum(t.key in done for t in tasks)
        todo = [t for t in tasks if t.key not in done]

        def finished(res: TaskResult):
            self.flows.update(((res.i, j), flow) for j, flow in res.flows.items())
            res.flows = {}
            if store is not None:
                store.write(res)
            else:
                results[res.key] = res
            st.computed += 1
            st.task_seconds += res.seconds
            st.max_rss_mib = max(st.max_rss_mib, res.max_rss_kib / 1024.0)
            st.point_seconds.extend(res.point_seconds.tolist())
            for name, sec in res.metric_seconds.items():
                st.metric_seconds[name] = st.metric_seconds.get(name, 0.0) + sec
            bar.advance(res.j1 - res.j0)

        npts_done = sum(t.size for t in tasks if t.key in done)
        with _Progress(
            progress, total=cfg.npoints, completed=npts_done, label=f"sweep φ={cfg.model.roughness:g}"
        ) as bar:
            if todo:
                if client is not None or scheduler is not None:
                    self._run_dask(todo, finished, client, scheduler, keep_flows)
                else:
                    n = int(workers) if workers else (os.cpu_count() or 1)
                    n = max(1, min(n, len(todo)))
                    if n == 1:
                        st.backend, st.workers = "serial", 1
                        _run_serial(cfg, todo, finished, keep_flows)
                    else:
                        st.backend, st.workers = "processes", n
                        _run_pool(cfg, todo, finished, n, keep_flows)
        parts = [store.read(t.key) for t in tasks] if store is not None else [results[t.key] for t in tasks]
        ds = assemble(cfg, parts)
        if self.out is not None:
            write_dataset(ds, self.out)
            if not self.keep_parts and store is not None:  # a store exists when out is set
                store.remove()
        st.seconds = time.perf_counter() - t0
        return ds

    # ------------------------------------------------------------------ helpers
    def _existing_final(self, digest):
        assert self.out is not None  # called only when the sweep writes a file
        if not self.out.exists():
            return None
        try:
            ds = load_sweep(self.out)
            old = ds.attrs.get("config_digest")
        except Exception:  # unreadable: treated as foreign
            ds, old = None, None
        if old == digest:
            return ds
        if not self.fresh:
            raise ConfigMismatchError(
                f"out: {self.out} exists and holds a different sweep (digest "
                f"{str(old)[:12]}, this one {digest[:12]}); use another output file, or "
                "fresh=True (--fresh) to overwrite it"
            )
        return None

    def _run_dask(self, todo, finished, client, scheduler, keep_flows=False):
        with dask_client(client, scheduler) as client:
            from dask.distributed import as_completed  # there: dask_client has checked

            st = self.stats
            st.backend = "dask"
            st.workers = sum(client.nthreads().values())
            cfg = self.config
            prefix = f"chuteflow-{cfg.digest()[:10]}"
            futures = [
                client.submit(run_task, cfg, t, keep_flows=keep_flows, pure=False, key=f"{prefix}-{t.key}")
                for t in todo
            ]
            try:
                for fut in as_completed(futures):
                    finished(fut.result())
            except BaseException:
                client.cancel(futures)
                raise


@contextmanager
def dask_client(client=None, scheduler: str | None = None):
    """The Dask client to run on: ``client`` itself, or one connected to ``scheduler`` for the
    ``with`` block (closed after). One-line :class:`ParameterError` when dask.distributed is
    missing, both are given, or the scheduler cannot be reached."""
    if client is not None and scheduler is not None:
        raise ParameterError("scheduler: give either a Dask client or a scheduler address, not both")
    try:
        from dask.distributed import Client
    except ImportError:
        raise ParameterError(
            "scheduler: running on Dask needs dask.distributed, which is not installed; "
            "install the extra with pip install 'chuteflow[dask]'"
        ) from None
    if client is not None:
        yield client
        return
    try:
        own = Client(scheduler, timeout="20s")
    except OSError as exc:
        raise ParameterError(
            f"scheduler: cannot connect to the Dask scheduler at {scheduler!r}: {exc}"
        ) from None
    try:
        yield own
    finally:
        own.close()


def _run_serial(cfg, todo, finished, keep_flows=False):
    with limit_blas_threads(1, set_env=False):
        for t in todo:
            finished(run_task(cfg, t, limit_threads=False, keep_flows=keep_flows))


def _init_worker():
    limit_blas_threads(1)
    keep_freed_memory()
    # Ctrl-C reaches the whole process group: the parent handles it, workers just stop
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _run_pool(cfg, todo, finished, n, keep_flows=False):
    # fork inherits the compiled equations (≈1.5 s of sympy per process otherwise)
    if sys.platform.startswith("linux"):
        warm_up(cfg)
        ctx = mp.get_context("fork")
    else:
        ctx = mp.get_context("spawn")
    ex = ProcessPoolExecutor(max_workers=n, mp_context=ctx, initializer=_init_worker)
    try:
        pending = {ex.submit(run_task, cfg, t, keep_flows=keep_flows) for t in todo}
        # the workers are forked (without xarray): the Dataset's imports now, not after the
        # last task
        warm_xarray()
        while pending:
            done, pending = wait(pending, return_when=FIRST_COMPLETED)
            for fut in done:
                finished(fut.result())
    except BaseException:
        ex.shutdown(wait=False, cancel_futures=True)
        raise
    ex.shutdown(wait=True)


class _Progress:
    """A rich progress bar with ETA, a user callback, or nothing."""

    def __init__(self, progress, total, completed, label):
        self.spec, self.total, self.completed, self.label = progress, total, completed, label
        self._rich = None

    def __enter__(self):
        if self.spec is True:
            from rich.progress import (
                BarColumn,
                MofNCompleteColumn,
                Progress,
                TextColumn,
                TimeElapsedColumn,
                TimeRemainingColumn,
            )

            self._rich = Progress(
                TextColumn("{task.description}"),
                BarColumn(),
                MofNCompleteColumn(),
                TextColumn("points"),
                TimeElapsedColumn(),
                TextColumn("ETA"),
                TimeRemainingColumn(),
                transient=False,
            )
            self._rich.start()
            self._task = self._rich.add_task(self.label, total=self.total, completed=self.completed)
        elif callable(self.spec):
            self.spec(self.label, total=self.total, completed=self.completed)
        return self

    def advance(self, n):
        if self._rich is not None:
            self._rich.advance(self._task, n)
        elif callable(self.spec):
            self.spec(advance=n)

    def __exit__(self, *exc):
        if self._rich is not None:
            self._rich.stop()
        return False


# ---------------------------------------------------------------------- Dataset
def assemble(config: SweepConfig, parts: list[TaskResult]):
    """Build the Dataset (coords theta, nu0) from the task results, and classify it."""
    import xarray as xr

    nt, nn = config.shape
    variables = config.variables()
    data = {v.name: np.full((nt, nn), v.missing, dtype=v.dtype) for v in variables}
    status = np.full((nt, nn), -1, dtype=np.int8)
    message = np.full((nt, nn), "", dtype=object)
    nm = len(config.markers)
    mdata = {v.name: np.full(nm, v.missing, dtype=v.dtype) for v in variables}
    mstatus = np.full(nm, -1, dtype=np.int8)
    mmessage = np.full(nm, "", dtype=object)
    for p in parts:
        if p.i < 0:
            for v in variables:
                mdata[v.name][p.j0 : p.j1] = p.values[v.name]
            mstatus[p.j0 : p.j1] = p.status
            mmessage[p.j0 : p.j1] = [str(s) for s in p.message]
            continue
        for v in variables:
            data[v.name][p.i, p.j0 : p.j1] = p.values[v.name]
        status[p.i, p.j0 : p.j1] = p.status
        message[p.i, p.j0 : p.j1] = [str(s) for s in p.message]
    if (status < 0).any() or (mstatus < 0).any():
        raise RuntimeError("assemble: some points have no result")
    dims = ("theta", "nu0")
    ds = xr.Dataset(
        {v.name: (dims, data[v.name], v.attrs()) for v in variables},
        coords={
            "theta": ("theta", np.array(config.theta), {"units": "degree", "long_name": "inclination θ"}),
            "nu0": ("nu0", np.array(config.nu0), {"units": "1", "long_name": "floor packing fraction ν0(0)"}),
        },
    )
    names = " ".join(STATUS)
    ds["status"] = (
        dims,
        status,
        {
            "long_name": "point status",
            "flag_values": np.array(list(STATUS.values()), np.int8),
            "flag_meanings": names,
        },
    )
    ds["message"] = (dims, message.astype(str), {"long_name": "why a point is not ok"})
    if nm:
        # marked points (paper's P1–P5, Q1–Q3): same variables on a 'marker' dimension
        ds = ds.assign_coords(
            marker=(
                "marker",
                np.array([m[0] for m in config.markers], dtype=str),
                {"long_name": "marked point"},
            ),
            marker_theta=(
                "marker",
                np.array([m[1] for m in config.markers]),
                {"units": "degree", "long_name": "inclination θ of the marked point"},
            ),
            marker_nu0=(
                "marker",
                np.array([m[2] for m in config.markers]),
                {"units": "1", "long_name": "ν0(0) of the marked point"},
            ),
        )
        for v in variables:
            ds["marker_" + v.name] = ("marker", mdata[v.name], v.attrs())
        ds["marker_status"] = ("marker", mstatus, dict(ds["status"].attrs))
        ds["marker_message"] = ("marker", mmessage.astype(str), dict(ds["message"].attrs))
    d = config.to_dict()
    ds.attrs.update(
        {
            "title": f"chuteflow stability sweep, roughness φ = {config.model.roughness:g}",
            "source": "chuteflow (Mitarai & Nakanishi, figures 6 / 12)",
            "chuteflow_version": __version__,
            "config_digest": config.digest(),
            "config_json": json.dumps(d, sort_keys=True),
            "metrics": " ".join(json.loads(s)["name"] for s in config.metrics),
        }
    )
    ds.attrs.update(config.model.attrs())  # parameters and closure names (ChuteModel.to_dict)
    ds.attrs["model_key"] = config.model.key()
    for k in ("nu_top", "steady_rtol", "n_max", "min_thickness"):
        ds.attrs[k] = d[k]
    ds.attrs["chunk"] = config.chunk or len(config.nu0)
    return classify(ds)


def write_dataset(ds, path) -> Path:
    """Write ``ds`` to NetCDF (h5netcdf) atomically: a temporary file, then ``os.replace``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with atomic_target(path) as tmp:
        ds.to_netcdf(tmp, engine="h5netcdf", invalid_netcdf=False)
    return path


def load_sweep(path):
    """Load a sweep Dataset written by :func:`run_sweep` (fully into memory).

    ``SweepConfig.from_dataset(ds)`` gives its configuration back and
    ``SweepConfig.from_dataset(ds).model`` the :class:`~chuteflow.closures.ChuteModel`
    (with its closures) it was computed with.
    """
    import xarray as xr

    path = Path(path)
    if not path.exists():
        raise ParameterError(f"file: {path} does not exist")
    with xr.open_dataset(path, engine="h5netcdf") as ds:
        ds = ds.load()
    if "config_digest" not in ds.attrs or "status" not in ds:
        raise ParameterError(f"file: {path} is not a chuteflow sweep (no config_digest/status)")
    return ds


def markers(ds):
    """The marked points of a sweep Dataset as their own Dataset (dimension ``marker``)."""
    names = [v for v in ds.data_vars if v.startswith("marker_")]
    out = ds[names].rename({v: v[len("marker_") :] for v in names})
    return out.drop_vars(
        [c for c in ds.coords if c not in ("marker", "marker_theta", "marker_nu0")], errors="ignore"
    )


def run_sweep(
    config: SweepConfig,
    out=None,
    *,
    workers: int | None = None,
    client=None,
    scheduler: str | None = None,
    progress: bool | ProgressFn = False,
    fresh: bool = False,
    keep_parts: bool = False,
):
    """Run (or resume) a sweep; see :class:`Sweep`. Returns the Dataset."""
    return Sweep(config, out, fresh=fresh, keep_parts=keep_parts).run(
        workers=workers, client=client, scheduler=scheduler, progress=progress
    )


__all__ += ["ConfigMismatchError"]

"""Parameter sweeps over (θ, ν0(0)) and stability diagrams in the (h, ν̄) plane (§4.2).

- :class:`SweepConfig`: the grid, closures, resolution and point functions (hashed).
- :func:`run_sweep` / :class:`Sweep`: run on local processes or Dask, persist each finished
  task, resume after an interruption, return an :class:`xarray.Dataset`.
- :class:`PointFunction`, :class:`Variable`, :func:`register_point_function`: per-point
  computations (steady quantities, kinematic-wave speeds, long-wave coefficients, k_c, growth).
- :func:`classify`: unstable points, regimes A, B, C, and the finite-k cross-check.
- ``ds.chute`` (:class:`ChuteAccessor`): the same operations as Dataset methods, and
  ``ds.chute.model``, the model a Dataset was computed with.
"""

from .._imports import when_imported
from . import metrics  # noqa: F401  (registers the built-in stability metrics)
from .config import DEFAULT_RANGES, SweepConfig, Task, default_ranges, parse_grid, resolve_model
from .engine import Sweep, SweepStats, assemble, load_sweep, markers, run_sweep, write_dataset
from .points import (
    Point,
    PointFunction,
    Variable,
    point_function,
    register_point_function,
    registered_point_functions,
)
from .regimes import classify
from .runner import STATUS, TaskResult, run_task
from .store import ConfigMismatchError, PartStore, parts_dir


def _register_accessor() -> None:
    from . import accessor  # noqa: F401  (registers ds.chute)


# ``ds.chute`` is registered as soon as xarray is imported (now, if it already is), and not
# earlier: xarray and pandas add ~44 MiB to every process, sweep workers included
when_imported("xarray", _register_accessor)


def __getattr__(name: str):
    if name == "ChuteAccessor":
        from .accessor import ChuteAccessor

        return ChuteAccessor
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = [
    "SweepConfig",
    "Task",
    "DEFAULT_RANGES",
    "markers",
    "default_ranges",
    "parse_grid",
    "resolve_model",
    "Sweep",
    "SweepStats",
    "run_sweep",
    "assemble",
    "load_sweep",
    "write_dataset",
    "Point",
    "PointFunction",
    "Variable",
    "point_function",
    "register_point_function",
    "registered_point_functions",
    "STATUS",
    "TaskResult",
    "run_task",
    "ConfigMismatchError",
    "PartStore",
    "parts_dir",
    "classify",
    "ChuteAccessor",
]

"""Run code once a third-party module is imported, without importing it (a post-import hook).

:mod:`chuteflow.sweep` registers its ``ds.chute`` accessor on xarray's Dataset. Importing
xarray (and pandas) costs ~44 MiB of resident memory, which every sweep worker forked from
the parent inherits, although workers never build a Dataset. So the registration waits
until xarray is imported by anyone (:func:`when_imported`), and a sweep whose parent has not
imported xarray yet forks lean workers.
"""

from __future__ import annotations

import importlib.abc
import importlib.util
import sys
from collections.abc import Callable

__all__ = ["when_imported", "warm_xarray"]


class _AfterImport(importlib.abc.MetaPathFinder):
    """A one-shot finder that wraps the loader of one top-level module."""

    def __init__(self, name: str, callback: Callable[[], None]):
        self.name, self.callback = name, callback

    def find_spec(self, fullname, path=None, target=None):
        if fullname != self.name:
            return None
        sys.meta_path.remove(self)  # one shot; the other finders find the real spec
        spec = importlib.util.find_spec(fullname)
        loader = None if spec is None else spec.loader
        if loader is None or not hasattr(loader, "exec_module"):
            return spec
        exec_module, callback = loader.exec_module, self.callback

        def exec_then_call(module):
            exec_module(module)
            callback()

        loader.exec_module = exec_then_call  # type: ignore[method-assign]  # this spec's loader only
        return spec


def when_imported(name: str, callback: Callable[[], None]) -> None:
    """Call ``callback()`` right after the top-level module ``name`` is imported (at once if
    it already is)."""
    if name in sys.modules:
        callback()
    else:
        sys.meta_path.insert(0, _AfterImport(name, callback))


def warm_xarray() -> None:
    """Import xarray and build one tiny Dataset, so that the next Dataset is cheap.

    Importing xarray costs ~0.3 s, and its first Dataset as much again: that is when xarray
    looks for chunked-array libraries and imports dask's array modules if dask is installed
    (~350 modules). A parent process whose workers are busy (a steady map, a sweep) does both
    while it waits, instead of after the last result, when they would add to the wall time.
    Call it only after the workers are forked (they need no xarray, see the module docstring).
    """
    import numpy as np
    import xarray as xr

    xr.Dataset({"warm": (("x",), np.zeros(1))}, coords={"x": ("x", np.zeros(1))})

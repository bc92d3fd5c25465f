"""``ds.chute`` methods that need the reduced 1D model (added to :class:`ChuteAccessor`)."""

from __future__ import annotations

from typing import Any

import xarray as xr

from ..sweep.accessor import ChuteAccessor
from .diagram import agreement

__all__ = ["chute_agreement"]


@ChuteAccessor.method("agreement")
def chute_agreement(self: ChuteAccessor, full: xr.Dataset, **kw: Any) -> dict:
    """``reduced_ds.chute.agreement(full_ds, ...)``: :func:`chuteflow.reduced.agreement` of
    this 1D diagram with the full model's (the fraction of points classified alike)."""
    return agreement(self._ds, full, **kw)

"""The ``ds.chute`` accessor: dataset-level operations of chuteflow as methods.

Importing :mod:`chuteflow.sweep` registers it on every :class:`xarray.Dataset`::

    ds = chuteflow.sweep.load_sweep("diagram_phi0.05.nc")
    ds.chute.model              # the ChuteModel the sweep was computed with
    ds = ds.chute.classify()    # unstable, regime, finite-k cross-check
    ds.chute.regime_summary()   # per regime: points, median h and ν̄, …
    ds.chute.markers()          # the marked points as their own Dataset

The accessor has the same methods whatever else is imported: those of :mod:`chuteflow.sweep`
and below (operations of higher layers are their functions, e.g.
:func:`chuteflow.reduced.agreement`). The free functions (:func:`~chuteflow.sweep.classify`,
:func:`~chuteflow.sweep.markers`, …) stay and do the same.

It is registered when xarray is imported (at once if it already is): a sweep's forked
workers never build a Dataset, and a parent that has not imported xarray forks them without
its ~44 MiB (measured: 60 × 60 diagram, worker peak 329 → 277 MiB; ``chuteflow._imports``).
"""

from __future__ import annotations

import json

import xarray as xr

from ..closures import FIELDS as MODEL_FIELDS
from ..closures import ChuteModel
from ..errors import ParameterError
from .config import SweepConfig
from .engine import markers
from .regimes import classify, regime_summary

__all__ = ["ChuteAccessor", "MODEL_ATTRS"]

#: Dataset attributes that may hold the model as JSON (``ChuteModel.to_dict()``), in order.
MODEL_ATTRS: tuple[str, ...] = ("model", "model_json", "chute_model")
#: The closure parameters older datasets carry as separate attributes.
_MODEL_FIELDS: tuple[str, ...] = ("roughness", "wall_loss", "restitution", "nu_max")


@xr.register_dataset_accessor("chute")
class ChuteAccessor:
    """chuteflow's operations on a Dataset it produced (sweeps, diagrams, dispersion data)."""

    def __init__(self, ds: xr.Dataset) -> None:
        self._ds = ds

    # ------------------------------------------------------------------ metadata
    @property
    def config(self) -> SweepConfig | None:
        """The :class:`SweepConfig` of a sweep Dataset (``None`` for other Datasets)."""
        text = self._ds.attrs.get("config_json")
        return SweepConfig.from_dict(json.loads(text)) if text else None

    @property
    def model(self) -> ChuteModel:
        """The :class:`~chuteflow.closures.ChuteModel` the Dataset was computed with.

        Read from the model's JSON attribute (:data:`MODEL_ATTRS`), else from the sweep
        configuration, else from the closure parameters stored as attributes;
        :class:`~chuteflow.errors.ParameterError` if none is there.
        """
        a = self._ds.attrs
        for key in MODEL_ATTRS:
            if key in a:
                d = json.loads(a[key]) if isinstance(a[key], str) else dict(a[key])
                return ChuteModel.from_dict(d)
        cfg = self.config
        if cfg is not None:
            return cfg.model
        if all(k in a for k in _MODEL_FIELDS):
            # the attributes written by ChuteModel.attrs(): the parameters and the closures
            return ChuteModel.from_dict({k: a[k] for k in MODEL_FIELDS if k in a})
        raise ParameterError(
            "dataset: no model in its attributes (expected one of "
            f"{', '.join(MODEL_ATTRS)}, a sweep's config_json, or "
            f"{', '.join(_MODEL_FIELDS)})"
        )

    # ------------------------------------------------------------------ sweep operations
    def classify(self) -> xr.Dataset:
        """:func:`chuteflow.sweep.classify`: a copy with ``unstable``, ``regime`` and the
        finite-k cross-check (if the metrics allow)."""
        return classify(self._ds)

    def regime_summary(self) -> dict:
        """:func:`chuteflow.sweep.regimes.regime_summary` of the classified Dataset."""
        return regime_summary(self._ds)

    def markers(self) -> xr.Dataset:
        """:func:`chuteflow.sweep.markers`: the marked points as their own Dataset."""
        return markers(self._ds)

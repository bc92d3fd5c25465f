"""What a sweep computes: the (θ, ν0(0)) grid, the model, resolution, point functions, tasks.

:class:`SweepConfig` is frozen and hashable; it holds a :class:`~chuteflow.closures.ChuteModel`
(parameters and every closure choice), the one source of the model for the whole sweep.
:meth:`SweepConfig.digest` (SHA-256 of its canonical JSON, with the model's
:meth:`~chuteflow.closures.ChuteModel.to_dict`, the chuteflow version and every point
function's version) names the results, so saved partial results are reused only by the very
same configuration.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._version import __version__
from ..closures import FIELDS as MODEL_FIELDS
from ..closures import ChuteModel
from ..errors import ParameterError
from .metrics import default_metrics
from .points import point_function

__all__ = [
    "DEFAULT_RANGES",
    "SweepConfig",
    "Task",
    "default_ranges",
    "parse_grid",
    "resolve_model",
]

#: (θ range in degrees, ν0(0) range) covering the paper's stability diagrams, where steady
#: flows exist (found by scanning with chuteflow.steady; beyond them no steady flow exists
#: or the steady solver does not converge). Figures 6 and 12.
DEFAULT_RANGES: dict[float, tuple[tuple[float, float], tuple[float, float]]] = {
    0.05: ((12.0, 18.0), (0.01, 0.25)),
    0.10: ((16.5, 22.5), (0.01, 0.30)),
}


def default_ranges(roughness: float) -> tuple[tuple[float, float], tuple[float, float]]:
    """Default (θ range, ν0 range) for a roughness: the paper's two cases, else a wide guess.

    For other roughness values the θ window is centred by linear interpolation between the
    paper's two cases (the window moves up by ~4.5° when φ doubles); check the ``status``
    map of the result and adjust ``theta_range``.
    """
    r = float(roughness)
    for key, val in DEFAULT_RANGES.items():
        if math.isclose(r, key, rel_tol=1e-9):
            return val
    (a0, a1), _ = DEFAULT_RANGES[0.05]
    (b0, b1), _ = DEFAULT_RANGES[0.10]
    s = (r - 0.05) / 0.05
    lo = max(1.0, a0 + s * (b0 - a0))
    hi = max(lo + 2.0, a1 + s * (b1 - a1))
    return (round(lo, 2), round(hi, 2)), (0.01, 0.30)


def parse_grid(text: str) -> tuple[int, int]:
    """``"60x60"`` → (n_theta, n_nu0)."""
    try:
        a, b = str(text).lower().replace("×", "x").split("x")
        nt, nn = int(a), int(b)
    except ValueError:
        raise ParameterError(f"grid = {text!r}: write it as N_THETAxN_NU0, e.g. 60x60") from None
    if nt < 1 or nn < 1:
        raise ParameterError(f"grid = {text!r}: both sizes must be at least 1")
    return nt, nn


@dataclass(frozen=True)
class Task:
    """A unit of work: one θ row, points ``j0 ≤ j < j1`` along ν0 (continuation inside).

    ``i = -1`` is the task of the marked points (``markers[j0:j1]``, each from a cold start).
    """

    index: int
    i: int
    j0: int
    j1: int

    @property
    def key(self) -> str:
        if self.i < 0:
            return f"markers_{self.j0:05d}-{self.j1:05d}"
        return f"t{self.i:05d}_{self.j0:05d}-{self.j1:05d}"

    @property
    def size(self) -> int:
        return self.j1 - self.j0


def resolve_model(model: ChuteModel | None = None, **fields: Any) -> ChuteModel:
    """``model`` (default: the paper's :class:`~chuteflow.closures.ChuteModel`) with the
    given model fields (``roughness=``, ``radial=`` …) replacing its own."""
    unknown = sorted(set(fields) - set(MODEL_FIELDS))
    if unknown:
        raise ParameterError(f"unknown parameters {unknown}: the model's are {list(MODEL_FIELDS)}")
    if model is None:
        model = ChuteModel()
    elif isinstance(model, Mapping):
        model = ChuteModel.from_dict(model)
    elif not isinstance(model, ChuteModel):
        raise ParameterError(f"model: expected a ChuteModel, got {type(model).__name__}")
    given = {k: v for k, v in fields.items() if v is not None}
    return dataclasses.replace(model, **given) if given else model


@dataclass(frozen=True, init=False)
class SweepConfig:
    """A sweep over the (θ, ν0(0)) grid.

    Parameters
    ----------
    theta : sequence of float
        Inclinations θ in degrees (strictly increasing).
    nu0 : sequence of float
        Floor packing fractions ν0(0) (strictly increasing).
    model : ChuteModel, optional
        Parameters and closures (default: the paper's, ``ChuteModel()``). A dict of
        :meth:`~chuteflow.closures.ChuteModel.to_dict` is accepted too.
    metrics : sequence
        Point functions by name, ``{"name", "options"}`` dict or instance; default: the
        steady quantities, kinematic-wave speeds and the stability metrics
        (:func:`chuteflow.sweep.metrics.default_metrics`).
    nu_top, steady_rtol, n_max, min_thickness :
        Passed to :func:`~chuteflow.steady.solve_steady`. ``min_thickness`` defaults to 0:
        the diagrams show h < 1 (hatched, paper figure 6: "not examined").
    chunk : int, optional
        Points per task along ν0 (default: the whole θ row). The steady flows of a task are
        one :func:`~chuteflow.steady.steady_family` (continuation in ν0), so results depend on
        the chunking at round-off level: it is part of the hash and independent of the
        number of workers.
    markers : sequence of (name, theta, nu0)
        Extra points computed with the same point functions and stored on a ``marker``
        dimension (e.g. the paper's P1–P5, Q1–Q3: ``chuteflow.papers.mitarai2004.markers``).
    **model_fields
        Convenience: fields of :class:`~chuteflow.closures.ChuteModel` (``roughness``,
        ``wall_loss``, ``restitution``, ``nu_max``, ``radial``, ``wall``, ``transport``)
        replacing those of ``model``. The resulting :attr:`model` is what the sweep uses,
        hashes and stores; ``config.roughness`` etc. read it.
    """

    theta: tuple[float, ...]
    nu0: tuple[float, ...]
    model: ChuteModel
    metrics: tuple
    nu_top: float
    steady_rtol: float
    n_max: int
    min_thickness: float
    chunk: int | None
    markers: tuple

    def __init__(
        self,
        theta,
        nu0,
        model: ChuteModel | None = None,
        *,
        metrics=None,
        nu_top: float = 1e-9,
        steady_rtol: float = 1e-8,
        n_max: int = 384,
        min_thickness: float = 0.0,
        chunk: int | None = None,
        markers=(),
        **model_fields,
    ):
        values = {
            "theta": theta,
            "nu0": nu0,
            "model": resolve_model(model, **model_fields),
            "metrics": metrics,
            "nu_top": nu_top,
            "steady_rtol": steady_rtol,
            "n_max": n_max,
            "min_thickness": min_thickness,
            "chunk": chunk,
            "markers": markers,
        }
        for name, value in values.items():
            object.__setattr__(self, name, value)
        self.__post_init__()

    def __post_init__(self):
        for name in ("theta", "nu0"):
            try:
                arr = np.asarray(getattr(self, name), dtype=float).ravel()
            except (TypeError, ValueError):
                raise ParameterError(f"{name}: must be a sequence of numbers") from None
            if arr.size == 0 or not np.isfinite(arr).all():
                raise ParameterError(f"{name}: need at least one finite value")
            if arr.size > 1 and not (np.diff(arr) > 0).all():
                raise ParameterError(f"{name}: values must be strictly increasing")
            object.__setattr__(self, name, tuple(float(x) for x in arr))
        if not (0.0 < self.theta[0] and self.theta[-1] < 90.0):
            raise ParameterError(
                f"theta: values must lie in (0, 90) degrees, got [{self.theta[0]:g}, {self.theta[-1]:g}]"
            )
        nu_max = self.model.nu_max
        if not (0.0 < self.nu0[0] and self.nu0[-1] < nu_max):
            raise ParameterError(
                f"nu0: values must lie in (0, nu_max = {nu_max:g}) "
                f"(floor packing fraction), got [{self.nu0[0]:g}, "
                f"{self.nu0[-1]:g}]"
            )
        if self.chunk is not None:
            if int(self.chunk) < 1:
                raise ParameterError(f"chunk = {self.chunk!r}: need at least 1 point per task")
            object.__setattr__(self, "chunk", int(self.chunk))
        marks = []
        for mk in self.markers:
            try:
                name, th, nu = mk
                name, th, nu = str(name), float(th), float(nu)
            except (TypeError, ValueError):
                raise ParameterError(f"markers: {mk!r} is not (name, theta, nu0)") from None
            if not (0 < th < 90 and 0 < nu < nu_max):
                raise ParameterError(
                    f"markers: {name} = ({th:g}°, {nu:g}) is outside theta in "
                    f"(0, 90) degrees, nu0 in (0, nu_max)"
                )
            marks.append((name, th, nu))
        if len({m[0] for m in marks}) != len(marks):
            raise ParameterError("markers: names must be unique")
        object.__setattr__(self, "markers", tuple(marks))
        object.__setattr__(self, "n_max", int(self.n_max))
        for name in ("nu_top", "steady_rtol", "min_thickness"):
            object.__setattr__(self, name, float(getattr(self, name)))
        if self.metrics is None:
            specs = default_metrics()
        else:
            # the canonical form stored by a configuration is JSON text (dataclasses.replace)
            specs = [json.loads(m) if isinstance(m, str) and m.startswith("{") else m for m in self.metrics]
        fns = [point_function(s) for s in specs]
        names = [f.name for f in fns]
        if len(set(names)) != len(names):
            raise ParameterError(f"metrics: duplicate point functions in {names}")
        seen = set()
        for f in fns:
            missing = [r for r in f.requires if r not in seen]
            if missing:
                raise ParameterError(f"metrics: {f.name!r} needs {missing} listed before it")
            seen.add(f.name)
        variables = [v.name for f in fns for v in f.variables]
        dup = {v for v in variables if variables.count(v) > 1}
        if dup:
            raise ParameterError(f"metrics: variables {sorted(dup)} are produced twice")
        object.__setattr__(self, "metrics", tuple(json.dumps(f.spec(), sort_keys=True) for f in fns))

    # ------------------------------------------------------------------ construction
    @classmethod
    def grid(
        cls,
        roughness: float | None = None,
        *,
        shape: tuple[int, int] = (60, 60),
        theta_range: tuple[float, float] | None = None,
        nu0_range: tuple[float, float] | None = None,
        model: ChuteModel | None = None,
        **kw,
    ) -> SweepConfig:
        """Uniform grid of ``shape = (n_theta, n_nu0)`` over the given (or default) ranges.

        The model is ``model`` with ``roughness`` (and any other model field in ``kw``)
        replacing its own; the default ranges and markers are those of its roughness.
        """
        model_kw = {k: kw.pop(k) for k in list(kw) if k in MODEL_FIELDS}
        model = resolve_model(model, roughness=roughness, **model_kw)
        roughness = model.roughness
        dt, dn = default_ranges(roughness)
        tr = tuple(theta_range) if theta_range is not None else dt
        nr = tuple(nu0_range) if nu0_range is not None else dn
        for name, r in (("theta_range", tr), ("nu0_range", nr)):
            if len(r) != 2 or not (float(r[0]) <= float(r[1])):
                raise ParameterError(f"{name} = {r!r}: need (low, high) with low <= high")
        nt, nn = (int(x) for x in shape)
        if nt < 1 or nn < 1:
            raise ParameterError(f"shape = {shape!r}: both sizes must be at least 1")
        if (nt > 1 and tr[0] == tr[1]) or (nn > 1 and nr[0] == nr[1]):
            raise ParameterError("a range with low == high allows one grid point only")
        th = np.linspace(float(tr[0]), float(tr[1]), nt)
        nu = np.linspace(float(nr[0]), float(nr[1]), nn)
        # round to 12 digits so that the same command line always gives the same hash
        return cls(theta=tuple(np.round(th, 12)), nu0=tuple(np.round(nu, 12)), model=model, **kw)

    # ------------------------------------------------------------------ derived
    @property
    def shape(self) -> tuple[int, int]:
        return len(self.theta), len(self.nu0)

    @property
    def size(self) -> int:
        return len(self.theta) * len(self.nu0)

    def point_functions(self) -> list:
        return [point_function(json.loads(s)) for s in self.metrics]

    def variables(self) -> list:
        return [v for f in self.point_functions() for v in f.variables]

    def tasks(self) -> list[Task]:
        """Tasks in a fixed order: θ rows, each cut into chunks of ``chunk`` points."""
        out: list[Task] = []
        nn = len(self.nu0)
        nchunks = math.ceil(nn / (self.chunk or nn))
        # equal-sized chunks (sizes differ by at most one)
        edges = [round(k * nn / nchunks) for k in range(nchunks + 1)]
        for i in range(len(self.theta)):
            for a, b in zip(edges[:-1], edges[1:]):
                out.append(Task(len(out), i, a, b))
        if self.markers:
            out.append(Task(len(out), -1, 0, len(self.markers)))
        return out

    @property
    def npoints(self) -> int:
        """Grid points plus marked points."""
        return self.size + len(self.markers)

    def to_dict(self) -> dict[str, Any]:
        """Canonical JSON-ready form (what is hashed, and stored in the Dataset attrs)."""
        return {
            "theta": list(self.theta),
            "nu0": list(self.nu0),
            "model": self.model.to_dict(),
            "metrics": [json.loads(s) for s in self.metrics],
            "nu_top": self.nu_top,
            "steady_rtol": self.steady_rtol,
            "n_max": self.n_max,
            "min_thickness": self.min_thickness,
            "chunk": self.chunk,
            "markers": [list(m) for m in self.markers],
            "chuteflow_version": __version__,
        }

    def digest(self) -> str:
        """SHA-256 (hex) of the canonical configuration."""
        text = json.dumps(self.to_dict(), sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()

    @classmethod
    def from_dict(cls, d: dict) -> SweepConfig:
        """The configuration of :meth:`to_dict` (also the flat model keys of older files)."""
        d = dict(d)
        d.pop("chuteflow_version", None)
        model = d.pop("model", None)
        flat = {k: d.pop(k) for k in list(d) if k in MODEL_FIELDS}
        model = ChuteModel.from_dict({**flat, **(model or {})})
        return cls(
            **{
                **d,
                "model": model,
                "theta": tuple(d["theta"]),
                "nu0": tuple(d["nu0"]),
                "metrics": tuple(d["metrics"]),
                "markers": tuple(tuple(m) for m in d.get("markers", ())),
            }
        )

    @classmethod
    def from_dataset(cls, ds) -> SweepConfig:
        """The configuration a sweep Dataset (or its NetCDF file, loaded) was computed with."""
        try:
            text = ds.attrs["config_json"]
        except KeyError:
            raise ParameterError("dataset: no config_json attribute (not a chuteflow sweep)") from None
        return cls.from_dict(json.loads(text))


def _model_property(name: str) -> property:
    def get(self):
        return getattr(self.model, name)

    get.__doc__ = f"``model.{name}`` (read-only)."
    return property(get)


for _name in MODEL_FIELDS:
    setattr(SweepConfig, _name, _model_property(_name))
del _name

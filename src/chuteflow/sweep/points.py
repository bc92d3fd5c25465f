"""Per-point computations of a sweep: small registered classes with declared outputs.

A sweep solves the steady flow at every (θ, ν0(0)) point (with continuation along ν0 inside a
task) and then hands it to each *point function* in turn. A point function is a subclass of
:class:`PointFunction` that declares its ``name``, a ``version`` (part of the configuration hash:
bump it when its numbers change) and its output :class:`Variable` s with units, and implements
``compute(flow, point) -> {variable: value}``. Register it with :func:`register_point_function`;
a new metric is a new small class and nothing else changes::

    @register_point_function
    class Froude(PointFunction):
        name = "froude"
        version = "1"
        variables = (Variable("Fr", "1", "Froude number u_floor / sqrt(h cos θ)"),)

        def compute(self, flow, point):
            return {"Fr": flow.u_floor / math.sqrt(flow.h * math.cos(math.radians(flow.theta)))}

Options given to the constructor (``FiniteKCheck(stride=3)``) are part of the configuration
and of its hash, so a sweep with other options never reuses old results.
"""

from __future__ import annotations

import importlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from ..errors import ParameterError
from ..steady import steady_tangent

__all__ = [
    "Variable",
    "Point",
    "PointFunction",
    "register_point_function",
    "point_function",
    "registered_point_functions",
    "SteadyQuantities",
    "Kinematic",
]

#: Variable kinds: 'float' (missing = NaN), 'flag' (int8: 1 true, 0 false, -1 missing),
#: 'int' (int32, missing = -1).
KINDS = ("float", "flag", "int")


@dataclass(frozen=True)
class Variable:
    """One output of a point function.

    Parameters
    ----------
    name : str
        Variable name in the Dataset.
    units : str
        Units (dimensionless groups: ``"1"``; lengths in particle diameters ``"sigma"``).
    long_name : str
        Description with the paper's symbol.
    kind : str
        ``"float"``, ``"flag"`` or ``"int"`` (see :data:`KINDS`).
    source : str
        Paper label or section defining it, if any.
    """

    name: str
    units: str
    long_name: str
    kind: str = "float"
    source: str = ""

    def __post_init__(self):
        if self.kind not in KINDS:
            raise ValueError(f"Variable {self.name!r}: kind {self.kind!r} not in {KINDS}")

    @property
    def missing(self):
        return {"float": np.nan, "flag": -1, "int": -1}[self.kind]

    @property
    def dtype(self):
        return {"float": np.float64, "flag": np.int8, "int": np.int32}[self.kind]

    def attrs(self) -> dict:
        a: dict[str, Any] = {"units": self.units, "long_name": self.long_name}
        if self.source:
            a["source"] = self.source
        if self.kind == "flag":
            a.update(flag_values=np.array([-1, 0, 1], dtype=np.int8), flag_meanings="missing false true")
        return a


@dataclass
class Point:
    """Where a point function is evaluated: grid indices, parameters, results so far.

    Attributes
    ----------
    i, j : int
        Indices along ``theta`` and ``nu0``.
    theta, nu0 : float
        Inclination (degrees) and floor packing fraction.
    values : dict
        Outputs of the point functions already evaluated at this point.
    notes : list of str
        Remarks added with :meth:`note`; they go to the point's ``message``.
    """

    i: int
    j: int
    theta: float
    nu0: float
    values: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)

    def note(self, text: str) -> None:
        """Add a remark to this point's message (e.g. why an optional value is missing)."""
        self.notes.append(str(text))


class PointFunction:
    """Base class of per-point computations (see the module docstring).

    Subclasses set the class attributes ``name``, ``version``, ``variables`` and optionally
    ``requires`` (names of point functions whose outputs they read from ``point.values``),
    and implement :meth:`compute`. Constructor keyword arguments are options; declare their
    defaults in ``defaults`` so that they can be validated and hashed.

    When a critical point function (the default) raises, the point's ``status`` becomes
    ``not_converged`` (a :class:`~chuteflow.errors.ConvergenceError`) or ``error`` and the
    later point functions are skipped. A point function with ``critical = False`` (a
    cross-check) only leaves its own variables missing and appends to ``message``.
    """

    name: ClassVar[str] = ""
    version: ClassVar[str] = "1"
    variables: ClassVar[tuple[Variable, ...]] = ()
    requires: ClassVar[tuple[str, ...]] = ()
    defaults: ClassVar[Mapping[str, Any]] = {}
    critical: ClassVar[bool] = True

    def __init__(self, **options):
        unknown = set(options) - set(self.defaults)
        if unknown:
            raise ParameterError(
                f"point function {self.name!r}: unknown option(s) "
                f"{sorted(unknown)}; allowed: {sorted(self.defaults)}"
            )
        self.options = {**self.defaults, **options}
        self.validate()

    def validate(self) -> None:
        """Check ``self.options``; raise :class:`ParameterError` naming the option."""

    def spec(self) -> dict:
        """JSON-ready description (name, version, options): what the configuration hashes."""
        return {
            "name": self.name,
            "version": str(self.version),
            "module": type(self).__module__,
            "options": {k: _plain(v) for k, v in sorted(self.options.items())},
        }

    def compute(self, flow, point: Point) -> Mapping[str, Any]:
        """Values of (some of) :attr:`variables` for the steady ``flow`` at ``point``.

        Variables left out stay missing (e.g. a check done on a sample of points only).
        Raise :class:`~chuteflow.errors.ConvergenceError` when a solver does not converge.
        """
        raise NotImplementedError

    def __repr__(self):
        opts = ", ".join(f"{k}={v!r}" for k, v in self.options.items())
        return f"{type(self).__name__}({opts})"


def _plain(v):
    if isinstance(v, (np.floating, np.integer)):
        return v.item()
    if isinstance(v, (list, tuple, np.ndarray)):
        return [_plain(x) for x in v]
    return v


_REGISTRY: dict[str, type[PointFunction]] = {}


def register_point_function(cls: type[PointFunction]) -> type[PointFunction]:
    """Class decorator: make ``cls`` available by its ``name`` (in configurations, the CLI)."""
    if not cls.name or not cls.name.isidentifier():
        raise ValueError(f"{cls.__name__}.name must be an identifier, got {cls.name!r}")
    old = _REGISTRY.get(cls.name)
    if old is not None and (old.__module__, old.__qualname__) != (cls.__module__, cls.__qualname__):
        raise ValueError(f"point function {cls.name!r} is already registered by {old.__module__}")
    names = [v.name for v in cls.variables]
    if len(set(names)) != len(names):
        raise ValueError(f"{cls.__name__}: duplicate variable names {names}")
    _REGISTRY[cls.name] = cls
    return cls


def registered_point_functions() -> dict[str, type[PointFunction]]:
    """Name → class of every registered point function (the built-in stability metrics of
    :mod:`chuteflow.sweep.metrics` register when :mod:`chuteflow.sweep` is imported)."""
    return dict(_REGISTRY)


def point_function(spec) -> PointFunction:
    """A point function from a name, a ``{"name", "options"}`` dict, or an instance."""
    if isinstance(spec, PointFunction):
        return spec
    name: Any  # from a mapping, anything: an unknown name raises below
    if isinstance(spec, str):
        name, options = spec, {}
    elif isinstance(spec, Mapping):
        name, options = spec.get("name"), dict(spec.get("options", {}))
        if name not in _REGISTRY and spec.get("module"):
            # a point function defined above this layer (e.g. chuteflow.reduced) registers
            # on import: a fresh worker (spawn, Dask) learns of it from the spec's module
            importlib.import_module(str(spec["module"]))
    else:
        raise ParameterError(f"metrics: cannot make a point function from {spec!r}")
    try:
        cls = _REGISTRY[name]
    except KeyError:
        raise ParameterError(
            f"metrics: unknown point function {name!r}; available: {sorted(_REGISTRY)}"
        ) from None
    return cls(**options)


# --------------------------------------------------------------------------- built-ins
@register_point_function
class SteadyQuantities(PointFunction):
    """Scalars of the steady flow (paper §3.2) and how converged they are."""

    name = "steady"
    # 2: the steady solver's grid is sinh-mapped at the layer's edge (more points converge)
    version = "2"
    variables = (
        Variable("h", "sigma", "thickness h (ν0 at 1 % of its maximum)", source="§3.2"),
        Variable("nu_mean", "1", "mean density ν̄ = ρ̄0 / h", source="§3.2"),
        Variable("rho_bar", "sigma", "one-dimensional density ρ̄0 = ∫ν0 dy", source="eq. (3.15)"),
        Variable("Q", "sigma^(3/2) g^(1/2)", "flux Q0 = ∫ν0 u0 dy", source="eq. (3.15)"),
        Variable("U", "sqrt(g sigma)", "mean velocity U = Q0 / ρ̄0"),
        Variable("T_mean", "g sigma", "density-weighted temperature T̄0", source="§5.1.2"),
        Variable("u_floor", "sqrt(g sigma)", "slip velocity u0(0)"),
        Variable("T_floor", "g sigma", "floor temperature T0(0)"),
        Variable("y_max", "sigma", "top of the domain, ν0(y_max) = nu_top"),
        Variable(
            "monotonic", "1", "ν0 decreases monotonically from the floor", kind="flag", source="figure 2"
        ),
        Variable("y_peak", "sigma", "height of the density maximum"),
        Variable("nu_peak", "1", "density maximum"),
        Variable("steady_n", "1", "Chebyshev intervals of the steady solution", kind="int"),
        Variable(
            "steady_convergence", "1", "largest relative change of the steady scalars between resolutions"
        ),
    )

    def compute(self, flow, point):
        return {
            "h": flow.h,
            "nu_mean": flow.nu_mean,
            "rho_bar": flow.rho_bar,
            "Q": flow.Q,
            "U": flow.Q / flow.rho_bar,
            "T_mean": flow.T_mean,
            "u_floor": flow.u_floor,
            "T_floor": flow.T_floor,
            "y_max": flow.y_max,
            "monotonic": bool(flow.monotonic),
            "y_peak": flow.y_peak,
            "nu_peak": flow.nu_peak,
            "steady_n": int(flow.n),
            "steady_convergence": flow.convergence,
        }


@register_point_function
class Kinematic(PointFunction):
    """Kinematic-wave quantities along the family at fixed θ (§5.1.1, eq. (B 6)).

    dQ0/dρ̄0 from the exact family tangent of the steady solver; dU/dρ̄0 with U = Q0/ρ̄0
    decides whether the denser flow is faster (> 0, regimes A and C) or slower (< 0,
    regime B), §4.2.
    """

    name = "kinematic"
    version = "1"
    requires = ("steady",)
    variables = (
        Variable("dQ_drho", "sqrt(g sigma)", "dQ0/dρ̄0 at fixed θ (kinematic wave speed)", source="eq. (B 6)"),
        Variable("dU_drho", "sqrt(g sigma)/sigma", "dU/dρ̄0 at fixed θ, U = Q0/ρ̄0", source="§4.2"),
        Variable("drho_dnu0", "sigma", "dρ̄0/dν0(0) at fixed θ"),
    )

    def compute(self, flow, point):

        t = steady_tangent(flow)
        dq = float(t["dQ_drho"])
        U = flow.Q / flow.rho_bar
        return {"dQ_drho": dq, "dU_drho": (dq - U) / flow.rho_bar, "drho_dnu0": float(t["drho_bar"])}

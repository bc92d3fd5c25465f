"""The steady-flow result object and its derived quantities (paper §3.2)."""

from __future__ import annotations

import ctypes
import functools
import math
import weakref
from dataclasses import dataclass, field, fields

import numpy as np

from ..closures import ChuteModel
from ..closures.model import FUNCTIONS
from ..spectral import ChebyshevGrid, MappedChebyshevGrid, coefficients, tail
from ._roots import brent_root


@functools.lru_cache(maxsize=8)
def _flow_grid(n: int, y_max: float, grid_map: tuple[float, float] | None) -> ChebyshevGrid:
    """:attr:`SteadyFlow.grid`: built once for the last few flows asked (its D2 is O(n³), and
    every operator, derivative and interpolation of a flow uses it; a sweep asks for one
    flow's grid at a time), without a flow keeping it (3 MB at N = 432). Its arrays are
    shared: read them, do not change them."""
    return steady_grid(n, y_max, grid_map)


def cached_per_flow(func):
    """Decorator: ``func(flow)`` computed once while the flow lives (weak keys: the cache
    never keeps a flow alive; flows equal in value share the entry)."""
    memo: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()

    @functools.wraps(func)
    def wrapper(flow):
        out = memo.get(flow)
        if out is None:
            out = memo[flow] = func(flow)
        return out

    return wrapper


def steady_grid(n: int, y_max: float, grid_map: tuple[float, float] | None = None) -> ChebyshevGrid:
    """The collocation grid of a steady flow: n + 1 Chebyshev–Lobatto nodes of [0, y_max],
    either linear in the computational variable (``grid_map`` None) or clustered by the sinh
    map of :class:`~chuteflow.spectral.MappedChebyshevGrid` around the layer's edge.

    ``grid_map`` = (ξ_c, ξ_w) gives the map's centre and width as fractions of y_max, so that
    the nodes sit at fixed ξ = y/y_max while y_max is an unknown of Newton (the free top)."""
    if grid_map is None:
        return ChebyshevGrid(n, 0.0, y_max)
    xc, xw = grid_map
    return MappedChebyshevGrid(n, 0.0, y_max, xc * y_max, xw * y_max)


@dataclass(frozen=True, eq=False)
class SteadyFlow:
    """A steady flow uniform along the slope, ν0(y), u0(y), T0(y) on Chebyshev nodes.

    Two flows are equal when all their fields are (arrays element by element, NaN equal to
    NaN); the hash uses the fields that identify the flow, (θ, ν0(0), model, ν_top, N), so
    flows can be keys of dicts and caches.

    Attributes
    ----------
    theta, nu0 : float
        Inclination (degrees) and floor packing fraction ν0(0) that label the flow.
    model : ChuteModel
        Parameters and closures the flow was computed with.
    y, nu, u, T : ndarray
        Chebyshev–Lobatto nodes on [0, y_max] (ascending, see ``grid_map``) and the profiles
        there.
    y_max : float
        Top of the domain, where ν0(y_max) = ``nu_top``.
    u_floor, T_floor : float
        Slip velocity u0(0) and floor temperature T0(0).
    h : float
        Thickness: height where ν0 falls to 1 % of its maximum.
    nu_mean : float
        Mean density ν̄ = (1/h) ∫ ν0 dy.
    rho_bar : float
        One-dimensional density ρ̄0 = ∫ ν0 dy (eq. (3.15)).
    Q : float
        Flux Q0 = ∫ ν0 u0 dy (eq. (3.15)).
    T_mean : float
        Density-weighted temperature T̄0 = ∫ ν0 T0 dy / ρ̄0 (§5.1.2).
    monotonic : bool
        Whether ν0 decreases monotonically from the floor.
    y_peak, nu_peak : float
        Height and value of the density maximum (0 and ν0(0) when monotonic).
    residual : float
        Max-norm of the scaled discrete residual at the solution.
    convergence : float
        Largest relative change of (u_floor, T_floor, h, nu_mean, rho_bar, Q, y_max) between
        this resolution and a coarser one: an estimate of the discretisation error.
    spectral_tail : float
        Largest of the ten highest Chebyshev coefficients of ln ν0, u0, T0 (relative).
    grid_map : tuple of float or None
        (ξ_c, ξ_w): the nodes are clustered by a sinh map around y = ξ_c y_max with width
        ξ_w y_max (:func:`steady_grid`; the layer's edge, where the dense layer meets the
        cold dilute top); None: plain Chebyshev nodes. :attr:`grid` is the grid either way.
    converged : bool
        False where the resolution ladder ended (at ``n_max``, or at Newton's round-off
        floor) before the change between two resolutions fell to the requested ``rtol``;
        ``convergence`` is then the estimate of the error. Only
        :func:`~chuteflow.steady.solve_steady` with ``strict=False`` returns such a flow.
    """

    theta: float
    nu0: float
    model: ChuteModel
    nu_top: float
    n: int
    y: np.ndarray = field(repr=False)
    log_nu: np.ndarray = field(repr=False)
    u: np.ndarray = field(repr=False)
    T: np.ndarray = field(repr=False)
    y_max: float = 0.0
    u_floor: float = 0.0
    T_floor: float = 0.0
    h: float = 0.0
    nu_mean: float = 0.0
    rho_bar: float = 0.0
    Q: float = 0.0
    T_mean: float = 0.0
    monotonic: bool = True
    y_peak: float = 0.0
    nu_peak: float = 0.0
    residual: float = 0.0
    iterations: int = 0
    convergence: float = float("nan")
    spectral_tail: float = float("nan")
    grid_map: tuple[float, float] | None = None
    converged: bool = True

    def __eq__(self, other):
        if other is self:
            return True
        if type(other) is not type(self):
            return NotImplemented
        for f in fields(self):
            a, b = getattr(self, f.name), getattr(other, f.name)
            if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
                if not np.array_equal(a, b, equal_nan=True):
                    return False
            elif not (a == b or (_isnan(a) and _isnan(b))):
                return False
        return True

    def __hash__(self) -> int:
        return hash((self.theta, self.nu0, self.model, self.nu_top, self.n))

    @property
    def nu(self) -> np.ndarray:
        return np.exp(self.log_nu)

    @property
    def grid(self) -> ChebyshevGrid:
        """The collocation grid of the profiles (:func:`steady_grid`), shared by the flows
        asked for last (:func:`_flow_grid`)."""
        return _flow_grid(self.n, self.y_max, self.grid_map)

    def profiles(self, y) -> dict[str, np.ndarray]:
        """ν0, u0, T0 interpolated spectrally at heights ``y`` (0 ≤ y ≤ y_max)."""
        g = self.grid
        y = np.asarray(y, dtype=float)
        return {
            "nu": np.exp(g.interpolate(self.log_nu, y)),
            "u": g.interpolate(self.u, y),
            "T": g.interpolate(self.T, y),
        }

    def derivatives(self) -> dict[str, np.ndarray]:
        """First and second y-derivatives of ν0, u0, T0 at the nodes."""
        g = self.grid
        nu = self.nu
        s1, s2 = g.D @ self.log_nu, g.D2 @ self.log_nu
        return {
            "nu_y": nu * s1,
            "nu_yy": nu * (s2 + s1**2),
            "u_y": g.D @ self.u,
            "u_yy": g.D2 @ self.u,
            "T_y": g.D @ self.T,
            "T_yy": g.D2 @ self.T,
        }

    def to_dict(self) -> dict:
        """Scalar quantities as a JSON-ready dict (keys used by the CLI)."""
        d = {"theta": self.theta, "nu0": self.nu0}
        d.update(self.model.to_dict())
        for k in (
            "u_floor",
            "T_floor",
            "h",
            "nu_mean",
            "rho_bar",
            "Q",
            "T_mean",
            "monotonic",
            "y_peak",
            "nu_peak",
            "y_max",
            "nu_top",
            "n",
            "residual",
            "iterations",
            "convergence",
            "spectral_tail",
            "converged",
        ):
            v = getattr(self, k)
            d[k] = (
                bool(v)
                if isinstance(v, (bool, np.bool_))
                else (int(v) if isinstance(v, (int, np.integer)) else float(v))
            )
        return d

    @property
    def note(self) -> str:
        """One line saying how far from converged the flow is ('' when ``converged``): for
        results returned with ``strict=False`` (:func:`~chuteflow.steady.solve_steady`)."""
        if self.converged:
            return ""
        return (
            f"the steady flow at theta = {self.theta:g} deg, nu0 = {self.nu0:g} is not converged to "
            f"the requested tolerance: its quantities change by {self.convergence:.1e} (relative) "
            f"between the last two resolutions (n = {self.n}); results from it carry about that "
            "relative error"
        )

    def to_xarray(self):
        """Profiles as an :class:`xarray.Dataset` on the nodes, scalars as attributes."""
        import xarray as xr

        ds = xr.Dataset(
            {
                "nu": ("y", self.nu, {"long_name": "packing fraction ν0", "units": "1"}),
                "u": ("y", self.u, {"long_name": "velocity u0", "units": "sqrt(g sigma)"}),
                "T": ("y", self.T, {"long_name": "granular temperature T0", "units": "g sigma"}),
            },
            coords={"y": ("y", self.y, {"long_name": "height above the floor", "units": "sigma"})},
        )
        ds.attrs.update({k: (str(v) if isinstance(v, bool) else v) for k, v in self.to_dict().items()})
        ds.attrs.update(self.model.attrs())
        return ds


def _isnan(v) -> bool:
    return isinstance(v, (float, np.floating)) and math.isnan(v)


def _chebval1(c: list[float], x: float) -> float:
    """Chebyshev series ``c`` at one point ``x``: numpy's ``chebval`` (the same Clenshaw
    recurrence, operation for operation, hence the same float) on Python floats, which is
    ~20× faster for a scalar (the root finding in :func:`derived_quantities`)."""
    if len(c) == 1:
        return c[0]
    if len(c) == 2:
        return c[0] + c[1] * x
    x2 = 2 * x
    c0, c1 = c[-2], c[-1]
    for i in range(3, len(c) + 1):
        c0, c1 = c[-i] - c1, c0 + c1 * x2
    return c0 + c1 * x


#: :func:`_chebval1` in C: the same Clenshaw recurrence, operation for operation and without
#: contraction (``-ffp-contract=off``), hence the same float (tests/steady/test_ladder_cost.py).
_CHEBVAL_SOURCE = """
double cf_chebval1(const double *c, long len, double x) {
    if (len == 1) return c[0];
    if (len == 2) return c[0] + c[1] * x;
    double x2 = 2 * x;
    double c0 = c[len - 2], c1 = c[len - 1];
    for (long i = 3; i <= len; ++i) {
        double previous = c0;
        c0 = c[len - i] - c1;
        c1 = previous + c1 * x2;
    }
    return c0 + c1 * x;
}
"""


@functools.cache
def _chebval_kernel():
    """The compiled :func:`_chebval1` (a ctypes function), or None (no compiler, or
    ``CHUTEFLOW_CCODE=off``: the Python recurrence)."""
    from .._ccode import C_HEAD, cached_library

    lib = cached_library("chebval1", "v1", lambda: C_HEAD + _CHEBVAL_SOURCE, sources=(__name__,))
    if lib is None:
        return None
    f = lib.cf_chebval1
    f.argtypes = [ctypes.c_void_p, ctypes.c_long, ctypes.c_double]
    f.restype = ctypes.c_double
    return f


def _series(c: np.ndarray):
    """x ↦ the Chebyshev series ``c`` at one point x, as :func:`_chebval1` computes it: in C
    where compiled kernels are available (~1 µs a call instead of ~0.3 µs a coefficient:
    the root finding of :func:`derived_quantities`), else in Python."""
    kernel = _chebval_kernel()
    if kernel is None:
        coef = [float(v) for v in c]
        return lambda x: _chebval1(coef, x)
    arr = np.ascontiguousarray(c, dtype=float)
    ptr, size = arr.ctypes.data, len(arr)
    return lambda x, arr=arr: kernel(ptr, size, x)  # (arr kept alive with the function)


@functools.lru_cache(maxsize=4)
def fine_sampling(n: int) -> tuple[np.ndarray, np.ndarray]:
    """The fine sampling of :func:`derived_quantities` and of
    :func:`~chuteflow.steady.grid.layer_grid_map` for a series of degree n: the points
    x = linspace(−1, 1, 8n + 1) and the matrix of T_0 … T_n there (one product per series
    instead of a Clenshaw recurrence over n vector operations); cached, read-only. 12 MiB
    at n = 432: the last four degrees are kept (a ladder's two rungs and the next
    continuation step's: 5 MiB for n = 64 … 216; a rebuild costs ~0.8 ms at n = 96,
    ~4 ms at n = 432)."""
    xf = np.linspace(-1.0, 1.0, 8 * n + 1)
    V = np.polynomial.chebyshev.chebvander(xf, n)
    xf.flags.writeable = False
    V.flags.writeable = False
    return xf, V


def _root_near(g, xf: np.ndarray, j: int, xtol: float) -> float:
    """Root x of ``g`` between the samples ``xf[j − 1]`` and ``xf[j]``, where the sampled
    values (a matrix product, :func:`fine_sampling`) change sign. ``g`` is the Clenshaw sum,
    which differs from the product by round-off: where that flips the sign of a sample lying
    on the root, the neighbouring intervals hold it."""
    for a, b in ((j - 1, j), (j - 2, j - 1), (j, j + 1)):
        if 0 <= a and b < len(xf):
            try:
                return brent_root(g, float(xf[a]), float(xf[b]), xtol=xtol)
            except ValueError:
                continue
    raise ValueError(f"no sign change near x = {xf[j]:.6g}")


_P = FUNCTIONS.index("p")


def _pressure(model: ChuteModel, nu: float, T: float) -> float:
    """p(ν, T) at one point by the closures' scalar code (:meth:`ChuteModel.scalar_evaluator`,
    ~50× cheaper than :meth:`ChuteModel.evaluate` on a scalar; the same number to
    round-off), or by ``evaluate`` where the scalar code fails (outside its domain)."""
    try:
        v = model.scalar_evaluator(((0, 0),))(nu, T)[_P]
        if isinstance(v, float):
            return v
    except (ValueError, ZeroDivisionError, OverflowError):
        pass
    return float(model.evaluate(nu, T)["p"][(0, 0)])


def derived_quantities(theta, grid: ChebyshevGrid, log_nu, u, T, model: ChuteModel):
    """h, ν̄, ρ̄0, Q0, T̄0, monotonicity and the density peak of a solved profile.

    The integrals include the dilute tail above y_max in closed form: integrating the
    y-momentum balance p' = −ν cos θ gives ∫_{y_max}^∞ ν dy = p(y_max)/cos θ, with u0 and T0
    constant there to the same order.
    """
    c = math.cos(math.radians(theta))
    nu = np.exp(log_nu)
    p_top = _pressure(model, float(nu[-1]), float(T[-1]))
    tail_rho = p_top / c
    rho_bar = grid.integrate(nu) + tail_rho
    Q = grid.integrate(nu * u) + u[-1] * tail_rho
    T_mean = (grid.integrate(nu * T) + T[-1] * tail_rho) / rho_bar
    # density maximum: sign of d ln ν/dy on a fine sampling, refined by root finding; the
    # Chebyshev coefficients are computed once (x ∈ [-1, 1] ↔ y ∈ [0, y_max])
    c_s = coefficients(log_nu)
    c_ds = coefficients(grid.D @ log_nu)
    # the roots are found in x (the series' own variable; no map to invert a step) to
    # 1e-15, i.e. in y to ~1e-15 y'(x) ≲ 1e-13
    xf, V = fine_sampling(grid.n)
    dsf = V @ c_ds
    if (dsf <= 0).all():
        monotonic, y_peak, x_peak = True, 0.0, -1.0
    else:
        monotonic = False
        idx = np.nonzero((dsf[:-1] > 0) & (dsf[1:] <= 0))[0]
        y_peak, x_peak = 0.0, -1.0
        if len(idx):
            x_peak = _root_near(_series(c_ds), xf, int(idx[0]) + 1, 1e-15)
            y_peak = float(grid.from_computational(x_peak))
    s_at = _series(c_s)
    s_peak = s_at(x_peak)
    target = s_peak + math.log(0.01)
    sf = V @ c_s
    above = np.nonzero((xf >= x_peak) & (sf <= target))[0]
    j = above[0]
    h = float(grid.from_computational(_root_near(lambda x: s_at(x) - target, xf, int(j), 1e-15)))
    return {
        "h": h,
        "nu_mean": rho_bar / h,
        "rho_bar": rho_bar,
        "Q": Q,
        "T_mean": T_mean,
        "monotonic": monotonic,
        "y_peak": y_peak,
        "nu_peak": math.exp(s_peak),
    }


def spectral_tail(log_nu, u, T) -> float:
    """Largest relative Chebyshev tail of ln ν0, u0 and T0 (:attr:`SteadyFlow.spectral_tail`)."""
    return max(tail(log_nu), tail(u), tail(T))

"""Stability diagrams of the 1D model (figure 15) and their agreement with the full model.

The 1D criterion at a grid point (θ, ν0(0)) needs only that steady flow and its family
tangent (:func:`~chuteflow.reduced.model.local_coefficients`), so the diagram is a sweep
(:mod:`chuteflow.sweep`) with the steady quantities and the point function ``reduced1d``
defined here. On the same grid as a full-model sweep the two classifications compare point by
point (:func:`agreement`).
"""

from __future__ import annotations

import math

import numpy as np

from .._version import __version__
from ..closures import ChuteModel
from ..continuation import StepRules, Trial, continue_to, march
from ..errors import ConvergenceError, NoSteadyFlowError, ParameterError
from ..steady import solve_steady
from ..sweep import (
    PointFunction,
    SweepConfig,
    Variable,
    classify,
    default_ranges,
    register_point_function,
    resolve_model,
    run_sweep,
)
from .model import local_coefficients

__all__ = ["Reduced1D", "reduced_diagram_config", "reduced_diagram", "agreement", "QUICK_SHAPE", "FULL_SHAPE"]

#: Grid shapes (n_theta, n_nu0) of the diagrams. The quick shape takes every other point of
#: the 13 × 13 quick grid of the full-model diagrams, so the two compare point by point.
QUICK_SHAPE = (7, 7)
FULL_SHAPE = (60, 60)


@register_point_function
class Reduced1D(PointFunction):
    """The 1D model's linear theory at one steady flow (eqs (5.13), (5.14), (5.12)).

    Exact: F', T̄' and a' come from the family tangent of the steady solver.
    """

    name = "reduced1d"
    version = "1"
    requires = ("steady",)
    variables = (
        Variable(
            "r1d_margin", "1", "(ρ0 U')² − (ρ0 T̄)' of the 1D model (> 0: unstable)", source="eq. (5.13)"
        ),
        Variable(
            "r1d_unstable",
            "1",
            "1D model long-wave unstable, (ρ0U')² > (ρ0T̄)'",
            kind="flag",
            source="eq. (5.13)",
        ),
        Variable("r1d_short_wave", "1", "(ρ0T̄)' < 0: the 1D model grows at every wavelength", kind="flag"),
        Variable("r1d_alpha2", "sigma^(3/2) g^(1/2)", "α2 of the 1D model", source="eq. (5.14)"),
        Variable(
            "r1d_k_c",
            "1/sigma",
            "critical wavenumber k_c of the 1D model (inf: all k grow, 0: stable)",
            source="eq. (5.12) (docs/errata.md, item 4)",
        ),
        Variable("r1d_U", "sqrt(g sigma)", "U(ρ0) = ρ0 sinθ / a(ρ0)", source="eq. (5.11)"),
        Variable("r1d_dU", "sqrt(g sigma)/sigma", "U'(ρ0)", source="eq. (5.11)"),
        Variable(
            "r1d_dq0",
            "sqrt(g sigma)",
            "dq0/dρ0 = (ρ0 U)' (the long-wave phase velocity, positive down the slope)",
            source="eq. (5.14)",
        ),
        Variable("r1d_dP", "g sigma", "(ρ0 T̄)'"),
        Variable("r1d_a", "sqrt(g/sigma)", "floor drag a(ρ0) = η*(F, T̄)", source="eq. (5.11)"),
        Variable("r1d_Tbar", "g sigma", "mean temperature T̄(ρ0)"),
    )

    def compute(self, flow, point):
        c = local_coefficients(flow)
        return {
            "r1d_margin": c.criterion_margin,
            "r1d_unstable": c.unstable,
            "r1d_short_wave": c.short_wave_unstable,
            "r1d_alpha2": c.alpha2,
            "r1d_k_c": c.k_c,
            "r1d_U": c.U,
            "r1d_dU": c.dU,
            "r1d_dq0": c.dq0,
            "r1d_dP": c.dP,
            "r1d_a": c.a,
            "r1d_Tbar": c.Tbar,
        }


def reduced_diagram_config(
    roughness: float | None = None,
    *,
    shape=QUICK_SHAPE,
    theta_range=None,
    nu0_range=None,
    grid=None,
    full: bool = False,
    model=None,
    **kw,
) -> SweepConfig:
    """Sweep configuration of a 1D diagram (``full=True``: with the full model's long-wave
    stability too, for a point-by-point comparison on the same grid).

    ``grid = (theta values, nu0 values)`` gives the grid explicitly; otherwise ``shape``
    points over the ranges, which default to those of the full-model diagrams
    (:func:`chuteflow.sweep.default_ranges`). ``model`` (a
    :class:`~chuteflow.closures.ChuteModel`, default the paper's) with ``roughness`` replacing
    its own is the model of the sweep. Other keywords go to :class:`SweepConfig`.
    """
    metrics: list[str | PointFunction] = ["steady", "kinematic", "longwave"] if full else ["steady"]
    metrics.append(Reduced1D())
    kw.setdefault("markers", ())
    if grid is not None:
        th, nu = (tuple(float(v) for v in np.asarray(g, dtype=float).ravel()) for g in grid)
        return SweepConfig(
            theta=th, nu0=nu, model=resolve_model(model, roughness=roughness), metrics=tuple(metrics), **kw
        )
    return SweepConfig.grid(
        roughness,
        shape=tuple(shape),
        theta_range=theta_range,
        nu0_range=nu0_range,
        model=model,
        metrics=tuple(metrics),
        **kw,
    )


def reduced_diagram(
    roughness: float | None = None,
    *,
    shape=QUICK_SHAPE,
    theta_range=None,
    nu0_range=None,
    grid=None,
    engine: str = "sweep",
    out=None,
    workers: int | None = 1,
    progress=None,
    full: bool = False,
    model=None,
    fresh: bool = False,
):
    """The 1D model's stability over a (θ, ν0(0)) grid (figure 15), as a Dataset.

    Parameters
    ----------
    roughness : float, optional
        Floor roughness φ (default: that of ``model``, 0.05 for the paper's model).
    shape : (int, int)
        Grid (n_theta, n_nu0).
    theta_range, nu0_range : (float, float), optional
        Grid ranges (default: the full-model diagrams' ranges for this φ).
    grid : (sequence, sequence), optional
        Explicit θ and ν0(0) values (increasing) instead of ``shape`` and the ranges — e.g.
        those of a full-model diagram, for a point-by-point comparison.
    engine : {"sweep", "walk"}
        ``"sweep"`` (default): the sweep engine of :mod:`chuteflow.sweep` (continuation along
        rows from anchors, workers, persistence to ``out`` and resume; ``full=True`` adds the
        full model's criterion). ``"walk"``: a minimal driver without the sweep engine — each
        θ row by continuation along ν0 from a seed (the row before, or a cold start),
        stopping a direction at its first failure; kept as a cross-check.
    out : path, optional
        NetCDF file to write (sweep engine: also to resume from).
    workers : int, optional
        Sweep engine only: worker processes (1: this process; None: all cores).
    progress : callable, optional
        ``progress(message, advance=n, total=N)``.
    full : bool
        Sweep engine only: also compute the full model's long-wave criterion.
    model : ChuteModel, optional
        Parameters and closures (g0, wall condition, transport closure) of the computation
        (default: the paper's); if ``roughness`` is given too it must equal
        ``model.roughness``.
    fresh : bool
        Sweep engine: discard saved results of another configuration at ``out``.

    Returns
    -------
    xarray.Dataset
        Over (theta, nu0): ``h``, ``nu_mean``, ``rho_bar``, ``monotonic`` (1/0/−1),
        ``status`` (0 steady flow, > 0 none found or not converged), and the ``r1d_*``
        variables of :class:`Reduced1D`; with ``full`` also ``unstable`` of the full model.
    """

    if engine not in ("sweep", "walk"):
        raise ParameterError(f"engine = {engine!r}: choose 'sweep' or 'walk'")
    if full and engine != "sweep":
        raise ParameterError(
            "full = True needs engine = 'sweep' (the full model's stability is a sweep metric)"
        )
    if model is None:
        model = ChuteModel() if roughness is None else ChuteModel(roughness=roughness)
    if roughness is None:
        roughness = model.roughness
    if not math.isclose(model.roughness, roughness):
        raise ParameterError(f"model.roughness = {model.roughness:g} differs from roughness = {roughness:g}")
    if grid is not None:
        thetas, nus = (np.asarray(g, dtype=float).ravel() for g in grid)
        if len(thetas) < 1 or len(nus) < 2 or np.any(np.diff(thetas) <= 0) or np.any(np.diff(nus) <= 0):
            raise ParameterError("grid: need increasing theta values and at least two increasing nu0 values")
        tr, nr = (thetas[0], thetas[-1]), (nus[0], nus[-1])
    else:
        dt, dn = default_ranges(roughness)
        tr = tuple(theta_range) if theta_range is not None else dt
        nr = tuple(nu0_range) if nu0_range is not None else dn
        nt, nn = (int(x) for x in shape)
        if nt < 1 or nn < 2:
            raise ParameterError(f"shape = {shape!r}: need n_theta >= 1 and n_nu0 >= 2")
    if not (0 < tr[0] <= tr[1] < 90 and 0 < nr[0] < nr[1] < model.nu_max):
        raise ParameterError(
            f"theta_range = {tr!r}, nu0_range = {nr!r}: need 0 < theta < 90 "
            f"degrees and 0 < nu0 < nu_max = {model.nu_max:g}, low < high"
        )
    if grid is None:
        thetas = np.round(np.linspace(tr[0], tr[1], nt), 12)
        nus = np.round(np.linspace(nr[0], nr[1], nn), 12)
    if engine == "sweep":
        cfg = reduced_diagram_config(grid=(thetas, nus), full=full, model=model)
        ds = run_sweep(cfg, out, workers=workers, progress=progress or False, fresh=fresh)
        return classify(ds) if full else ds
    flows = _walk_grid(thetas, nus, model, progress)
    ds = _dataset(thetas, nus, flows, model)
    if out is not None:
        ds.to_netcdf(out, engine="h5netcdf")
    return ds


def _solve_from(theta, nu0, model, guess):
    """Steady flow at (θ, ν0) from ``guess`` (a flow or None: cold start), or None."""
    try:
        if guess is None:
            return solve_steady(theta, nu0, model, continuation=False, strict=True)
        return solve_steady(theta, nu0, model, guess=guess, continuation=False, strict=True)
    except (NoSteadyFlowError, ConvergenceError, ArithmeticError, ValueError, np.linalg.LinAlgError):
        return None


def _try(theta, nu0, model, guess, depth: int = 1):
    """Steady flow at (θ, ν0) from ``guess`` (a flow or None: cold start), else None.

    A failed continuation is retried through 2, …, 2**``depth`` equal steps between the
    guess and the target (θ linear, ν0 geometric; :func:`~chuteflow.continuation.continue_to`,
    ``retry="subdivide"``): grid steps of the diagrams are large at small ν0."""
    if guess is None:
        return _solve_from(theta, nu0, model, None)
    th0, nu00 = guess.theta, guess.nu0

    def solve(start, s):
        if s == 1.0:
            th, nu = theta, nu0
        elif s == 0.5:
            th, nu = 0.5 * (theta + th0), math.sqrt(nu0 * nu00)
        else:
            th, nu = th0 + s * (theta - th0), nu00 * (nu0 / nu00) ** s
        f = _solve_from(th, nu, model, start)
        return Trial(f is not None, f)

    res = continue_to(solve, guess, 0.0, 1.0, StepRules(retry="subdivide", max_depth=depth))
    return res.state if res.reached else None


def _walk_grid(thetas, nus, model, progress):
    """Steady flows on the grid: rows from the middle outwards, each by continuation in ν0."""
    nt, nn = len(thetas), len(nus)
    flows = [[None] * nn for _ in range(nt)]
    mid = nt // 2
    order = [mid] + [i for k in range(1, nt) for i in (mid + k, mid - k) if 0 <= i < nt]
    done_rows: dict[int, list] = {}
    for i in order:
        th = thetas[i]
        row = flows[i]
        # the nearest finished row seeds this one (continuation in θ)
        near = [r for r in (i - 1, i + 1) if r in done_rows]
        prev = done_rows[near[0]] if near else None
        seeds = []
        if prev is not None:
            solved = [j for j in range(nn) if prev[j] is not None]
            if solved:
                c = solved[len(solved) // 2]
                seeds = sorted(solved, key=lambda j: abs(j - c))[:3]
        for j in seeds:  # seeds only where prev is a row
            f = _try(th, nus[j], model, prev[j] if prev is not None else None)
            if f is not None:
                row[j] = f
                break
        if all(f is None for f in row):
            for j in sorted(range(nn), key=lambda j: abs(j - nn // 2))[:4]:
                f = _try(th, nus[j], model, None)
                if f is not None:
                    row[j] = f
                    break
        start = next((j for j in range(nn) if row[j] is not None), None)
        if start is not None:

            def step(flow, j, th=th, prev=prev):
                # from the neighbour along the row, else from the row before
                f = _try(th, nus[j], model, flow)
                if f is None and prev is not None and prev[j] is not None:
                    f = _try(th, nus[j], model, prev[j])
                return Trial(f is not None, f)

            # each direction until its first failure
            for direction in (+1, -1):
                stop = nn if direction > 0 else -1
                for j, f in march(step, row[start], range(start + direction, stop, direction)):
                    row[j] = f
        done_rows[i] = row
        if progress:
            progress(f"1D diagram: θ = {th:g}°", advance=1, total=nt)
    return flows


def _dataset(thetas, nus, flows, model):
    import xarray as xr

    nt, nn = len(thetas), len(nus)
    fl = {v.name: np.full((nt, nn), v.missing, dtype=v.dtype) for v in Reduced1D.variables}
    base = {
        k: np.full((nt, nn), np.nan) for k in ("h", "nu_mean", "rho_bar", "Q", "T_mean", "u_floor", "T_floor")
    }
    mono = np.full((nt, nn), -1, dtype=np.int8)
    status = np.ones((nt, nn), dtype=np.int8)
    fn = Reduced1D()
    for i in range(nt):
        for j in range(nn):
            f = flows[i][j]
            if f is None:
                continue
            status[i, j] = 0
            for k in base:
                base[k][i, j] = getattr(f, k)
            mono[i, j] = 1 if f.monotonic else 0
            for v, val in fn.compute(f, None).items():
                fl[v][i, j] = val
    var = {v.name: v for v in Reduced1D.variables}
    data = {k: (("theta", "nu0"), a, var[k].attrs()) for k, a in fl.items()}
    names = {
        "h": ("thickness h", "sigma"),
        "nu_mean": ("mean density ν̄", "1"),
        "rho_bar": ("one-dimensional density ρ̄0", "sigma"),
        "Q": ("flux Q0", "sigma^2"),
        "T_mean": ("mean temperature T̄0", "g sigma"),
        "u_floor": ("slip velocity u0(0)", "sqrt(g sigma)"),
        "T_floor": ("floor temperature T0(0)", "g sigma"),
    }
    for k, a in base.items():
        data[k] = (("theta", "nu0"), a, {"long_name": names[k][0], "units": names[k][1]})
    data["monotonic"] = (
        ("theta", "nu0"),
        mono,
        {
            "long_name": "ν0 decreases monotonically from the floor",
            "units": "1",
            "flag_values": np.array([-1, 0, 1], dtype=np.int8),
            "flag_meanings": "missing false true",
        },
    )
    data["status"] = (
        ("theta", "nu0"),
        status,
        {
            "long_name": "0: steady flow; 1: none found (outside the existence band, or beyond "
            "the first failure of the continuation along ν0)",
            "flag_values": np.array([0, 1], dtype=np.int8),
            "flag_meanings": "ok no_steady_flow",
        },
    )
    attrs = dict(model.attrs())
    attrs.update(
        model_key=model.key(),
        title="1D model stability diagram (Mitarai & Nakanishi figure 15)",
        engine="walk",
        chuteflow_version=__version__,
    )
    return xr.Dataset(
        data,
        coords={
            "theta": ("theta", thetas, {"long_name": "inclination θ", "units": "degree"}),
            "nu0": ("nu0", nus, {"long_name": "floor packing fraction ν0(0)", "units": "1"}),
        },
        attrs=attrs,
    )


def _grid_match(a, b):
    """Index in ``b`` of each value of ``a`` (equal to 1e-9 relative), or None if one is
    absent."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    best = np.abs(a[:, None] - b[None, :]).argmin(axis=1)
    if not np.all(np.abs(b[best] - a) <= 1e-9 * np.maximum(1.0, np.abs(a))):
        return None
    return best


def agreement(reduced_ds, full_ds, *, full_var: str = "unstable", h_min: float = 1.0) -> dict:
    """Fraction of grid points classified alike by the 1D model and the full model.

    Compares ``r1d_unstable`` of ``reduced_ds`` with ``full_var`` (a 0/1 flag, −1 or NaN
    missing; default ``unstable``, Re α2 > 0, from :func:`chuteflow.sweep.classify`) of
    ``full_ds`` at the (θ, ν0) points the two grids share (the 1D grid may be a sub-grid).
    Only points where both are known count, and only flows with thickness h ≥ ``h_min``
    (paper, figure 6: "the region of h < 1 … was not examined … physically
    unacceptable"; needs ``h`` in ``reduced_ds``; 0 compares all).

    Returns
    -------
    dict
        ``fraction`` (agreeing / compared), ``compared``, ``agree``, and the confusion counts
        ``both_unstable``, ``both_stable``, ``only_1d_unstable``, ``only_full_unstable``;
        ``short_wave`` (compared points where the 1D model is unstable at every k);
        ``thin_excluded`` (points left out for h < ``h_min``).
    """
    if "r1d_unstable" not in reduced_ds:
        raise ParameterError(
            "reduced_ds: no variable 'r1d_unstable' (a 1D diagram from chuteflow.reduced.reduced_diagram)"
        )
    if full_var not in full_ds:
        raise ParameterError(
            f"full_ds: no variable {full_var!r}; run chuteflow.sweep.classify "
            "on a sweep with the 'longwave' metric, or name the variable"
        )
    ii = _grid_match(reduced_ds["theta"].values, full_ds["theta"].values)
    jj = _grid_match(reduced_ds["nu0"].values, full_ds["nu0"].values)
    if ii is None or jj is None:
        raise ParameterError("agreement: the 1D grid is not a sub-grid of the full model's (theta, nu0) grid")
    r = reduced_ds["r1d_unstable"].values.astype(float)
    f = full_ds[full_var].values.astype(float)[np.ix_(ii, jj)]
    sw = (
        reduced_ds["r1d_short_wave"].values.astype(float)
        if "r1d_short_wave" in reduced_ds
        else np.zeros_like(r)
    )
    known = (r >= 0) & np.isfinite(r) & (f >= 0) & np.isfinite(f)
    thin = np.zeros_like(known)
    if h_min > 0 and "h" in reduced_ds:
        h = reduced_ds["h"].values
        thin = known & np.isfinite(h) & (h < h_min)
        known &= ~thin
    rb, fb = r[known] == 1, f[known] == 1
    n = int(known.sum())
    agree = int((rb == fb).sum())
    return {
        "fraction": agree / n if n else math.nan,
        "compared": n,
        "agree": agree,
        "both_unstable": int((rb & fb).sum()),
        "both_stable": int((~rb & ~fb).sum()),
        "only_1d_unstable": int((rb & ~fb).sum()),
        "only_full_unstable": int((~rb & fb).sum()),
        "short_wave": int((sw[known] == 1).sum()),
        "thin_excluded": int(thin.sum()),
    }

"""Families of steady flows at fixed inclination, by continuation in ν0(0) (paper §3.2).

Along a family the neighbouring solution, advanced along the exact tangent dX/dβ
(β = ν0(0), :func:`~chuteflow.steady.steady_tangent`), is an excellent Newton start: two
or three iterations instead of a cold start's ten, and it follows the branch through
parameter regions where the isothermal cold start fails (the non-monotonic layers with a
dilute hot cushion under a denser band). Every point is nevertheless converged and
checked at two resolutions exactly as :func:`~chuteflow.steady.solve_steady` does.
"""

from __future__ import annotations

from ..closures import ChuteModel
from .inputs import check_nu0, validate_point
from .options import Options
from .result import SteadyFlow
from .rows import continue_row
from .schema import dataset_attrs, row_arrays, variable_attrs


def steady_family(
    theta: float,
    nu0_values,
    model: ChuteModel | None = None,
    *,
    nu_top: float = 1e-9,
    n: int = 64,
    rtol: float = 1e-8,
    n_max: int = 384,
    min_thickness: float = 1.0,
    tangent: bool = True,
    return_flows: bool = False,
):
    """Steady flows at inclination ``theta`` for each floor density in ``nu0_values``.

    Parameters
    ----------
    theta : float
        Inclination θ in degrees.
    nu0_values : sequence of float
        Floor densities ν0(0), strictly increasing.
    model : ChuteModel, optional
        Closure parameters (paper defaults).
    nu_top, n, rtol, n_max, min_thickness
        As for :func:`~chuteflow.steady.solve_steady`.
    tangent : bool
        Also compute dQ0/dρ̄0, dρ̄0/dν0(0), dQ0/dν0(0) from the exact family tangent
        (eq. (B 6)); about 2 ms per point.
    return_flows : bool
        Also return the list of :class:`~chuteflow.steady.result.SteadyFlow` (None where there is none).

    Returns
    -------
    xarray.Dataset
        Over ``nu0``: the scalars of :data:`~chuteflow.steady.schema.SCALARS`, ``monotonic`` (1/0), ``n``,
        ``status`` and ``error`` (strings). Points without a physical steady flow are NaN
        with their status; no exception is raised for them. Attributes: the model
        parameters, ``theta``, ``nu_top``, ``rtol``, ``min_thickness`` and the chuteflow
        version.
    """
    import xarray as xr

    model = model or ChuteModel()
    opts = Options(nu_top=nu_top, n=n, rtol=rtol, n_max=n_max, min_thickness=min_thickness, tangent=tangent)
    theta, nus, pts = _row(theta, nu0_values, model, opts)
    arr = row_arrays(pts)
    ds = xr.Dataset(
        {k: ("nu0", v, variable_attrs(k)) for k, v in arr.items()},
        coords={"nu0": ("nu0", nus, {"long_name": "floor packing fraction ν0(0)", "units": "1"})},
        attrs={**dataset_attrs(model, opts), "theta": theta},
    )
    if return_flows:
        return ds, [p.flow if p.status == "ok" else None for p in pts]
    return ds


def _row(theta, nu0_values, model: ChuteModel, opts: Options):
    theta = validate_point(theta, 0.5 * model.nu_max, model, 1e-9)[0]
    nus = check_nu0(nu0_values, model)
    validate_point(theta, nus[0], model, opts.nu_top)
    return theta, nus, continue_row(theta, nus, model, opts)


def steady_row(
    theta: float,
    nu0_values,
    model: ChuteModel | None = None,
    *,
    nu_top: float = 1e-9,
    n: int = 64,
    rtol: float = 1e-8,
    n_max: int = 384,
    min_thickness: float = 1.0,
) -> list[tuple[str, SteadyFlow | None, str]]:
    """The solves of :func:`steady_family` without the Dataset: (status, flow, error) per
    floor density, the flow None unless the status is ``"ok"``.

    For callers that need the flows only (a sweep's rows: no table of derived scalars, and
    no xarray in a worker process). Same arguments as :func:`steady_family` (without the
    family tangent); the same solves, so the same flows bit for bit.
    """
    model = model or ChuteModel()
    opts = Options(nu_top=nu_top, n=n, rtol=rtol, n_max=n_max, min_thickness=min_thickness, tangent=False)
    pts = _row(theta, nu0_values, model, opts)[2]
    return [(p.status, p.flow if p.status == "ok" else None, p.error) for p in pts]

"""The Dataset schema of steady families and maps (paper §3.2): variables, their attributes,
and the arrays of a solved row.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .._version import __version__
from ..closures import ChuteModel
from .options import Options

if TYPE_CHECKING:
    from .continuation_step import _Point


#: Scalar variables of a family / map dataset that are attributes of the SteadyFlow.
FLOW_SCALARS = (
    "h",
    "nu_mean",
    "rho_bar",
    "Q",
    "T_mean",
    "u_floor",
    "T_floor",
    "y_max",
    "y_peak",
    "nu_peak",
    "convergence",
)
#: Scalar variables of a family / map dataset (float, NaN where no steady flow): the flow's
#: and the family tangent's.
SCALARS = (*FLOW_SCALARS, "dQ_drho", "drho_dnu0", "dQ_dnu0")


_ATTRS = {
    "h": ("thickness h (ν0 = 1 % of its maximum)", "sigma"),
    "nu_mean": ("mean density ν̄ = ρ̄0 / h", "1"),
    "rho_bar": ("one-dimensional density ρ̄0 = ∫ν0 dy (eq. (3.15))", "sigma"),
    "Q": ("flux Q0 = ∫ν0 u0 dy (eq. (3.15))", "sigma^2 sqrt(g/sigma)"),
    "T_mean": ("density-weighted temperature T̄0", "g sigma"),
    "u_floor": ("slip velocity u0(0)", "sqrt(g sigma)"),
    "T_floor": ("floor temperature T0(0)", "g sigma"),
    "y_max": ("top of the domain, ν0(y_max) = nu_top", "sigma"),
    "y_peak": ("height of the density maximum (0 if monotonic)", "sigma"),
    "nu_peak": ("maximum packing fraction", "1"),
    "convergence": ("relative change of the scalars between resolutions n and 3n/2", "1"),
    "dQ_drho": ("dQ0/dρ̄0 along the family (exact tangent; eq. (B 6))", "sqrt(g sigma)"),
    "drho_dnu0": ("dρ̄0/dν0(0) along the family (exact tangent)", "sigma"),
    "dQ_dnu0": ("dQ0/dν0(0) along the family (exact tangent)", "sigma^2 sqrt(g/sigma)"),
    "monotonic": ("1 if ν0 decreases monotonically from the floor, 0 if its maximum is above the floor", "1"),
    "n": ("Chebyshev intervals of the accepted resolution", "1"),
    "status": ("'ok', 'thin' (h < min_thickness), 'no_steady_flow' or 'not_converged'", ""),
    "error": ("message of the error for points without a steady flow", ""),
}


def variable_attrs(k):
    """``long_name`` and ``units`` attributes of the family variable ``k``."""
    name, units = _ATTRS.get(k, (k, ""))
    return {"long_name": name, "units": units}


def dataset_attrs(model: ChuteModel, opts: Options) -> dict:
    """Attributes of a family or map Dataset: the model, the solver options and the version."""
    attrs = dict(model.attrs())
    attrs.update(
        nu_top=opts.nu_top,
        rtol=opts.rtol,
        min_thickness=opts.min_thickness,
        chuteflow_version=__version__,
        source="Mitarai & Nakanishi §3.2",
    )
    return {k: (str(v) if isinstance(v, bool) else v) for k, v in attrs.items()}


def row_arrays(points: list[_Point]) -> dict[str, np.ndarray]:
    """Scalar results of solved family points as arrays (NaN where not ``ok``), by variable."""
    N = len(points)
    out = {k: np.full(N, np.nan) for k in SCALARS}
    out["monotonic"] = np.full(N, np.nan)
    out["n"] = np.zeros(N, dtype=int)
    out["status"] = np.array([p.status for p in points], dtype=object)
    out["error"] = np.array([p.error for p in points], dtype=object)
    for i, p in enumerate(points):
        if p.status != "ok":
            continue
        f = p.flow
        assert f is not None  # status "ok" carries a flow
        for k in FLOW_SCALARS:
            out[k][i] = getattr(f, k)
        out["monotonic"][i] = 1.0 if f.monotonic else 0.0
        out["n"][i] = f.n
        if p.tangent is not None:
            out["dQ_drho"][i] = p.tangent["dQ_drho"]
            out["drho_dnu0"][i] = p.tangent["drho_bar"]
            out["dQ_dnu0"][i] = p.tangent["dQ"]
    return out

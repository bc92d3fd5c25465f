"""The minimum of the flux Q0(ρ̄0) along a family at fixed θ (paper §3.2, eq. (B 6))."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..closures import ChuteModel
from ..errors import ConvergenceError
from .continuation_step import _continue, _Point, _with_tangent
from .family import steady_family
from .options import Options


@dataclass(frozen=True)
class FluxMinimum:
    """The minimum of Q0(ρ̄0) along a family at fixed θ (:func:`flux_minimum`; paper §3.2,
    eq. (B 6): the root of dQ0/dρ̄0).

    Attributes
    ----------
    theta : float
        Inclination θ in degrees.
    nu0 : float
        Floor density ν0(0) at the minimum (Brent's root of dQ0/dρ̄0 to ``xtol``).
    rho_bar, Q, h, nu_mean : float
        ρ̄0, Q0, the thickness h and ν̄ of the flow there.
    bracket : (float, float)
        The two family points around the minimum.
    xtol : float
        Absolute tolerance of the root in ν0(0).
    convergence : float
        The flow's relative change of its scalars between its last two resolutions.
    converged : bool
        Brent reached ``xtol`` (it raises otherwise) and the flow there its ``rtol``.
    note : str
        How the minimum was found and how converged it is.
    family : xarray.Dataset
        The family that brackets it (not in :meth:`to_dict`).
    """

    theta: float
    nu0: float
    rho_bar: float
    Q: float
    h: float
    nu_mean: float
    bracket: tuple[float, float]
    xtol: float
    convergence: float
    converged: bool
    note: str
    family: Any = field(default=None, repr=False, compare=False)

    def to_dict(self) -> dict:
        """The fields as plain Python values (without the family Dataset)."""
        return {
            "theta": self.theta,
            "nu0": self.nu0,
            "rho_bar": self.rho_bar,
            "Q": self.Q,
            "h": self.h,
            "nu_mean": self.nu_mean,
            "bracket": list(self.bracket),
            "xtol": self.xtol,
            "convergence": self.convergence,
            "converged": self.converged,
            "note": self.note,
        }


def flux_minimum(
    theta: float,
    model: ChuteModel | None = None,
    *,
    nu0_values=None,
    nu_top: float = 1e-9,
    rtol: float = 1e-8,
    xtol: float = 1e-9,
):
    """Minimum of Q0(ρ̄0) at fixed θ: the root of dQ0/dν0(0) along the family (eq. B 6).

    A family on ``nu0_values`` (default 30 values from 0.005 to 0.3, geometric) brackets a
    sign change of dQ0/dρ̄0 from − to + (both from the exact tangent); Brent's method then
    refines it, each evaluation continued from the nearest converged flow.

    Returns
    -------
    FluxMinimum or None
        None when dQ0/dρ̄0 keeps its sign on the family (Q0 monotonic in ρ̄0). Otherwise the
        minimum: ``nu0``, ``rho_bar``, ``Q``, ``h``, ``nu_mean``, ``bracket`` (the two family
        points around it), ``family`` (the dataset) and how converged it is.
    """
    from .._memory import brentq  # scipy's, without keeping the family's flows alive

    model = model or ChuteModel()
    if nu0_values is None:
        nu0_values = np.geomspace(0.005, 0.3, 30)
    fam, flows = steady_family(theta, nu0_values, model, nu_top=nu_top, rtol=rtol, return_flows=True)
    ok = np.nonzero(fam.status.values == "ok")[0]
    slope = fam.dQ_drho.values
    idx = [i for a, i in zip(ok[:-1], ok[1:]) if i == a + 1 and slope[a] < 0 < slope[i]]
    if not idx:
        return None
    i = idx[0]
    opts = Options(nu_top=nu_top, rtol=rtol, min_thickness=0.0)
    cache: dict[float, _Point] = {}
    seeds = [_with_tangent(_Point("ok", flows[i - 1]), opts), _with_tangent(_Point("ok", flows[i]), opts)]

    def g(nu0):
        nb = min(seeds, key=lambda p: abs(p.flow.nu0 - nu0))  # type: ignore[union-attr]  # seeds have flows
        p = _continue(nb, theta, nu0, model, opts)
        if not p.usable:
            raise ConvergenceError(
                f"flux minimum at theta = {theta:g}: no converged flow at nu0 = {nu0:g} ({p.error})"
            )
        cache[nu0] = p
        assert p.tangent is not None  # a usable point has its tangent
        return p.tangent["dQ_drho"]

    root = brentq(g, float(fam.nu0[i - 1]), float(fam.nu0[i]), xtol=xtol, rtol=1e-12)
    f = (cache.get(root) or _continue(seeds[0], theta, root, model, opts)).flow
    assert f is not None  # g(root) was evaluated, and g raises where no flow converged
    bracket = (float(fam.nu0[i - 1]), float(fam.nu0[i]))
    converged = bool(f.converged and math.isfinite(root))
    return FluxMinimum(
        theta=float(theta),
        nu0=float(root),
        rho_bar=float(f.rho_bar),
        Q=float(f.Q),
        h=float(f.h),
        nu_mean=float(f.nu_mean),
        bracket=bracket,
        xtol=float(xtol),
        convergence=float(f.convergence),
        converged=converged,
        note=(
            f"Brent on dQ0/dρ̄0 (exact family tangent) in ν0(0) ∈ [{bracket[0]:g}, {bracket[1]:g}] "
            f"to xtol = {xtol:g}; the flow's scalars change by {f.convergence:.1e} between its "
            f"last two resolutions (rtol = {rtol:g})"
        ),
        family=fam,
    )

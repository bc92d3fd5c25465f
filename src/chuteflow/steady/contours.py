"""The separatrix θ* between collapsing and diverging families (paper §3.2, figure 2(a))."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..closures import ChuteModel
from ..errors import ConvergenceError
from .family import steady_family


@dataclass(frozen=True)
class Separatrix:
    """The angle θ* between contours of θ that collapse (h → 0) and those that diverge
    (h → ∞) as ν̄ decreases (:func:`separatrix`; paper §3.2, figure 2(a)).

    Attributes
    ----------
    theta : float
        θ* in degrees: the midpoint of the final bracket.
    bracket : (float, float)
        The collapsing and the diverging angle, ``xtol`` or less apart.
    h, nu_mean : float
        Thickness and ν̄ at ν0(0) = ``nu0_small`` on the diverging side of the bracket.
    h_lo_side : float
        The last h reached on the collapsing side.
    nu0_small : float
        The smallest floor density of the families (θ* is located at its ν̄, not in the
        limit ν̄ → 0).
    xtol : float
        Width of the bisection's bracket asked for.
    converged : bool
        The bracket is at most ``xtol`` wide (θ* is known to ± xtol/2).
    note : str
        What the number is and how converged.
    """

    theta: float
    bracket: tuple[float, float]
    h: float
    nu_mean: float
    h_lo_side: float
    nu0_small: float
    xtol: float
    converged: bool
    note: str

    def to_dict(self) -> dict:
        """The fields as plain Python values."""
        return {
            "theta": self.theta,
            "bracket": list(self.bracket),
            "h": self.h,
            "nu_mean": self.nu_mean,
            "h_lo_side": self.h_lo_side,
            "nu0_small": self.nu0_small,
            "xtol": self.xtol,
            "converged": self.converged,
            "note": self.note,
        }


def separatrix(
    model: ChuteModel | None = None,
    *,
    theta_range=(14.0, 15.0),
    nu0_small: float = 0.006,
    nu0_ref: float = 0.012,
    xtol: float = 0.01,
    nu_top: float = 1e-9,
) -> Separatrix:
    """Angle θ* separating contours of θ that collapse (h → 0) from those that diverge
    (h → ∞) as ν̄ decreases (§3.2, figure 2(a)).

    A family is *diverging* at θ when it reaches ν0(0) = ``nu0_small`` with h still growing
    as ν0(0) decreases (h(nu0_small) > h(nu0_ref)); otherwise (h falling, or the branch ending
    before ``nu0_small``) it is *collapsing*. θ* is bracketed in ``theta_range`` and bisected
    to ``xtol``. Since ν0(0) cannot reach 0, this locates the separatrix at ν̄ ≈ 1e-3, not in
    the limit.

    Returns
    -------
    Separatrix
        ``theta`` (θ*, midpoint of the final bracket), ``bracket``, ``h`` (thickness at
        ν0(0) = ``nu0_small`` on the diverging side of the bracket), ``nu_mean`` there,
        ``h_lo_side`` (the last h reached on the collapsing side), ``converged``, ``note``.
    """
    model = model or ChuteModel()
    nus = np.array(sorted({nu0_small, nu0_ref, 0.0085, 0.018, 0.025, 0.035, 0.05, 0.07}))
    i_small, i_ref = int(np.argmin(abs(nus - nu0_small))), int(np.argmin(abs(nus - nu0_ref)))

    def classify(theta):
        ds = steady_family(theta, nus, model, nu_top=nu_top, min_thickness=0.0, tangent=False)
        h = ds.h.values
        ok = ds.status.values == "ok"
        diverging = bool(ok[i_small] and ok[i_ref] and h[i_small] > h[i_ref])
        last = h[np.nonzero(ok)[0][0]] if ok.any() else float("nan")
        return diverging, ds, last

    lo, hi = map(float, theta_range)
    d_lo, _, last_lo = classify(lo)
    d_hi, ds_hi, _ = classify(hi)
    if d_lo or not d_hi:
        raise ConvergenceError(
            f"separatrix: theta_range = {theta_range} does not bracket it (diverging at "
            f"{lo:g}: {d_lo}, at {hi:g}: {d_hi})"
        )
    while hi - lo > xtol:
        mid = 0.5 * (lo + hi)
        d, ds, last = classify(mid)
        if d:
            hi, ds_hi = mid, ds
        else:
            lo, last_lo = mid, last
    return Separatrix(
        theta=0.5 * (lo + hi),
        bracket=(lo, hi),
        h=float(ds_hi.h.values[i_small]),
        nu_mean=float(ds_hi.nu_mean.values[i_small]),
        h_lo_side=float(last_lo),
        nu0_small=float(nus[i_small]),
        xtol=float(xtol),
        converged=bool(hi - lo <= xtol),
        note=(
            f"bisection of the families' behaviour at nu0 = {nus[i_small]:g} (nu_mean ≈ "
            f"{float(ds_hi.nu_mean.values[i_small]):.2g}, not the limit nu_mean → 0): theta* in "
            f"[{lo:.6g}, {hi:.6g}] deg, ± {0.5 * (hi - lo):.2g}"
        ),
    )

"""The shooting scan inside a row of a family or map (paper §3): deciding a point the
continuation did not reach, and the quadrants of (θ, ν0(0)) a verdict proves to have no flow.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .continuation_step import _attempt, _Point, _with_tangent
from .options import Options
from .shooting import ExistenceVerdict, steady_existence

#: Verdict kinds of :func:`~chuteflow.steady.shooting.steady_existence` that extend to
#: smaller θ and ν0(0) (the layer is too thin / heats up) and to larger θ and ν0(0) (it
#: collapses or packs): the region with a steady flow lies between them.
_LOW_KINDS = ("too_small", "thin")


_HIGH_KINDS = ("too_large",)


@dataclass(frozen=True)
class Proof:
    """A point where the shooting scan proves that no (physical) steady flow exists.

    The scan's verdicts are ordered (tests/steady/test_existence_map.py checks this against
    an independent shooting scan over the paper's ranges): a layer too thin or heating up
    at (θ, ν0(0)) (kind ``too_small`` or ``thin``) is so at every smaller θ and ν0(0); one
    that collapses or packs (``too_large``) is so at every larger θ and ν0(0). A proof
    therefore decides a whole quadrant of a map without further scans.
    """

    theta: float
    nu0: float
    kind: str
    reason: str

    def covers(self, theta: float, nu0: float) -> bool:
        """Whether the quadrant of this verdict contains (θ, ν0(0))."""
        eps = 1e-12
        if self.kind in _LOW_KINDS:
            return theta <= self.theta + eps and nu0 <= self.nu0 * (1 + eps)
        if self.kind in _HIGH_KINDS:
            return theta >= self.theta - eps and nu0 >= self.nu0 * (1 - eps)
        return abs(theta - self.theta) < eps and abs(nu0 - self.nu0) <= eps * self.nu0


def _implied(theta, nu0, model, proof: Proof) -> _Point:
    side = "smaller" if proof.kind in _LOW_KINDS else "larger"
    where = (
        f"theta = {theta:g} deg, nu0 = {nu0:g}, roughness = {model.roughness:g}, "
        f"wall_loss = {model.wall_loss:g}"
    )
    return _Point(
        "no_steady_flow",
        None,
        f"no steady flow at {where}: the shooting scan at theta = {proof.theta:g} deg, "
        f"nu0 = {proof.nu0:g} finds none ({proof.kind.replace('_', ' ')}), and that verdict "
        f"holds at every {side} angle and floor density — there: {proof.reason}",
    )


def _estimate(v: ExistenceVerdict) -> str:
    return f"u0(0) = {v.u_floor:.6g}, h = {v.h:.4g}, y_max = {v.y_max:.4g}"


def _decide(theta, nu0, model, opts: Options) -> tuple[_Point, ExistenceVerdict | None]:
    """The shooting scan's verdict at (θ, ν0(0))
    (:func:`~chuteflow.steady.shooting.verdict.steady_existence`); where a flow
    exists, Newton from the shot profile at n, 2n, … ≤ n_max (a layer thinner than
    ``min_thickness``: from n only; one thinner than a diameter: from n and 2n)."""
    try:
        v = steady_existence(theta, nu0, model, nu_top=opts.nu_top, min_thickness=opts.min_thickness)
    except (ArithmeticError, ValueError, np.linalg.LinAlgError) as exc:
        return _Point("not_converged", None, f"the shooting scan failed: {type(exc).__name__}: {exc}"), None
    if not v.exists:
        return _Point("no_steady_flow", None, v.reason), v
    m, errors = opts.n, []
    if not v.physical:  # thinner than min_thickness: kept only as a thin layer
        m_last = opts.n
    elif v.h < 1.0:
        # below one diameter (outside the hydrodynamics, §3.2) Newton from the shot profile
        # converges from n or 2n, or stalls at a resolution change of 1e-7…1e-4 from every
        # start: the start from 4n (its ladder also climbs to n_max, ~0.5 s a point)
        # converged nowhere on the 40 × 40 quick diagrams
        m_last = 2 * opts.n
    else:
        m_last = opts.n_max
    while m <= m_last:
        # the shot profile is accurate to ~1e-6: Newton converges in a few steps where the
        # grid resolves the layer, so fail fast as from a continuation guess
        p = _attempt(theta, nu0, model, opts, v.starting_state(m), m)
        if p.usable:
            return _with_tangent(p, opts), v
        errors.append(f"n = {m}: {p.error}")
        m *= 2
    if not v.physical:
        # the scan's solution is thinner than min_thickness: a thin layer, as where Newton
        # resolves it (the label must not depend on which of the two found it)
        return _Point("thin", None, v.reason), v
    if v.h < 1.0:
        # accepted by min_thickness < 1, but thinner than a diameter: outside the
        # hydrodynamics and not examined by the paper (§3.2, figure 6: h < 1)
        return (
            _Point(
                "no_steady_flow",
                None,
                f"no physical steady flow at theta = {theta:g} deg, nu0 = {nu0:g}: the shooting "
                f"scan finds a layer thinner than one diameter ({_estimate(v)}), which Newton "
                f"does not resolve with n_max = {opts.n_max} and the hydrodynamics cannot "
                "describe (§3.2)",
            ),
            v,
        )
    return (
        _Point(
            "not_converged",
            None,
            f"a steady flow exists at theta = {theta:g} deg, nu0 = {nu0:g} (shooting scan: "
            f"{_estimate(v)}) but is not resolved: Newton from the continuation neighbours, the "
            f"isothermal start and the shooting profile did not converge to rtol = "
            f"{opts.rtol:g} with n_max = {opts.n_max} ({'; '.join(errors)})",
        ),
        v,
    )

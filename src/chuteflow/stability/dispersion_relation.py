"""The dispersion relation α(k) of the α(0) = 0 branch (paper §4.2, figures 7–9, 13).

:func:`dispersion` follows the branch of :mod:`.tracking` over a grid of k, with the
fallbacks of :mod:`.lost` where the continuation loses it.
"""

from __future__ import annotations

import numpy as np

from ..conventions import RATE_UNITS, WAVENUMBER_UNITS
from ..errors import ConvergenceError, ParameterError
from ..steady import SteadyFlow, steady_tangent
from .lost import _direct_ladder, _outranked, after_lost_branch, relaxed_branch_modes
from .modes import (
    Mode,
    OperatorCache,
    cache_for,
    check_hydrodynamic_k,
    direct_mode,
    drift_of,
    make_mode,
    resolve_policy,
)
from .operator import validate_k
from .policy import RejectionPolicy
from .resolver import search_above
from .tracking import BranchTracker


def dispersion(
    flow: SteadyFlow,
    k,
    *,
    n: int | None = None,
    policy: RejectionPolicy | None = None,
    n_max: int | None = None,
    drift_tol: float | None = None,
    tail_tol: float | None = None,
    strict: bool = False,
    cache: OperatorCache | None = None,
    least_stable: bool = False,
):
    """Dispersion relation α(k) of the α(0) = 0 branch (figures 7–9, 13).

    Parameters
    ----------
    flow : SteadyFlow
        Base state.
    k : array_like
        Wavenumbers ≥ 0 (any order; computed in increasing order by continuation).
    n : int, optional
        Starting resolution (default ``policy.n_start``, 80); raised along the policy's
        ladder where a point fails.
    policy : RejectionPolicy, optional
        Drift and tail thresholds and the resolution ladder (default: the paper's, §4.1).
    n_max, drift_tol, tail_tol : optional
        Overrides of the policy's fields of the same names.
    strict : bool
        False (default, the package's convention): return points that are not physical at
        N = ``n_max`` flagged ``physical = False``; True: raise :class:`ConvergenceError`
        there or where the branch is lost. Where the continuation loses the branch (non-strict), that
        and every larger k up to ``policy.relaxed_k_max`` are followed once more from k = 0
        with the relaxed tail threshold (:func:`relaxed_branch_modes`, judged by the paper's
        tests), where a direct mode that passes both tests and is less damped outranks a
        rejected relaxed value (:meth:`RejectionPolicy.direct_outranks_relaxed`, as in
        :func:`least_stable`); beyond ``relaxed_k_max`` each k as :func:`after_lost_branch`
        answers; where none of these reaches k, solved directly at k (least-stable physical
        mode by dense QZ at the ladder's first rung, followed up the policy's ladder by
        shift-invert while it converges, :func:`_direct_ladder`). Direct answers are flagged
        ``direct = True`` and ``physical = False`` (a direct solve is not known to lie on
        the branch); the attribute ``branch_lost_at`` is the k where the branch was lost.
    least_stable : bool
        Also the least-stable mode at each k by the resolver's contract
        (:func:`~chuteflow.stability.resolver.search_above` on the branch's value: a mode
        above the branch that passes the paper's tests replaces it, an undecided candidate
        above flags it): variables ``least_re``, ``least_im``, ``least_converged`` and
        ``branch_is_least`` (one dense eigensolve at N = 48 per k, 2D: ~30 ms each). The
        branch's variables are unchanged.

    Returns
    -------
    xarray.Dataset
        Over ``k``: ``alpha_re``, ``alpha_im``, ``drift`` (|α(N) − α(N')|), ``tail``, ``n``,
        ``physical``, ``direct`` (solved directly at k, not on the tracked branch);
        attributes: the flow's parameters, ``dQ_drho`` (dQ0/dρ̄0 of the
        steady family, eq. (B 6): the long-wave slope −Im α/k, figure 8) and ``alpha1_re``,
        ``alpha1_im`` (the continuation's first-order coefficient, α ≈ α1 k).
    """
    import xarray as xr

    ks = np.atleast_1d(np.asarray(k, dtype=float))
    if ks.ndim != 1 or len(ks) == 0:
        raise ParameterError("k: expected a non-empty 1-D array of wavenumbers")
    for kk in ks:
        validate_k(kk, "k")
        check_hydrodynamic_k(kk)
    order = np.argsort(ks, kind="stable")
    policy = resolve_policy(policy, drift_tol=drift_tol, tail_tol=tail_tol, n_max=n_max)
    tr = BranchTracker(flow, n or None, policy=policy, cache=cache)
    out = {name: np.full(len(ks), np.nan) for name in ("alpha_re", "alpha_im", "drift", "tail")}
    nres = np.zeros(len(ks), dtype=int)
    phys = np.zeros(len(ks), dtype=bool)
    direct = np.zeros(len(ks), dtype=bool)
    lost_at = None
    followed: dict[int, Mode] = {}  # the relaxed continuation's modes, by index into ks
    extra = {
        "least_re": np.full(len(ks), np.nan),
        "least_im": np.full(len(ks), np.nan),
        "least_converged": np.zeros(len(ks), dtype=bool),
        "branch_is_least": np.zeros(len(ks), dtype=bool),
    }
    for pos, i in enumerate(order):
        if lost_at is None:
            try:
                mode = _zero_mode(tr) if ks[i] == 0.0 else tr.mode(ks[i])
            except ConvergenceError:
                if strict:
                    raise
                lost_at = float(ks[i])
                # this and the larger k up to policy.relaxed_k_max: followed once more from
                # k = 0 with the relaxed tail threshold, up to the first k not reached
                below = [int(j) for j in order[pos:] if ks[j] <= policy.relaxed_k_max]
                reached = relaxed_branch_modes(
                    flow, [float(ks[j]) for j in below], n=tr.n, policy=policy, cache=cache
                )
                followed = dict(zip(below, reached))
        if lost_at is not None and i in followed:
            mode = followed[i]
            if not mode.physical:
                # as least_stable below policy.relaxed_k_max: a direct mode that passes both
                # of the paper's tests and is less damped outranks the flagged relaxed value
                # (one dense solve at the ladder's first rung: where the relaxed value is
                # rejected, the branch has dissolved and is strongly damped, e.g. Re α =
                # −0.023 with drift 8e-5 at k = 0.0079 against a resolved −0.0046 for θ =
                # 15.36°, ν0(0) = 0.12)
                cand = direct_mode(flow, float(ks[i]), n=policy.n_start, policy=policy, cache=cache)
                mode = _outranked(mode, cand, float(ks[i]), policy)
                direct[i] = mode.method != "branch (relaxed)"
        elif lost_at is not None:
            # branch lost and not reached by the relaxed continuation: past
            # policy.relaxed_k_max as least_stable answers there (after_lost_branch: the band
            # search and the direct mode); else solved directly at k (dense QZ at the
            # ladder's first rung, whose resolved modes need no more, then the candidate
            # followed up the ladder by shift-invert: _direct_ladder)
            relaxed = None
            if ks[i] > policy.relaxed_k_max:
                relaxed = after_lost_branch(flow, float(ks[i]), n=tr.n, policy=policy, cache=cache)
            if relaxed is not None:
                mode = relaxed
                direct[i] = relaxed.method != "branch (relaxed)"
            else:
                mode = _direct_ladder(flow, float(ks[i]), policy, cache)
                direct[i] = True
        if strict and not mode.physical:
            raise ConvergenceError(
                f"dispersion at theta = {flow.theta:g}, nu0 = {flow.nu0:g}: k = {ks[i]:g} not "
                f"converged at N = {mode.n} (drift {mode.drift:.1e}, tail {mode.tail:.1e}; "
                f"thresholds {policy.drift_tol:g}, {policy.tail_tol:g}); raise n_max or pass "
                "strict=False"
            )
        if least_stable:
            least = search_above(flow, float(ks[i]), 0.0, mode, policy, cache_for(0.0, cache))
            assert least is not None  # the branch's own value at least
            extra["least_re"][i], extra["least_im"][i] = least.alpha.real, least.alpha.imag
            extra["least_converged"][i] = least.converged
            extra["branch_is_least"][i] = least is mode
        out["alpha_re"][i], out["alpha_im"][i] = mode.alpha.real, mode.alpha.imag
        out["drift"][i], out["tail"][i] = mode.drift, mode.tail
        # a direct solve is not known to lie on the tracked branch: flagged, not physical
        nres[i], phys[i] = mode.n, mode.physical and not direct[i]
    attrs = {
        "long_name": "dispersion relation of the alpha(0) = 0 branch",
        "source": "Mitarai & Nakanishi §4, eq. (4.4)",
        "theta": flow.theta,
        "nu0": flow.nu0,
        "nu_top": flow.nu_top,
        "y_max": flow.y_max,
        "dQ_drho": float(steady_tangent(flow)["dQ_drho"]),
        "alpha1_re": tr.alpha1.real,
        "alpha1_im": tr.alpha1.imag,
        "drift_tol": policy.drift_tol,
        "tail_tol": policy.tail_tol,
    }
    if lost_at is not None:
        attrs["branch_lost_at"] = lost_at
    attrs.update(flow.model.attrs())
    u = RATE_UNITS
    ds = xr.Dataset(
        {
            "alpha_re": ("k", out["alpha_re"], {"long_name": "growth rate Re alpha", "units": u}),
            "alpha_im": ("k", out["alpha_im"], {"long_name": "Im alpha", "units": u}),
            "drift": ("k", out["drift"], {"long_name": "|alpha(N) - alpha(N')|", "units": u}),
            "tail": (
                "k",
                out["tail"],
                {"long_name": "largest of the ten highest Chebyshev coefficients", "units": "1"},
            ),
            "n": ("k", nres, {"long_name": "Chebyshev intervals N"}),
            "physical": ("k", phys, {"long_name": "passes drift and tail tests"}),
            "direct": (
                "k",
                direct,
                {"long_name": "solved directly at k (dense QZ), not on the tracked branch"},
            ),
        },
        coords={"k": ("k", ks, {"long_name": "wavenumber", "units": WAVENUMBER_UNITS})},
        attrs=attrs,
    )
    if least_stable:
        ds["least_re"] = (
            "k",
            extra["least_re"],
            {"long_name": "growth rate of the least-stable mode", "units": u},
        )
        ds["least_im"] = (
            "k",
            extra["least_im"],
            {"long_name": "Im alpha of the least-stable mode", "units": u},
        )
        ds["least_converged"] = (
            "k",
            extra["least_converged"],
            {"long_name": "the least-stable mode passes drift and tail tests, nothing undecided above"},
        )
        ds["branch_is_least"] = (
            "k",
            extra["branch_is_least"],
            {"long_name": "the branch is the least-stable mode"},
        )
    return ds


def _zero_mode(tr: BranchTracker) -> Mode:
    """The k = 0 point: the null vector, with its own drift and tail."""
    a0 = tr.nv.alpha0
    v = tr.nv.right / tr._operator(tr.n).col_eq
    pencil = tr._pencil(0.0)
    drift, n2 = drift_of(tr.flow, a0, v, tr.n, 0.0, 0.0, tr.three_d, cache=tr.cache)
    return make_mode(pencil, a0, v, drift, n2, tr.policy)

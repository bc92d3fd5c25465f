"""Linear stability commands (paper §4, Appendix B): ``eig``, ``dispersion``, ``longwave``, ``mode``.

Each solves the steady flow at (θ, ν0(0)) first, then:

- ``chuteflow eig``: the least-stable mode at one k (the α(0) = 0 branch, or the whole spectrum
  by dense QZ with ``--method qz``), with its convergence estimates;
- ``chuteflow dispersion``: α(k) of that branch on [0, k_max] and the critical k_c;
- ``chuteflow longwave``: α1, α2 of α = α1 k + α2 k² + … (α2 from the eigenvalue at k = 1e-5,
  the Taylor α2 beside it) and k_c where long-wave unstable;
- ``chuteflow mode``: the eigenfunction figure at one k (figures 10, 11, 14).

``--json`` prints one JSON object (non-finite numbers as null) and nothing else on standard
output; progress goes to standard error.
"""

from __future__ import annotations

import math
from pathlib import Path

import typer

from chuteflow.closures import ChuteModel

from ._app import MODEL_OPTIONS_HERE, app, with_model_options
from ._keys import COMMON_KEYS

#: Keys of ``eig --json`` (and of ``mode --json``), besides the nested ``steady`` summary.
EIG_KEYS = (
    *COMMON_KEYS,
    "k",
    "kx",
    "kz",
    "alpha_re",
    "alpha_im",
    "drift",
    "tail",
    "convergence",
    "physical",
    "n",
    "n_check",
    "wave_speed",
    "unstable",
    "method",
    "converged",
    "note",
)
#: Keys of ``longwave --json`` taken from :meth:`LongWave.to_dict` (with the model's keys,
#: ``k_c``, ``k_max``, ``lambda_c``, ``k_c_converged`` and the nested ``steady``; every key is
#: documented in docs/cli.md). ``alpha2_*`` is the dispersion relation's k² coefficient (from
#: the eigenvalue at k = 1e-5); the Taylor coefficient is the diagnostic ``alpha2_taylor_*``.
LONGWAVE_KEYS = (
    *COMMON_KEYS,
    "alpha1_re",
    "alpha1_im",
    "alpha2_re",
    "alpha2_im",
    "alpha2_convergence",
    "alpha2_im_convergence",
    "alpha2_k",
    "dQ_drho",
    "convergence_alpha1",
    "n",
    "alpha2_taylor_re",
    "alpha2_taylor_im",
    "alpha2_taylor_convergence",
    "taylor_converged",
    "k_check",
    "alpha2_check_re",
    "alpha2_check_im",
    "long_wave_unstable",
    "k_c",
    "k_max",
    "eig_k",
    "eig_alpha2_re",
    "eig_n",
    "sign_consistent",
    "converged",
    "note",
    "k_c_converged",
)


def _opt_theta():
    return typer.Option(..., "--theta", help="Inclination θ in degrees.")


def _opt_nu0():
    return typer.Option(..., "--nu0", help="Floor packing fraction ν0(0).")


_NU_TOP_HELP = "Density where the domain ends (paper: 1e-9)."


def _plain(value):
    """JSON-ready: numpy scalars to Python, non-finite floats to None."""
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if hasattr(value, "item") and not isinstance(value, (str, bytes)):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _echo_json(obj) -> None:
    import json

    typer.echo(json.dumps(_plain(obj), allow_nan=False))


def _console():
    from rich.console import Console

    return Console(stderr=True)


def _steady(console, theta, nu0, model, nu_top):

    from chuteflow._threads import limit_blas_threads
    from chuteflow.steady import solve_steady

    limit_blas_threads(1)
    with console.status(f"steady flow at θ = {theta:g}°, ν0(0) = {nu0:g}"):
        flow = solve_steady(theta, nu0, model, nu_top=nu_top, strict=False)
    if not flow.converged:
        _warn(flow.note)
    return flow


def _params(flow) -> dict:
    return {"theta": flow.theta, "nu0": flow.nu0, **flow.model.to_dict(), "nu_top": flow.nu_top}


def _caption(flow) -> str:
    return (
        f"{flow.model.describe()}, ν0(y_max) = {flow.nu_top:g}; steady h = {flow.h:.5g}, "
        f"y_max = {flow.y_max:.5g}"
    )


def _check_positive(name, value, allow_zero=False):
    from chuteflow.errors import ParameterError

    if value is None:
        return
    if not math.isfinite(value) or value < 0 or (value == 0 and not allow_zero):
        raise ParameterError(
            f"{name} = {value!r} is outside {'[0' if allow_zero else '(0'}, "
            "inf): a wavenumber range of perturbations exp(ikx)"
        )


def _warn(message: str) -> None:
    """One warning line on standard error (results that miss the paper's 1e-7 are still
    printed, exit status 0)."""
    typer.echo(f"warning: {message}", err=True)


def _warn_mode(mode) -> None:
    if not mode.physical:
        _warn(
            f"k = {mode.k:g}: not converged to the paper's thresholds (drift "
            f"{mode.drift:.1e}, tail {mode.tail:.1e} at N = {mode.n}, method {mode.method}); "
            "the best estimate is shown" + (f" ({mode.note})" if mode.note else "")
        )
    elif not mode.method.startswith("branch") and mode.method != "shift":
        how = "a mode above the tracked branch" if mode.method == "global" else "direct solve at k"
        _warn(f"k = {mode.k:g}: answered by {mode.method} ({how})" + (f"; {mode.note}" if mode.note else ""))


def _mode_summary(mode, flow, method) -> dict:
    s = mode.to_dict()
    out = _params(flow)
    out.update({k: s[k] for k in ("k", "alpha_re", "alpha_im", "drift", "tail", "physical", "n", "n_check")})
    # k stays the wavenumber along the slope (the 2D commands' key); kx, kz the wavevector
    # (3D callers set k = kx: a 3D mode's k is |k|)
    stationary = abs(mode.alpha.imag) <= 1e-14 + 1e-9 * abs(mode.alpha)
    out.update(kx=out["k"], kz=float(mode.kz), stationary=bool(stationary))
    out.update(
        convergence=s["drift"],
        wave_speed=mode.wave_speed,
        unstable=bool(mode.alpha.real > 0),
        method=getattr(mode, "method", method) if method == "branch" else method,
        converged=bool(mode.physical),
        note=mode.note,
    )
    out["steady"] = flow.to_dict()
    return out


def _least_stable(console, flow, k, n, method, policy):
    from chuteflow.stability import least_stable
    from chuteflow.stability.modes import check_hydrodynamic_k

    check_hydrodynamic_k(k)
    with console.status(f"least-stable mode at k = {k:g} ({method})"):
        mode = least_stable(flow, k, n=n, method=method, policy=policy, strict=False)
    _warn_mode(mode)
    return mode


def _mode_table(title, summary, caption):
    from rich.table import Table

    t = Table(title=title, caption=caption)
    t.add_column("quantity")
    t.add_column("value", justify="right")
    rows = (
        ("k", "wavenumber k (1/σ)", ".6g"),
        ("alpha_re", "growth rate Re α", ".10g"),
        ("alpha_im", "Im α", ".10g"),
        ("wave_speed", "wave speed −Im α/k", ".8g"),
        ("drift", "|α(N) − α(N')| (convergence)", ".1e"),
        ("tail", "Chebyshev tail (10 highest)", ".1e"),
        ("n", "resolution N", "d"),
        ("n_check", "check resolution N'", "d"),
        ("physical", "physical mode", ""),
        ("unstable", "unstable (Re α > 0)", ""),
    )
    for key, label, fmt in rows:
        v = summary[key]
        t.add_row(label, ("yes" if v else "no") if fmt == "" else format(v, fmt))
    return t


_METHOD_HELP = (
    "branch: follow the α(0) = 0 branch from k = 0 (fast); qz: dense QZ of the "
    "whole spectrum (reference, seconds)."
)


def _wavevector(k, kx, kz):
    """(k_x, k_z) from ``--k`` (k_x, with k_z = 0) or ``--kx``/``--kz``."""
    from chuteflow.errors import ParameterError

    if k is not None and kx is not None:
        raise ParameterError("--k and --kx: give one (--k K is --kx K --kz 0)")
    if k is None and kx is None:
        if kz is None:
            raise ParameterError("k: give --k K (along the slope) or --kx KX [--kz KZ]")
        kx = 0.0
    kx = k if k is not None else kx
    kz = 0.0 if kz is None else kz
    _check_positive("kx" if k is None else "k", kx, allow_zero=kz != 0)
    if not math.isfinite(kz):
        raise ParameterError(f"kz = {kz!r}: expected a finite wavenumber")
    if kx == 0 and kz == 0:
        raise ParameterError("k = 0: the mass mode α = 0; give a nonzero wavevector")
    return float(kx), float(kz)


def _mode_3d(console, flow, kx, kz, n, method, policy):
    """The least-stable mode at (k_x, k_z ≠ 0): the α(0) = 0 branch along the ray (branch),
    or the dense scan of the 3D spectrum (qz)."""
    from chuteflow.stability import least_stable
    from chuteflow.stability.modes import check_hydrodynamic_k

    check_hydrodynamic_k(kx, kz)
    with console.status(f"least-stable mode at kx = {kx:g}, kz = {kz:g} ({method})"):
        mode = least_stable(flow, kx, kz=kz, n=n, method=method, policy=policy, strict=False)
    _warn_mode(mode)
    return mode


@app.command("eig")
@with_model_options
def eig(
    theta: float = _opt_theta(),
    nu0: float = _opt_nu0(),
    k: float | None = typer.Option(
        None, "--k", help="Wavenumber k (1/σ) of exp(αt + ikx) (= --kx K --kz 0)."
    ),
    kx: float | None = typer.Option(None, "--kx", help="Wavenumber along the slope k_x (1/σ)."),
    kz: float | None = typer.Option(None, "--kz", help="Wavenumber across the slope k_z (1/σ; default 0)."),
    model: ChuteModel = MODEL_OPTIONS_HERE,
    nu_top: float = typer.Option(1e-9, "--nu-top", help=_NU_TOP_HELP),
    n: int | None = typer.Option(
        None, "--n", help="Chebyshev intervals N (default: adaptive, from 80 up until drift and tail < 1e-7)."
    ),
    n_max: int = typer.Option(256, "--n-max", help="Largest N of the adaptive choice."),
    method: str = typer.Option("branch", "--method", help=_METHOD_HELP),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object."),
) -> None:
    """Least-stable eigenvalue α at one wavevector (k_x, k_z), with its convergence estimate."""
    kx, kz = _wavevector(k, kx, kz)
    console = _console()
    flow = _steady(console, theta, nu0, model, nu_top)
    from chuteflow.stability import RejectionPolicy

    policy = RejectionPolicy(n_max=n_max)
    if kz == 0:
        mode = _least_stable(console, flow, kx, n, method, policy)
    else:
        mode = _mode_3d(console, flow, kx, kz, n, method, policy)
    out = _mode_summary(mode, flow, method)
    out.update(k=kx, kx=kx, kz=kz)
    if as_json:
        _echo_json(out)
        return
    from rich.console import Console

    where = f"k = {kx:g}" if kz == 0 else f"kx = {kx:g}, kz = {kz:g}"
    Console().print(
        _mode_table(f"Least-stable mode at θ = {theta:g}°, ν0(0) = {nu0:g}, {where}", out, _caption(flow))
    )


@app.command("dispersion")
@with_model_options
def dispersion_cmd(
    theta: float = _opt_theta(),
    nu0: float = _opt_nu0(),
    k_max: float = typer.Option(0.02, "--k-max", help="Largest wavenumber (1/σ)."),
    num: int = typer.Option(50, "--num", help="Number of wavenumbers on [0, k_max]."),
    model: ChuteModel = MODEL_OPTIONS_HERE,
    nu_top: float = typer.Option(1e-9, "--nu-top", help=_NU_TOP_HELP),
    n_max: int = typer.Option(256, "--n-max", help="Largest Chebyshev resolution N."),
    strict: bool = typer.Option(
        False,
        "--strict/--no-strict",
        help="Fail when a point does "
        "not pass the drift and tail tests by N = n_max, or keep it, "
        "flagged physical = false, with a warning (default); where the "
        "branch is lost, points are solved directly at k.",
    ),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object."),
    plot: Path | None = typer.Option(None, "--plot", help="Save the figure (PNG)."),
    out: Path | None = typer.Option(
        None, "--out", "-o", help="Save the dispersion relation as NetCDF (.nc)."
    ),
) -> None:
    """Dispersion relation α(k) of the least-stable (α(0) = 0) branch, and k_c."""
    import numpy as np

    from chuteflow.errors import ParameterError
    from chuteflow.stability import RejectionPolicy, dispersion
    from chuteflow.stability.modes import check_hydrodynamic_k
    from chuteflow.stability.scan import peak_index

    _check_positive("k_max", k_max)
    check_hydrodynamic_k(k_max)
    if num < 2:
        raise ParameterError(f"num = {num}: need at least 2 wavenumbers")
    console = _console()
    flow = _steady(console, theta, nu0, model, nu_top)
    ks = np.linspace(0.0, k_max, num)
    policy = RejectionPolicy(n_max=n_max)
    with console.status(f"dispersion relation at {num} wavenumbers on [0, {k_max:g}]"):
        ds = dispersion(flow, ks, policy=policy, strict=strict, least_stable=True)
    with console.status("critical wavenumbers (sign changes of Re α, Brent)"):
        scan, kc_error = _k_c(flow, k_max, max(num, 12), policy, strict)
    found, k_c = scan.to_crossings(), scan.k_c
    if kc_error is None and not found.converged:
        _warn(f"k_c: {found.note}")
    if found:
        ds.attrs["crossings"] = np.asarray(found, dtype=float)
    if k_c is not None:
        ds.attrs["k_c"] = k_c
    if out is not None:
        out.parent.mkdir(parents=True, exist_ok=True)
        ds.to_netcdf(out, engine="h5netcdf")
    if plot is not None:
        from chuteflow.figures.stability import dispersion_figure

        dispersion_figure([("", ds, k_c)], plot, title=f"Least-stable branch α(k), {_caption(flow)}")
    v = {
        name: ds[name].values
        for name in (
            "k",
            "alpha_re",
            "alpha_im",
            "drift",
            "tail",
            "n",
            "physical",
            "direct",
            "least_re",
            "least_im",
            "least_converged",
            "branch_is_least",
        )
    }
    others = v["k"][~v["branch_is_least"]]
    if len(others):
        j = int(np.flatnonzero(~v["branch_is_least"])[0])
        _warn(
            f"at {len(others)} wavenumbers (k = {others.min():g} … {others.max():g}) another mode "
            f"is less damped than the branch (e.g. k = {v['k'][j]:g}: {v['least_re'][j]:.6g} "
            f"{v['least_im'][j]:+.6g}i against the branch's {v['alpha_re'][j]:.6g}; "
            "`least_re`, `least_im` in --json and --out; `chuteflow eig --k K` answers it)"
        )
    if not v["physical"].all():
        bad = v["k"][~v["physical"]]
        _warn(
            f"{len(bad)} of {len(bad) + int(v['physical'].sum())} wavenumbers (k = "
            f"{bad.min():g} … {bad.max():g}) miss the paper's thresholds by N = {n_max} "
            f"(largest drift {np.nanmax(v['drift']):.1e}, tail {np.nanmax(v['tail']):.1e}); "
            "their best estimates are shown"
        )
    if "branch_lost_at" in ds.attrs:
        _warn(
            f"the branch was lost near k = {ds.attrs['branch_lost_at']:g}; from there on "
            "the least-stable mode is solved directly at each k (dense QZ)"
        )
    # --no-strict: NaN where the branch was lost; k = 0 is outside (0, k_max] (α(0) = 0 by
    # mass conservation, Appendix B: the computed value is its discretisation error)
    # the largest sampled Re α by the branch scan's rule (chuteflow.stability.scan.peak_index)
    i_max = peak_index(v["alpha_re"], v["k"]) or 0
    summary = {
        **_params(flow),
        "k_max": k_max,
        "num": num,
        "k_c": k_c,
        "lambda_c": 2 * math.pi / k_c if k_c else None,
        "crossings": list(found),
        "k_c_error": kc_error,
        "k_c_converged": bool(found.converged),
        "k_cutoff": scan.cutoff(),
        "peak_growth": scan.peak().growth,
        "k_peak": scan.peak().k,
        "all_converged": bool(v["physical"].all()),
        "max_growth": float(v["alpha_re"][i_max]),
        "k_max_growth": float(v["k"][i_max]),
        "max_drift": float(v["drift"].max()),
        "max_tail": float(v["tail"].max()),
        "all_physical": bool(v["physical"].all()),
        "alpha1_im": ds.attrs.get("alpha1_im"),
        **{name: arr.tolist() for name, arr in v.items()},
        "steady": flow.to_dict(),
    }
    if as_json:
        _echo_json(summary)
        return
    from rich.console import Console
    from rich.table import Table

    t = Table(title=f"Dispersion relation at θ = {theta:g}°, ν0(0) = {nu0:g}", caption=_caption(flow))
    for col in ("k", "Re α", "Im α", "drift", "tail", "N"):
        t.add_column(col, justify="right")
    for i in range(len(ks)):
        t.add_row(
            f"{v['k'][i]:.5g}",
            f"{v['alpha_re'][i]:.6e}",
            f"{v['alpha_im'][i]:.6e}",
            f"{v['drift'][i]:.1e}",
            f"{v['tail'][i]:.1e}",
            str(int(v["n"][i])),
        )
    c = Console()
    c.print(t)
    c.print(
        _kc_line(k_c, found, summary, k_max) if kc_error is None else f"k_c not determined: {kc_error}",
        highlight=False,
    )
    for p in (out, plot):
        if p is not None:
            c.print(f"wrote {p}", highlight=False)


def _k_c(flow, k_max, num, policy, strict):
    """The branch scan that decides k_c (:func:`chuteflow.stability.branch_scan`: the first
    sign change of Re α when it goes from + to −, the upper edge of the long-wave unstable
    band 0 < k < k_c; None where the flow is long-wave stable on the scan), and the error
    that ended it (``--no-strict``: an empty scan and the message instead of the error)."""
    import numpy as np

    from chuteflow.errors import ConvergenceError
    from chuteflow.stability import BranchScan, branch_scan

    try:
        return branch_scan(flow, k_max=k_max, num=num, policy=policy, strict=strict), None
    except ConvergenceError as exc:
        if strict:
            raise
        empty = BranchScan.from_samples([0.5 * k_max, k_max], np.full(2, np.nan), note=str(exc))
        return empty, str(exc)


def _kc_line(k_c, found, s, k_max):
    if k_c is not None:
        return (
            f"unstable for 0 < k < k_c = {k_c:.6g} (λ_c = 2π/k_c = {2 * math.pi / k_c:.5g});"
            f" largest sampled Re α = {s['max_growth']:.4e} at k = {s['k_max_growth']:.4g}"
        )
    where = ", ".join(f"{v:.6g}" for v in found) or "none"
    state = "Re α > 0 somewhere" if s["max_growth"] > 0 else "stable"
    band = (
        f"; no long-wave band 0 < k < k_c, Re α > 0 up to k = {s['k_cutoff']:.6g}"
        if s.get("k_cutoff") is not None
        else ""
    )
    return (
        f"{state} on (0, {k_max:g}]: largest sampled Re α = {s['max_growth']:.4e} at k = "
        f"{s['k_max_growth']:.4g}; sign changes of Re α at: {where}{band}"
    )


@app.command("longwave")
@with_model_options
def longwave_cmd(
    theta: float = _opt_theta(),
    nu0: float = _opt_nu0(),
    model: ChuteModel = MODEL_OPTIONS_HERE,
    nu_top: float = typer.Option(1e-9, "--nu-top", help=_NU_TOP_HELP),
    n: int = typer.Option(200, "--n", help="Starting Chebyshev resolution N."),
    rtol: float = typer.Option(
        0.01,
        "--rtol",
        help="Accepted relative change of the Taylor α2 (a diagnostic) between resolutions.",
    ),
    n_max: int = typer.Option(480, "--n-max", help="Largest resolution."),
    k_max: float = typer.Option(0.05, "--k-max", help="Search k_c on (0, k_max]."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object."),
) -> None:
    """Long-wave coefficients α1, α2 (α = α1 k + α2 k² + …) and k_c where unstable."""
    from chuteflow.errors import ParameterError
    from chuteflow.longwave import longwave
    from chuteflow.stability import branch_scan

    _check_positive("k_max", k_max)
    if not 0 < rtol < 1:
        raise ParameterError(f"rtol = {rtol!r} is outside (0, 1): a relative change of α2")
    console = _console()
    flow = _steady(console, theta, nu0, model, nu_top)
    with console.status("long-wave perturbation theory at k = 0"):
        lw = longwave(flow, n=n, rtol=rtol, n_max=n_max, strict=False)
    if not math.isfinite(lw.alpha2.real):
        _warn(
            f"the branch's eigenvalue at k = {lw.alpha2_k:g} was not reached: α2 is unknown and "
            "the sign is that of the Taylor α2 (a diagnostic, docs/errata.md)"
        )
    elif not lw.alpha2_convergence <= 0.2:
        _warn(
            f"Re α2 changed by {lw.alpha2_convergence:.1e} (relative) between N = {lw.eig_n} and "
            "the rung below: its value is uncertain to about that"
        )
    if not lw.sign_consistent:
        _warn(
            f"the signs of the Taylor Re α2 ({lw.alpha2_taylor.real:.4g}, a diagnostic) and of "
            f"Re α2 = Re α/k² at k = {lw.alpha2_k:g} ({lw.alpha2.real:.4g}) differ; the latter "
            "decides"
        )
    k_c, kc_ok = None, True
    if lw.unstable:
        with console.status("critical wavenumber k_c (dispersion relation, Brent)"):
            # the one rule of chuteflow.stability.scan (the same k_c as `chuteflow dispersion`)
            scan = branch_scan(flow, k_max=k_max, refine_peak=False)
            k_c, kc_ok = scan.k_c, scan.converged
            if not kc_ok:
                _warn(f"k_c: {scan.note}")
    s = lw.to_dict()
    out = _params(flow)
    out.update({k: s[k] for k in LONGWAVE_KEYS if k in s})
    out.update(
        k_c=k_c,
        k_max=k_max,
        lambda_c=2 * math.pi / k_c if k_c else None,
        k_c_converged=kc_ok,
        steady=flow.to_dict(),
    )
    if as_json:
        _echo_json(out)
        return
    from rich.console import Console
    from rich.table import Table

    t = Table(title=f"Long-wave expansion at θ = {theta:g}°, ν0(0) = {nu0:g}", caption=_caption(flow))
    t.add_column("quantity")
    t.add_column("value", justify="right")
    t.add_row("α1 (= −i dQ0/dρ̄0)", f"{lw.alpha1.real:.3e} {lw.alpha1.imag:+.10g}i")
    t.add_row("dQ0/dρ̄0 (steady family)", f"{lw.dQ_drho:.10g}")
    t.add_row(
        f"α2 (dispersion relation: (α − α1 k)/k² at k = {lw.alpha2_k:g}, N = {lw.eig_n})",
        f"{lw.alpha2.real:.6g} {lw.alpha2.imag:+.6g}i",
    )
    t.add_row(
        "relative change of Re α2, Im α2 (N → 4N/5)",
        f"{lw.alpha2_convergence:.1e}, {lw.alpha2_im_convergence:.1e}",
    )
    for kk, val in zip(lw.eig_k, lw.eig_alpha2):
        t.add_row(f"Re α/k² at k = {kk:g} (eigenvalue, N = {lw.eig_n})", f"{val:.8g}")
    t.add_row(
        f"diagnostic: Taylor α2 (perturbation theory at k = 0, N = {lw.n})",
        f"{lw.alpha2_taylor.real:.6g} {lw.alpha2_taylor.imag:+.6g}i",
    )
    t.add_row(
        "relative change of α1, Taylor α2 (N → 4N/5)",
        f"{lw.convergence_alpha1:.1e}, {lw.alpha2_taylor_convergence:.1e}",
    )
    chk = lw.alpha2_check
    t.add_row(f"diagnostic: (α(k) − α1 k)/k² at k = {lw.k_check:g}", f"{chk.real:.6g} {chk.imag:+.6g}i")
    t.add_row("long-wave stability", "unstable (Re α/k² > 0)" if lw.unstable else "stable (Re α/k² < 0)")
    t.add_row("k_c", "—" if k_c is None else f"{k_c:.6g} (λ_c = {2 * math.pi / k_c:.5g})")
    Console().print(t)


@app.command("mode")
@with_model_options
def mode_cmd(
    theta: float = _opt_theta(),
    nu0: float = _opt_nu0(),
    k: float | None = typer.Option(None, "--k", help="Wavenumber k (1/σ), > 0 (= --kx K --kz 0)."),
    kx: float | None = typer.Option(None, "--kx", help="Wavenumber along the slope k_x (1/σ)."),
    kz: float | None = typer.Option(
        None, "--kz", help="Wavenumber across the slope k_z (1/σ): ≠ 0 draws the (z, y) cross-section."
    ),
    plot: Path = typer.Option(..., "--plot", help="Eigenfunction figure (PNG)."),
    model: ChuteModel = MODEL_OPTIONS_HERE,
    nu_top: float = typer.Option(1e-9, "--nu-top", help=_NU_TOP_HELP),
    n: int | None = typer.Option(None, "--n", help="Chebyshev intervals N (default: adaptive)."),
    y_top: float | None = typer.Option(
        None, "--y-top", help="Top of the plot (σ; default: where ν0 falls to a tenth of its peak)."
    ),
    x_peak: float = typer.Option(
        0.0,
        "--x-peak",
        help="Put the density maximum at x = x_peak·λ (the eigenvector's phase is arbitrary).",
    ),
    magnify: tuple[float, float, float, float] | None = typer.Option(
        None, "--magnify", metavar="X0 X1 Y0 Y1", help="Add panel (c): (a) on x/λ ∈ [X0, X1], y ∈ [Y0, Y1]."
    ),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object."),
) -> None:
    """Eigenfunction of the least-stable mode over one wavelength (figs 10, 11, 14); with
    ``--kz`` the transverse/oblique mode in the (z, y) cross-section."""
    from chuteflow.errors import ParameterError
    from chuteflow.figures.stability import eigenfunction_diagnostics, eigenfunction_figure
    from chuteflow.figures.transverse import cross_section_figure

    kx, kz = _wavevector(k, kx, kz)
    if y_top is not None and not (math.isfinite(y_top) and y_top > 0):
        raise ParameterError(f"y_top = {y_top!r} is outside (0, inf): a height in diameters")
    if magnify is not None:
        x0, x1, y0, y1 = magnify
        if not (0 <= x0 < x1 <= 1 and 0 <= y0 < y1):
            raise ParameterError(
                f"magnify = {magnify!r}: need 0 <= X0 < X1 <= 1 (fractions of "
                "a wavelength) and 0 <= Y0 < Y1 (heights)"
            )
    console = _console()
    flow = _steady(console, theta, nu0, model, nu_top)
    if kz != 0:
        mode = _mode_3d(console, flow, kx, kz, n, "branch", None)
        with console.status("cross-section figure"):
            path = cross_section_figure(mode, flow, plot, y_top=y_top)
        out = _mode_summary(mode, flow, "branch")
        out.update(k=kx, kx=kx, kz=kz, plot=str(path))
        if as_json:
            _echo_json(out)
            return
        from rich.console import Console

        c = Console()
        where = f"kx = {kx:g}, kz = {kz:g}"
        c.print(
            _mode_table(f"Least-stable mode at θ = {theta:g}°, ν0(0) = {nu0:g}, {where}", out, _caption(flow))
        )
        c.print(f"wrote {path}", highlight=False)
        return
    k = kx
    mode = _least_stable(console, flow, k, n, "branch", None)
    with console.status("eigenfunction figure"):
        path = eigenfunction_figure(mode, flow, plot, y_top=y_top, x_peak=x_peak, magnify=magnify)
    out = _mode_summary(mode, flow, "branch")
    out["diagnostics"] = eigenfunction_diagnostics(mode, flow)
    out["plot"] = str(path)
    if as_json:
        _echo_json(out)
        return
    from rich.console import Console

    c = Console()
    c.print(
        _mode_table(f"Least-stable mode at θ = {theta:g}°, ν0(0) = {nu0:g}, k = {k:g}", out, _caption(flow))
    )
    d = out["diagnostics"]
    c.print(
        f"grains flow {'into' if d['compression'] > 0 else 'out of'} the region of "
        f"positive density perturbation: ∫Re[ν̂*(−ν0∇·û)]/∫|ν̂|² = {d['compression']:.4e} "
        f"(vertical advection {d['vertical_advection']:.4e}; sum = Re α to "
        f"{d['identity_residual']:.0e})",
        highlight=False,
    )
    c.print(
        f"temperature vs density: mean cos(phase) = {d['temperature_density']:.3f} "
        f"(at the density peak {d['temperature_at_peak']:.3f}); floor velocity vs density: "
        f"{d['floor_velocity_density']:.3f}",
        highlight=False,
    )
    c.print(f"wrote {path}", highlight=False)

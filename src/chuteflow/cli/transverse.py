"""Three-dimensional stability commands: ``transverse`` and ``eig3d``.

- ``chuteflow transverse``: perturbations across the slope (k_x = 0): the long-wave
  coefficient α2z, the dispersion α(k_z) on (0, kz_max], the most unstable k_z* and its
  growth rate, whether the mode is stationary;
- ``chuteflow eig3d`` (hidden, deprecated: use ``chuteflow eig --kx KX --kz KZ``): the
  least-stable physical mode at one wavevector (k_x, k_z) by a dense scan.

``--json`` prints one JSON object (non-finite numbers as null) on standard output.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import typer

from chuteflow.closures import ChuteModel

from ._app import MODEL_OPTIONS_HERE, app, with_model_options

#: Keys of ``transverse --json`` the issue asks for (more follow: convergence, model).
TRANSVERSE_KEYS = ("alpha2_z", "kz_max", "growth_max", "stationary", "unstable")
#: Keys of ``eig3d --json``.
EIG3D_KEYS = (
    "theta",
    "nu0",
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
    "unstable",
    "stationary",
)


def _plain(value):
    if isinstance(value, dict):
        return {k: _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if hasattr(value, "item") and not isinstance(value, (str, bytes)):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _flow(theta, nu0, model, nu_top):
    """The steady flow as every stability command solves it (flagged with a warning line
    where it misses the tolerance): :func:`chuteflow.cli.stability._steady`."""
    from .stability import _console, _steady

    return _steady(_console(), theta, nu0, model, nu_top)


def _check_positive(name, value):
    from chuteflow.errors import ParameterError

    if not math.isfinite(value) or value <= 0:
        raise ParameterError(f"{name} = {value!r} is outside (0, inf): a wavenumber")


@app.command("transverse")
@with_model_options
def transverse_cmd(
    theta: float = typer.Option(..., "--theta", help="Inclination θ in degrees."),
    nu0: float = typer.Option(..., "--nu0", help="Floor packing fraction ν0(0)."),
    kz_max: float = typer.Option(3.0, "--kz-max", help="Largest spanwise wavenumber (1/σ)."),
    num: int = typer.Option(50, "--num", help="Number of k_z (geometric from 1e-5)."),
    model: ChuteModel = MODEL_OPTIONS_HERE,
    nu_top: float = typer.Option(1e-9, "--nu-top", help="Density where the domain ends."),
    n_max: int = typer.Option(256, "--n-max", help="Largest Chebyshev resolution N."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object."),
    plot: Path | None = typer.Option(None, "--plot", help="Save Re α(k_z) (PNG)."),
    method: str = typer.Option(
        "track", "--method", help="track: follow the α(0) = 0 branch in k_z (fast); dense: every eigenvalue."
    ),
    plane_plot: Path | None = typer.Option(
        None, "--plane-plot", help="Save a map of Re α over (k_x, k_z) (PNG; the branch along each ray)."
    ),
    plane_max: float | None = typer.Option(
        None, "--plane-max", help="Largest k_x and k_z of the map (default: 2.5 × the transverse cut-off)."
    ),
    plane_num: int = typer.Option(9, "--plane-num", help="Points per axis of the map."),
) -> None:
    """Transverse (k_x = 0) stability: α2z, α(k_z), the most unstable k_z* and its growth."""
    from chuteflow.errors import ParameterError
    from chuteflow.longwave.spanwise import transverse
    from chuteflow.stability import RejectionPolicy

    _check_positive("kz_max", kz_max)
    if kz_max <= 1e-5 or num < 3:
        raise ParameterError("need kz_max > 1e-5 and num >= 3")
    if method not in ("track", "dense"):
        raise ParameterError(f"method = {method!r}: choose 'track' (fast) or 'dense' (every eigenvalue)")
    if plane_max is not None:
        _check_positive("plane_max", plane_max)
    if plane_plot is not None and not 2 <= plane_num <= 40:
        raise ParameterError(f"plane_num = {plane_num}: need 2 to 40 points per axis")
    flow = _flow(theta, nu0, model, nu_top)
    policy = RejectionPolicy(n_max=n_max)
    res = transverse(flow, kz_max=kz_max, num=num, policy=policy, method=method)
    out = {**res.to_dict(), "nu_top": flow.nu_top}
    if plot is not None:
        _plot(res, plot)
    if plane_plot is not None:
        import numpy as np

        from chuteflow.figures.transverse import plane_figure
        from chuteflow.stability.transverse import growth_plane

        top = plane_max or 2.5 * (res.kz_cutoff or res.kz_at_growth_max or 0.01)
        ks = np.linspace(0.0, top, plane_num)
        ds = growth_plane(flow, ks, ks, policy=policy, method="branch")
        plane_figure(ds, plane_plot)
        out["plane"] = {k: ds.attrs[k] for k in ("growth_max", "kx_max", "kz_max", "direction")}
    if as_json:
        typer.echo(json.dumps(_plain(out), allow_nan=False))
        return
    from rich.console import Console
    from rich.table import Table

    t = Table(title=f"Transverse stability at θ = {theta:g}°, ν0(0) = {nu0:g}", caption=flow.model.describe())
    t.add_column("quantity")
    t.add_column("value", justify="right")
    for key in (
        "alpha2_z",
        "alpha2_z_lubrication",
        "convergence_alpha2",
        "dP_drho",
        "drho_T_drho",
        "kz_max",
        "growth_max",
        "kz_cutoff",
        "stationary",
        "unstable",
        "all_physical",
    ):
        v = out[key]
        t.add_row(
            key, "—" if v is None else ("yes" if v else "no") if isinstance(v, bool) else format(v, ".6g")
        )
    Console().print(t)


def _plot(res, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    d = res.dispersion
    fig, ax = plt.subplots(figsize=(5, 3.5))
    g = d.alpha_re
    ax.semilogx(d.kz, np.where(g > 0, g, np.nan), "C3.-", label="Re α > 0")
    ax.semilogx(d.kz, np.where(g <= 0, g, np.nan), "C0.-", label="Re α ≤ 0")
    ax.set_yscale("symlog", linthresh=1e-6)
    ax.set_xlabel("spanwise wavenumber $k_z$ (1/σ)")
    ax.set_ylabel("growth rate Re α")
    ax.set_title(f"θ = {res.theta:g}°, ν0(0) = {res.nu0:g}, α2z = {res.alpha2_z:.4g}")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


@app.command("eig3d", hidden=True, deprecated=True)
@with_model_options
def eig3d(
    theta: float = typer.Option(..., "--theta", help="Inclination θ in degrees."),
    nu0: float = typer.Option(..., "--nu0", help="Floor packing fraction ν0(0)."),
    kx: float = typer.Option(..., "--kx", help="Wavenumber along the slope (1/σ)."),
    kz: float = typer.Option(..., "--kz", help="Wavenumber across the slope (1/σ)."),
    model: ChuteModel = MODEL_OPTIONS_HERE,
    nu_top: float = typer.Option(1e-9, "--nu-top", help="Density where the domain ends."),
    n_max: int = typer.Option(256, "--n-max", help="Largest Chebyshev resolution N."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object."),
) -> None:
    """Least-stable physical mode at the wavevector (k_x, k_z) (dense scan, 3D operator)."""
    from chuteflow.stability import RejectionPolicy
    from chuteflow.stability.transverse import least_stable_3d

    flow = _flow(theta, nu0, model, nu_top)
    m = least_stable_3d(flow, kx, kz, policy=RejectionPolicy(n_max=n_max), strict=True)
    out = {
        "theta": flow.theta,
        "nu0": flow.nu0,
        "kx": kx,
        "kz": kz,
        "alpha_re": m.alpha.real,
        "alpha_im": m.alpha.imag,
        "drift": m.drift,
        "tail": m.tail,
        "convergence": m.drift,
        "physical": m.physical,
        "n": m.n,
        "n_check": m.n_check,
        "unstable": bool(m.alpha.real > 0),
        "stationary": bool(m.alpha.imag == 0),
        **flow.model.to_dict(),
        "nu_top": flow.nu_top,
    }
    if as_json:
        typer.echo(json.dumps(_plain(out), allow_nan=False))
        return
    typer.echo(
        f"alpha = {m.alpha.real:.10g} {m.alpha.imag:+.10g}i  (N = {m.n}, drift "
        f"{m.drift:.1e}, tail {m.tail:.1e}, physical: {m.physical})"
    )


@app.command("winner")
def winner_cmd(
    file: Path = typer.Argument(..., help="NetCDF file of chuteflow diagram --metrics ...,transverse."),
    out: Path | None = typer.Option(None, "--out", "-o", help="Image file (default: FILE with -winner.png)."),
    as_json: bool = typer.Option(False, "--json", help="Print the counts per class as one JSON object."),
) -> None:
    """Draw which instability wins over (h, ν̄) from a sweep with the ``transverse`` metric:
    stable / longitudinal only / transverse only / both."""
    from chuteflow.errors import ParameterError
    from chuteflow.figures.transverse import WINNER_CLASSES, winner_figure
    from chuteflow.sweep import load_sweep

    if not file.exists():
        raise ParameterError(f"file = {str(file)!r}: no such sweep file")
    ds = load_sweep(file)
    if "winner" not in ds:
        raise ParameterError(
            f"file = {str(file)!r} has no 'winner': run chuteflow diagram with --metrics "
            "steady,kinematic,longwave,transverse"
        )
    path = winner_figure(ds, out or file.with_name(file.stem + "-winner.png"))
    w = ds["winner"].values
    counts = {name: int((w == code).sum()) for code, name in WINNER_CLASSES.items()}
    if as_json:
        typer.echo(json.dumps({"plot": str(path), **counts}))
        return
    typer.echo(f"{counts}; wrote {path}")

"""Spatial stability commands: ``spatial`` and ``absolute`` (:mod:`chuteflow.spatial`).

Each solves the steady flow at (θ, ν0(0)) first, then:

- ``chuteflow spatial --omega W``: one point k(ω) of the spatial branch, α(k) = −iω with
  complex k (the wave forced at the inlet at angular frequency ω grows as exp(−Im k · x) down
  the slope), beside Gaster's estimate from the temporal mode of the same frequency;
- ``chuteflow absolute``: absolute or convective instability by the Briggs–Bers saddle
  points along the rays x = V t: the packet's edges V−, V+ and the growth rate at V = 0;
- ``chuteflow signalling --diameter D --chute-length X``: the signalling problem in a
  laboratory's units (:func:`chuteflow.spatial.signalling`): the gain of each inlet
  frequency (Hz) over X metres of chute, the most amplified frequency, the cut-off, and
  whether a wave grows by ``--threshold`` before the end.

``--json`` prints one JSON object (non-finite numbers as null) and nothing else on standard
output; progress goes to standard error.
"""

from __future__ import annotations

import typer

from chuteflow.closures import ChuteModel

from ._app import MODEL_OPTIONS_HERE, app, with_model_options
from ._keys import COMMON_KEYS
from .stability import (
    _NU_TOP_HELP,
    _caption,
    _console,
    _echo_json,
    _opt_nu0,
    _opt_theta,
    _params,
    _steady,
    _warn,
)

#: Keys of ``spatial --json`` (every key is documented in docs/cli.md).
SPATIAL_KEYS = (
    *COMMON_KEYS,
    "omega",
    "k_re",
    "k_im",
    "spatial_growth",
    "group_velocity",
    "k_real",
    "gaster_growth",
    "drift",
    "tail",
    "n",
    "n_check",
    "converged",
    "note",
)
#: Keys of ``absolute --json``.
ABSOLUTE_KEYS = (
    *COMMON_KEYS,
    "k_saddle_re",
    "k_saddle_im",
    "absolute_growth",
    "absolute_frequency",
    "verdict",
    "v_minus",
    "v_plus",
    "v_peak",
    "growth_peak",
    "k_peak",
    "pinch",
    "pinch_v",
    "kinematic_speed",
    "lab_pinch",
    "n",
    "drift",
    "tail",
    "converged",
    "note",
)

#: Keys of ``signalling --json`` (``spectrum`` is a list of objects with ``SPECTRUM_KEYS``).
SIGNALLING_KEYS = (
    *COMMON_KEYS,
    "grain_diameter",
    "chute_length",
    "g",
    "threshold",
    "time_unit",
    "depth",
    "speed",
    "frequency_max",
    "spatial_growth_max",
    "amplification_max",
    "frequency_cutoff",
    "length_to_threshold",
    "visible",
    "omega_max",
    "omega_c",
    "spectrum",
    "converged",
    "note",
)
#: Keys of each entry of ``spectrum`` in ``signalling --json``.
SPECTRUM_KEYS = ("frequency", "omega", "spatial_growth", "amplification", "wavelength", "converged")


def _summary(result, flow) -> dict:
    out = _params(flow)
    out.update(result.to_dict())
    out["nu_top"] = flow.nu_top
    return out


def _table(title, caption, rows, summary):
    from rich.table import Table

    t = Table(title=title, caption=caption)
    t.add_column("quantity")
    t.add_column("value", justify="right")
    for key, label, fmt in rows:
        v = summary[key]
        if fmt == "":
            t.add_row(label, str(v) if not isinstance(v, bool) else ("yes" if v else "no"))
        elif v is None:
            t.add_row(label, "—")
        else:
            t.add_row(label, format(v, fmt))
    return t


@app.command("spatial")
@with_model_options
def spatial_cmd(
    theta: float = _opt_theta(),
    nu0: float = _opt_nu0(),
    omega: float = typer.Option(
        ..., "--omega", help="Angular frequency ω > 0 of the inlet forcing exp(−iωt) (√(g/σ))."
    ),
    model: ChuteModel = MODEL_OPTIONS_HERE,
    nu_top: float = typer.Option(1e-9, "--nu-top", help=_NU_TOP_HELP),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object."),
) -> None:
    """Spatial branch k(ω): the complex wavenumber of the wave forced at frequency ω."""
    from chuteflow.spatial import spatial_point
    from chuteflow.spatial.branches import check_omega

    omega = check_omega(omega)
    console = _console()
    flow = _steady(console, theta, nu0, model, nu_top)
    with console.status(f"spatial branch at ω = {omega:g}"):
        pt = spatial_point(flow, omega, strict=False)
    if not pt.converged:
        _warn(f"ω = {omega:g}: not converged, the best estimate is shown ({pt.note})")
    out = _summary(pt, flow)
    if as_json:
        _echo_json(out)
        return
    from rich.console import Console

    rows = (
        ("omega", "angular frequency ω", ".6g"),
        ("k_re", "Re k", ".10g"),
        ("k_im", "Im k", ".10g"),
        ("spatial_growth", "spatial growth −Im k", ".8g"),
        ("group_velocity", "group velocity", ".8g"),
        ("k_real", "temporal k of the same ω", ".8g"),
        ("gaster_growth", "Gaster's estimate Re α/c_g", ".8g"),
        ("drift", "|α(N) − α(N')| (convergence)", ".1e"),
        ("tail", "Chebyshev tail (10 highest)", ".1e"),
        ("n", "resolution N", "d"),
        ("converged", "converged", ""),
    )
    Console().print(
        _table(f"Spatial branch at θ = {theta:g}°, ν0(0) = {nu0:g}, ω = {omega:g}", _caption(flow), rows, out)
    )


@app.command("absolute")
@with_model_options
def absolute_cmd(
    theta: float = _opt_theta(),
    nu0: float = _opt_nu0(),
    model: ChuteModel = MODEL_OPTIONS_HERE,
    nu_top: float = typer.Option(1e-9, "--nu-top", help=_NU_TOP_HELP),
    lab_frame: bool = typer.Option(
        False,
        "--lab-frame",
        help="Where the saddle family leaves the principal sheet before V = 0, continue it to the "
        "lab frame across the branch cut and check that its saddle pinches (slower).",
    ),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object."),
) -> None:
    """Absolute or convective instability (Briggs–Bers): the packet's edges and the V = 0 saddle."""
    from chuteflow.spatial import absolute_instability

    console = _console()
    flow = _steady(console, theta, nu0, model, nu_top)
    with console.status("saddle points along the rays x = V t (Briggs–Bers)"):
        res = absolute_instability(flow, strict=False, lab_frame=lab_frame)
    if not res.converged:
        _warn(f"verdict {res.verdict!r} is not converged ({res.note})")
    out = _summary(res, flow)
    if as_json:
        _echo_json(out)
        return
    from rich.console import Console

    rows = (
        ("verdict", "verdict", ""),
        ("absolute_growth", "absolute growth Re α(k*) at V = 0", ".8g"),
        ("k_saddle_re", "Re k* (V = 0)", ".8g"),
        ("k_saddle_im", "Im k* (V = 0)", ".8g"),
        ("v_minus", "packet's lower edge V−", ".6g"),
        ("v_plus", "packet's upper edge V+", ".6g"),
        ("v_peak", "ray of fastest growth", ".6g"),
        ("growth_peak", "its growth rate", ".6g"),
        ("kinematic_speed", "kinematic-wave speed dQ0/dρ̄0", ".6g"),
        ("converged", "converged", ""),
    )
    Console().print(
        _table(f"Absolute instability at θ = {theta:g}°, ν0(0) = {nu0:g}", _caption(flow), rows, out)
    )


@app.command("signalling")
@with_model_options
def signalling_cmd(
    theta: float = _opt_theta(),
    nu0: float = _opt_nu0(),
    diameter: float = typer.Option(..., "--diameter", help="Grain diameter σ in metres (> 0)."),
    chute_length: float = typer.Option(
        ..., "--chute-length", help="Distance from the inlet down the slope, in metres (> 0)."
    ),
    g: float = typer.Option(9.81, "--g", help="Gravitational acceleration in m/s² (> 0)."),
    threshold: float = typer.Option(
        10.0, "--threshold", help="Amplitude gain (> 1) that counts as visible at the end of the chute."
    ),
    frequency: list[float] | None = typer.Option(
        None,
        "--frequency",
        "-f",
        help="Forcing frequency in Hz (repeat for several; default: 24 up to 1.25 × the cut-off).",
    ),
    model: ChuteModel = MODEL_OPTIONS_HERE,
    nu_top: float = typer.Option(1e-9, "--nu-top", help=_NU_TOP_HELP),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object."),
) -> None:
    """Would a chute show density waves? The gain of inlet forcing over the chute, in Hz and metres."""
    from chuteflow.spatial import signalling
    from chuteflow.spatial.inlet_forcing import _positive, check_units

    # before any solve, named as the options are
    check_units(diameter, chute_length, g, threshold, names=("diameter", "chute_length", "g", "threshold"))
    for f in frequency or ():
        _positive("frequency", f, "forcing frequencies in Hz")
    console = _console()
    flow = _steady(console, theta, nu0, model, nu_top)
    with console.status("spatial branches k(ω) of the forcing frequencies"):
        res = signalling(
            flow,
            grain_diameter=diameter,
            chute_length=chute_length,
            g=g,
            frequencies=list(frequency) if frequency else None,
            threshold=threshold,
        )
    if not res.converged:
        _warn(f"not converged, the best estimates are shown ({res.note})")
    out = _summary(res, flow)
    if as_json:
        _echo_json(out)
        return
    from rich.console import Console

    rows = (
        ("visible", f"grows by ≥ {threshold:g} within {chute_length:g} m", ""),
        ("amplification_max", "largest gain over the chute", ".4g"),
        ("frequency_max", "most amplified frequency (Hz)", ".4g"),
        ("spatial_growth_max", "its spatial growth (1/m)", ".4g"),
        ("length_to_threshold", f"length to grow by {threshold:g} (m)", ".4g"),
        ("frequency_cutoff", "cut-off frequency (Hz)", ".4g"),
        ("depth", "layer thickness h σ (m)", ".4g"),
        ("speed", "mean velocity (m/s)", ".4g"),
        ("converged", "converged", ""),
    )
    Console().print(
        _table(
            f"Signalling at θ = {theta:g}°, ν0(0) = {nu0:g}: σ = {diameter:g} m, X = {chute_length:g} m",
            _caption(flow),
            rows,
            out,
        )
    )

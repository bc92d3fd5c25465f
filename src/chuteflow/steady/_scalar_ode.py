"""Generated scalar code of the steady equations as an ODE in y (for the shooting scan).

The shooting scan of :mod:`chuteflow.steady.shooting` evaluates the right-hand side of
the steady equations ~10⁴ times per point, one point at a time. Here the right-hand side is
derived symbolically, once, from the same statements as everything else: the y-momentum and
energy residuals of :func:`chuteflow.equations._derive_compiled` (eqs 3.5, 3.6; both affine in
their highest derivative, ν0' and T0'', which they therefore give exactly as
−R(0)/coefficient), u0' = tanθ p/μ (eq. 3.7) and the closures' partials of
:func:`chuteflow.closures.model._derive` substituted in. Common subexpressions are
eliminated and the code is generated for Python floats with the ``math`` module
(:func:`chuteflow._codegen.cached_lambdify`, cached on disk like the other generated code):
about five times faster than calling the closures' and equations' numpy code with scalars.
"""

from __future__ import annotations

import functools
from collections.abc import Callable

from .._codegen import cached_lambdify, lazy_module
from ..closures.model import FUNCTIONS, ORDERS, _derive
from ..equations import BASE, _derive_compiled

sp = lazy_module("sympy")


@functools.cache
def scalar_rhs(transport, radial, wall) -> Callable:
    """``f(nu, u, T, T_y, e_p, nu_m, phi, Phi, sin θ, cos θ)`` → [ν0'/ν0, u0', T0''] for
    the given closure objects (Python floats; raises or returns complex numbers outside the
    closures' domain)."""
    code = cached_lambdify(
        "steady_ode",
        repr((transport, radial, wall)),
        lambda: _derive_rhs(transport, radial, wall),
        sources=(__name__, "chuteflow.equations", "chuteflow.closures.model", transport, radial, wall),
        modules="math",
    )
    return code["rhs"]


def _derive_rhs(transport, radial, wall):
    """Sympy expressions of :func:`scalar_rhs`: {"rhs": (args, [ν0'/ν0, u0', T0''])}."""
    espec, data = _derive_compiled()
    terms = dict(data)
    cspec, _ = _derive(transport, radial, wall)
    (nu, T, e, num, phi, phiw), flat = cspec["partials"]
    eargs = espec["ymom"][0]
    nb, npart = len(BASE), len(FUNCTIONS) * len(ORDERS)
    b = dict(zip(BASE, eargs[:nb]))
    sin_t, cos_t = eargs[nb + npart :]
    u, T_y = sp.symbols("u T_y", real=True)

    def coefficient(name, field, c):
        for t in terms[name]:
            if (t[0], t[1], t[2], t[3], t[4]) == (field, 0, 0, c, 0):
                return espec[name][1][1 + t[5]]
        raise KeyError(f"{name} has no term d^{c} {field}/dy^{c}")

    p00 = flat[FUNCTIONS.index("p") * len(ORDERS) + ORDERS.index((0, 0))]
    mu00 = flat[FUNCTIONS.index("mu") * len(ORDERS) + ORDERS.index((0, 0))]
    u_y = sin_t / cos_t * p00 / mu00  # eq. (3.7)
    sub = dict(zip(eargs[nb : nb + npart], flat))
    sub.update({b["nu"]: nu, b["T"]: T, b["u"]: u, b["T_y"]: T_y, b["u_y"]: u_y})
    sub.update({b["nu_yy"]: 0, b["u_yy"]: 0, b["T_yy"]: 0})
    # y-momentum (eq. 3.5), affine in ν0'
    at0 = {b["nu_y"]: 0}
    nu_y = -espec["ymom"][1][0].xreplace(at0).xreplace(sub) / coefficient("ymom", "nu", 1).xreplace(
        at0
    ).xreplace(sub)
    # energy (eq. (3.6), docs/errata.md, item 1), affine in T0''
    at = {b["nu_y"]: nu_y}
    try:  # the coefficient of ν0'' (κ_h of the heat flux q = −κ∇T − κ_h∇ν)
        c_nu2 = coefficient("energy", "nu", 2).xreplace(sub).xreplace(at)
    except KeyError:
        c_nu2 = sp.S.Zero
    if c_nu2 == 0:  # no density-gradient heat flux (κ_h = 0, the paper's closure)
        T_yy = -espec["energy"][1][0].xreplace(sub).xreplace(at) / coefficient("energy", "T", 2).xreplace(
            sub
        ).xreplace(at)
    else:  # κ_h ν0'' with ν0'' = A + B T0'' (the y-derivative of ν0'(ν0, T0, T0') above)
        Ty_s = sp.Symbol("T_yy_", real=True)
        dnu = (nu_y.diff(nu) * nu_y + nu_y.diff(T) * T_y + nu_y.diff(T_y) * Ty_s).xreplace(sub)
        R = espec["energy"][1][0].xreplace({b["nu_yy"]: dnu, b["T_yy"]: Ty_s}).xreplace(sub).xreplace(at)
        R1 = R.diff(Ty_s)
        T_yy = -R.xreplace({Ty_s: 0}) / R1.xreplace({Ty_s: 0})
    args = (nu, u, T, T_y, e, num, phi, phiw, sin_t, cos_t)
    return {"rhs": (args, [nu_y / nu, u_y, T_yy])}


# ---------------------------------------------------------------------------------------
# The same right-hand side as C, with the Dormand–Prince loop around it (compiled kernel)
# ---------------------------------------------------------------------------------------

#: Status codes of the compiled integrator (those of Hairer's DOPRI5, plus −5: the record
#: arrays are full).
REACHED, STOPPED, TOO_MANY_STEPS, STEP_TOO_SMALL, STIFF, FULL = 1, 2, -2, -3, -4, -5

#: Number of unknowns of the steady ODE: (ln ν0, u0, T0, T0').
NEQ = 4


@functools.cache
def compiled_kernel(transport, radial, wall):
    """The shooting scan's integrator compiled with the right-hand side of
    :func:`scalar_rhs` (a ctypes library, :func:`chuteflow._ccode.cached_library`), or
    ``None`` where compiled kernels are unavailable (the caller uses scipy's ``dopri5``
    with :func:`scalar_rhs` instead).

    The library exports

    * ``cf_rhs(par, z, f)``: f = d/dy of z = (ln ν0, u0, T0, T0'), with par = (e_p, ν_m, φ, Φ,
      sin θ, cos θ); a non-finite value becomes ±1e300 (all four 1e300 if one is NaN), as
      :meth:`~chuteflow.steady.shooting.SteadyODE.rhs_bounded` does;
    * ``cf_integrate(...)``: Dormand–Prince 5(4) with the step-size control, error norm,
      initial step and stiffness test of Hairer's DOPRI5 (what scipy's ``dopri5`` runs,
      with its default settings), stopping at the first accepted step across which one of
      the events z[k] − c changes sign in its direction (the test of
      :func:`~chuteflow.steady.shooting.integrate`'s ``solout``); it records the accepted
      steps and the derivatives there (the first stage of the next step).
    """
    from .._ccode import cached_library

    lib = cached_library(
        "steady_shoot",
        repr((transport, radial, wall)),
        lambda: _kernel_source(transport, radial, wall),
        sources=(__name__, "chuteflow.equations", "chuteflow.closures.model", transport, radial, wall),
    )
    if lib is None:
        return None
    import ctypes

    dp, ip, lp = ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_int), ctypes.POINTER(ctypes.c_long)
    lib.cf_rhs.argtypes = [dp, dp, dp]
    lib.cf_rhs.restype = None
    lib.cf_integrate.argtypes = [
        dp,  # par
        ctypes.c_double,  # t0
        dp,  # z0
        ctypes.c_double,  # tend
        ctypes.c_double,  # rtol
        ctypes.c_double,  # atol
        ctypes.c_long,  # nmax
        ctypes.c_int,  # number of events
        ip,  # event components
        dp,  # event constants
        ip,  # event directions
        ctypes.c_long,  # capacity of the records (0: record nothing)
        dp,  # ts
        dp,  # zs
        dp,  # fs
        lp,  # number recorded
        ip,  # mask of the events that triggered
        dp,  # t, z, f at the exit
    ]
    lib.cf_integrate.restype = ctypes.c_int
    return lib


_KERNEL = r"""
/* d/dy (ln nu0, u0, T0, T0') at z; par = (e, nu_m, phi, Phi, sin theta, cos theta) */
void cf_rhs(const double *par, const double *z, double *f)
{
    const double e = par[0], nu_m = par[1], phi = par[2], Phi = par[3];
    const double sin_theta = par[4], cos_theta = par[5];
    const double nu = exp(z[0]), u = z[1], T = z[2], T_y = z[3];
    (void)u; (void)phi; (void)Phi; (void)e; (void)nu_m; (void)sin_theta; (void)cos_theta;
@BODY@
    f[0] = @OUT0@;
    f[1] = @OUT1@;
    f[2] = T_y;
    f[3] = @OUT2@;
    if (!(isfinite(f[0]) && isfinite(f[1]) && isfinite(f[2]) && isfinite(f[3]))) {
        int i, nan = 0;
        for (i = 0; i < 4; i++) nan |= isnan(f[i]);
        for (i = 0; i < 4; i++) {
            if (nan) f[i] = 1e300;
            else if (!isfinite(f[i])) f[i] = f[i] > 0 ? 1e300 : -1e300;
        }
    }
}

static int crossing(double a, double b, int d)
{
    if (d < 0) return a > 0 && 0 >= b;
    if (d > 0) return a < 0 && 0 <= b;
    return (a > 0 && 0 >= b) || (a < 0 && 0 <= b);
}

#define N 4
#define MAXEV 16

/* Dormand-Prince 5(4) with Hairer's DOPRI5 step control (safety 0.9, step ratio in
   [0.2, 10], beta 0.04, uround 2.3e-16, stiffness test every 1000 steps, initial step by
   HINIT). Records (t, z, f) at the start and at every accepted step until an event crosses
   (that step's end is not recorded but returned in out = (t, z[4], f[4]), with hit = mask
   of the crossing events). Returns 1 (tend reached), 2 (event), -2 (nmax), -3 (step too
   small), -4 (stiff), -5 (records full); out holds the last state in every case. */
int cf_integrate(const double *par, double x, const double *z0, double xend, double rtol,
                 double atol, long nmax, int nev, const int *ek, const double *ec,
                 const int *ed, long cap, double *ts, double *zs, double *fs, long *nrec,
                 int *hit, double *out)
{
    static const double c2 = 0.2, c3 = 0.3, c4 = 0.8, c5 = 8.0 / 9.0;
    static const double a21 = 0.2, a31 = 3.0 / 40.0, a32 = 9.0 / 40.0;
    static const double a41 = 44.0 / 45.0, a42 = -56.0 / 15.0, a43 = 32.0 / 9.0;
    static const double a51 = 19372.0 / 6561.0, a52 = -25360.0 / 2187.0,
                        a53 = 64448.0 / 6561.0, a54 = -212.0 / 729.0;
    static const double a61 = 9017.0 / 3168.0, a62 = -355.0 / 33.0, a63 = 46732.0 / 5247.0,
                        a64 = 49.0 / 176.0, a65 = -5103.0 / 18656.0;
    static const double a71 = 35.0 / 384.0, a73 = 500.0 / 1113.0, a74 = 125.0 / 192.0,
                        a75 = -2187.0 / 6784.0, a76 = 11.0 / 84.0;
    static const double e1 = 71.0 / 57600.0, e3 = -71.0 / 16695.0, e4 = 71.0 / 1920.0,
                        e5 = -17253.0 / 339200.0, e6 = 22.0 / 525.0, e7 = -1.0 / 40.0;
    const double uround = 2.3e-16, safe = 0.9, fac1 = 0.2, fac2 = 10.0, beta = 0.04;
    const double expo1 = 0.2 - beta * 0.75, facc1 = 1.0 / fac1, facc2 = 1.0 / fac2;
    const long nstiff = 1000;
    double y[N], y1[N], ysti[N], k1[N], k2[N], k3[N], k4[N], k5[N], k6[N];
    double gprev[MAXEV], gnow[MAXEV];
    double h, hmax, posneg, facold = 1e-4, hlamb = 0.0, err, fac, fac11, hnew, xph, sk;
    long nstep = 0, naccpt = 0, n = 0;
    int i, j, last = 0, reject = 0, iasti = 0, nonsti = 0, idid;

    if (nev > MAXEV) nev = MAXEV;
    *hit = 0;
    memcpy(y, z0, sizeof y);
    posneg = xend - x >= 0 ? 1.0 : -1.0;
    hmax = fabs(xend - x);
    cf_rhs(par, y, k1);
    {   /* initial step (HINIT, order 5) */
        double dnf = 0.0, dny = 0.0, der2 = 0.0, der12, h1;
        for (i = 0; i < N; i++) {
            sk = atol + rtol * fabs(y[i]);
            dnf += (k1[i] / sk) * (k1[i] / sk);
            dny += (y[i] / sk) * (y[i] / sk);
        }
        h = (dnf <= 1e-10 || dny <= 1e-10) ? 1e-6 : sqrt(dny / dnf) * 0.01;
        h = fmin(h, hmax);
        h = copysign(h, posneg);
        for (i = 0; i < N; i++) y1[i] = y[i] + h * k1[i];
        cf_rhs(par, y1, k2);
        for (i = 0; i < N; i++) {
            sk = atol + rtol * fabs(y[i]);
            der2 += ((k2[i] - k1[i]) / sk) * ((k2[i] - k1[i]) / sk);
        }
        der2 = sqrt(der2) / h;
        der12 = fmax(fabs(der2), sqrt(dnf));
        h1 = der12 <= 1e-15 ? fmax(1e-6, fabs(h) * 1e-3) : pow(0.01 / der12, 1.0 / 5.0);
        h = fmin(fmin(100 * fabs(h), h1), hmax);
        h = copysign(h, posneg);
    }
    /* the output at the start: record it and the events' values there */
    if (cap > 0) {
        ts[0] = x;
        memcpy(zs, y, sizeof y);
        memcpy(fs, k1, sizeof k1);
        n = 1;
    }
    for (j = 0; j < nev; j++) gprev[j] = y[ek[j]] - ec[j];
    for (;;) {
        if (nstep > nmax) { idid = -2; break; }
        if (0.1 * fabs(h) <= fabs(x) * uround) { idid = -3; break; }
        if ((x + 1.01 * h - xend) * posneg > 0.0) { h = xend - x; last = 1; }
        nstep++;
        for (i = 0; i < N; i++) y1[i] = y[i] + h * a21 * k1[i];
        cf_rhs(par, y1, k2);
        for (i = 0; i < N; i++) y1[i] = y[i] + h * (a31 * k1[i] + a32 * k2[i]);
        cf_rhs(par, y1, k3);
        for (i = 0; i < N; i++) y1[i] = y[i] + h * (a41 * k1[i] + a42 * k2[i] + a43 * k3[i]);
        cf_rhs(par, y1, k4);
        for (i = 0; i < N; i++)
            y1[i] = y[i] + h * (a51 * k1[i] + a52 * k2[i] + a53 * k3[i] + a54 * k4[i]);
        cf_rhs(par, y1, k5);
        for (i = 0; i < N; i++)
            ysti[i] = y[i] + h * (a61 * k1[i] + a62 * k2[i] + a63 * k3[i] + a64 * k4[i] + a65 * k5[i]);
        xph = x + h;
        cf_rhs(par, ysti, k6);
        for (i = 0; i < N; i++)
            y1[i] = y[i] + h * (a71 * k1[i] + a73 * k3[i] + a74 * k4[i] + a75 * k5[i] + a76 * k6[i]);
        cf_rhs(par, y1, k2);
        for (i = 0; i < N; i++)
            k4[i] = (e1 * k1[i] + e3 * k3[i] + e4 * k4[i] + e5 * k5[i] + e6 * k6[i] + e7 * k2[i]) * h;
        err = 0.0;
        for (i = 0; i < N; i++) {
            sk = atol + rtol * fmax(fabs(y[i]), fabs(y1[i]));
            err += (k4[i] / sk) * (k4[i] / sk);
        }
        err = sqrt(err / N);
        fac11 = pow(err, expo1);
        fac = fac11 / pow(facold, beta);
        fac = fmax(facc2, fmin(facc1, fac / safe));
        hnew = h / fac;
        if (err <= 1.0) {
            facold = fmax(err, 1e-4);
            naccpt++;
            if (naccpt % nstiff == 0 || iasti > 0) {
                double stnum = 0.0, stden = 0.0;
                for (i = 0; i < N; i++) {
                    stnum += (k2[i] - k6[i]) * (k2[i] - k6[i]);
                    stden += (y1[i] - ysti[i]) * (y1[i] - ysti[i]);
                }
                if (stden > 0.0) hlamb = h * sqrt(stnum / stden);
                if (hlamb > 3.25) {
                    nonsti = 0;
                    iasti++;
                    if (iasti == 15) { idid = -4; break; }
                } else {
                    nonsti++;
                    if (nonsti == 6) iasti = 0;
                }
            }
            memcpy(k1, k2, sizeof k1);
            memcpy(y, y1, sizeof y);
            x = xph;
            if (nev > 0) {
                int found = 0;
                for (j = 0; j < nev; j++) {
                    gnow[j] = y[ek[j]] - ec[j];
                    if (crossing(gprev[j], gnow[j], ed[j])) found |= 1 << j;
                }
                if (found) { *hit = found; idid = 2; break; }
                memcpy(gprev, gnow, sizeof(double) * (size_t)nev);
            }
            if (cap > 0) {
                if (n >= cap) { idid = -5; break; }
                ts[n] = x;
                memcpy(zs + N * n, y, sizeof y);
                memcpy(fs + N * n, k1, sizeof k1);
                n++;
            }
            if (last) { idid = 1; break; }
            if (fabs(hnew) > hmax) hnew = posneg * hmax;
            if (reject) hnew = posneg * fmin(fabs(hnew), fabs(h));
            reject = 0;
        } else {
            hnew = h / fmin(facc1, fac11 / safe);
            reject = 1;
            last = 0;
        }
        h = hnew;
    }
    *nrec = n;
    out[0] = x;
    memcpy(out + 1, y, sizeof y);
    memcpy(out + 1 + N, k1, sizeof k1);
    return idid;
}
"""


def _kernel_source(transport, radial, wall) -> str:
    """C source of :func:`compiled_kernel`: the expressions of :func:`_derive_rhs` (common
    subexpressions eliminated, as in the Python code) printed by sympy's C99 printer."""
    from .._ccode import C_HEAD, c_statements

    args, exprs = _derive_rhs(transport, radial, wall)["rhs"]
    names = [str(a) for a in args]
    if names != ["nu", "u", "T", "T_y", "e", "nu_m", "phi", "Phi", "sin_theta", "cos_theta"]:
        raise ValueError(f"unexpected arguments of the steady right-hand side: {names}")
    decls, out = c_statements(exprs)
    return C_HEAD + (
        _KERNEL.replace("@BODY@", "\n".join(decls))
        .replace("@OUT0@", out[0])
        .replace("@OUT1@", out[1])
        .replace("@OUT2@", out[2])
    )

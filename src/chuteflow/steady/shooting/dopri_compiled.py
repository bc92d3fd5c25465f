"""The shooting scan's compiled integrator: Dormand–Prince 5(4) and the right-hand side in C
(:func:`~chuteflow.steady._scalar_ode.compiled_kernel`).
"""

from __future__ import annotations

import numpy as np

from .._scalar_ode import FULL, NEQ, STOPPED
from .trajectory import Trajectory, _hermite, _hermite_output, _level, _secant_event


class _Kernel:
    """The compiled shooting integrator (:func:`~chuteflow.steady._scalar_ode.compiled_kernel`)
    for one θ and model: :meth:`~chuteflow.steady.shooting.dopri_scipy.integrate` does what
    :func:`~chuteflow.steady.shooting.dopri_scipy.integrate` does with scipy's dopri5 and
    :meth:`~chuteflow.steady.shooting.ode.SteadyODE.rhs_bounded`, the stepping loop and the
    right-hand side in C (one call per trajectory instead of ~10³ Python calls)."""

    def __init__(self, lib, params):
        import ctypes

        self.lib = lib
        self._dp = ctypes.POINTER(ctypes.c_double)
        self._par = np.array(params, dtype=float)
        self._z = np.empty(NEQ)
        self._f = np.empty(NEQ)
        self._out = np.empty(1 + 2 * NEQ)
        self._nrec = ctypes.c_long(0)
        self._hit = ctypes.c_int(0)
        self._p_par, self._p_z, self._p_f, self._p_out = map(
            self._ptr, (self._par, self._z, self._f, self._out)
        )
        self._p_nrec, self._p_hit = ctypes.byref(self._nrec), ctypes.byref(self._hit)
        self._grow(4096)

    def _grow(self, cap: int) -> None:
        self._cap = cap
        self._ts = np.empty(cap)
        self._zs = np.empty(cap * NEQ)
        self._fs = np.empty(cap * NEQ)
        self._p_ts, self._p_zs, self._p_fs = map(self._ptr, (self._ts, self._zs, self._fs))

    def _ptr(self, a: np.ndarray):
        return a.ctypes.data_as(self._dp)

    def rhs(self, z) -> np.ndarray:
        """d/dy of z (a copy), bounded as :meth:`~chuteflow.steady.shooting.ode.SteadyODE.rhs_bounded`."""
        self._z[:] = z
        self.lib.cf_rhs(self._p_par, self._p_z, self._p_f)
        return self._f.copy()

    def _run(self, t0, z0, t_end, rtol, nmax, levels, record):
        import ctypes

        ne = len(levels)
        ek = (ctypes.c_int * max(ne, 1))(*[k for _, k, _, _ in levels])
        ec = (ctypes.c_double * max(ne, 1))(*[c for _, _, c, _ in levels])
        ed = (ctypes.c_int * max(ne, 1))(*[d for _, _, _, d in levels])
        self._z[:] = z0
        while True:
            status = self.lib.cf_integrate(
                self._p_par,
                float(t0),
                self._p_z,
                float(t_end),
                float(rtol),
                1e-12,
                int(nmax),
                ne,
                ek,
                ec,
                ed,
                self._cap if record else 0,
                self._p_ts,
                self._p_zs,
                self._p_fs,
                self._p_nrec,
                self._p_hit,
                self._p_out,
            )
            if status != FULL:
                return status
            self._grow(4 * self._cap)  # deterministic: the same run with room for it

    def state_at(self, t0, z0, t_end, rtol) -> np.ndarray:
        """The state at ``t_end`` integrated from (t0, z0) (no events; scipy's dopri5 with
        ``nsteps = 10**4`` in :func:`~chuteflow.steady.shooting.dopri_scipy.integrate`)."""
        self._run(t0, z0, t_end, rtol, 10**4, (), record=False)
        return self._out[1 : 1 + NEQ].copy()

    def integrate(self, z0, y_cap: float, rtol: float, levels, *, dense: bool = False) -> Trajectory:
        """:func:`~chuteflow.steady.shooting.dopri_scipy.integrate` of the steady ODE from y = 0
        with the events z[k] − c of
        ``levels`` ((name, k, c, direction), in order of priority for simultaneous
        crossings at the same height as in :func:`~chuteflow.steady.shooting.dopri_scipy.integrate`)."""
        status = self._run(0.0, z0, y_cap, rtol, 10**6, levels, record=True)
        n = self._nrec.value
        t = self._ts[:n].copy()
        zs = self._zs[: n * NEQ].reshape(n, NEQ).copy()
        fs = self._fs[: n * NEQ].reshape(n, NEQ).copy()
        hit = None
        if status == STOPPED:
            # the crossing on the step's cubic Hermite interpolant (bisection to round-off),
            # then two secant steps each integrating afresh from the step's start, exactly
            # as integrate() does
            t_old, z_old, f0 = float(t[-1]), zs[-1], fs[-1]
            t_new = float(self._out[0])
            z_new, f1 = self._out[1 : 1 + NEQ].copy(), self._out[1 + NEQ :].copy()
            mask = self._hit.value
            best = None
            for j, (name, k, c, _) in enumerate(levels):
                if not mask & (1 << j):
                    continue
                lo, hi = t_old, t_new
                glo = float(z_old[k]) - c
                y0, y1, d0, d1 = float(z_old[k]), float(z_new[k]), float(f0[k]), float(f1[k])
                for _ in range(100):
                    mid = 0.5 * (lo + hi)
                    if mid <= lo or mid >= hi:
                        break
                    gm = _hermite(t_old, t_new, y0, y1, d0, d1, mid) - c
                    if (gm > 0) == (glo > 0) and gm != 0:
                        lo, glo = mid, gm
                    else:
                        hi = mid
                if best is None or hi < best[1]:
                    best = (name, hi, k, c)
            assert best is not None  # the mask names at least one event
            hit, t_ev, k, c = best

            def state_at(t_end):
                return self.state_at(t_old, z_old, t_end, rtol) if t_end > t_old else z_old

            t_ev, z_ev = _secant_event(_level(k, c), lambda _t, z: self.rhs(z), state_at, t_old, t_ev, t_new)
            t = np.append(t, t_ev)
            zs = np.vstack([zs, z_ev])
            fs = np.vstack([fs, self.rhs(z_ev)])
        traj_status = 0 if (hit is not None or status > 0) else -1
        y = zs.T
        sol = _hermite_output(t, zs, fs) if dense and len(t) > 1 else None
        return Trajectory(t, y, hit, traj_status, sol)

"""Fully implicit time steps (BDF2) solved by preconditioned Newton–Krylov.

Each step solves F(C^{n+1}) = 0 (:meth:`Discretisation.residual`). Newton's linear systems
are solved by GMRES on finite-difference Jacobian–vector products, right-preconditioned by
the block-diagonal (per Fourier mode) linearisation about the x-averaged state
(:meth:`Discretisation.linear_blocks`): in the linear phase the preconditioner is the
Jacobian and one chord iteration converges. The block inverses are reused across steps while
Newton converges in at most ``refresh_after`` iterations and GMRES in at most
``refresh_krylov``, and rebuilt from the current state's x-mean otherwise. Newton starts from
the caller's extrapolation in time and asks GMRES only for the reduction that reaches the
tolerance (inexact Newton). At large amplitude the x-mean describes the Jacobian badly
(GMRES needs hundreds of iterations) and ``preconditioner="auto"`` switches to the Jacobian
of each x-column at the local state (:class:`~chuteflow.dns.columns.ColumnPreconditioner`),
rebuilt when GMRES needs twice what it needed after the last build; docs/dns.md, *Solver*.
``preconditioner="coupled"`` keeps the transport exact in every mode and couples each mode to
its neighbours through the first x-harmonics of the local Jacobian
(:class:`~chuteflow.dns.coupled.CoupledPreconditioner`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.sparse.linalg import LinearOperator, gmres

from ..errors import ConvergenceError, ParameterError
from .columns import NX_LIMIT, ColumnPreconditioner, check_column_order, check_column_x, check_column_y
from .coupled import CoupledPreconditioner
from .discretisation import BDF1, BDF2, Discretisation

__all__ = ["NewtonSettings", "Stepper", "StepInfo", "PRECONDITIONERS"]

#: Preconditioners of the Newton–Krylov solve (:class:`NewtonSettings`).
PRECONDITIONERS = ("auto", "mean", "columns", "coupled")


@dataclass(frozen=True)
class NewtonSettings:
    """Tolerances of the Newton–Krylov solve of one implicit step.

    Attributes
    ----------
    atol : float
        Converged when the max-norm of the scaled residual is below this.
    floor_atol : float
        A residual below this that has stopped falling (not halved over the last two
        iterations), or that ``max_iter`` iterations leave there, is taken as the round-off
        floor of the scaled residual and the step is accepted with it
        (:attr:`StepInfo.residual`). At θ = 16°, ν0(0) = 0.2 with
        ``garzo_dufty`` the steady relaxation's Newton stalls at 3.7e-10 > ``atol``, and
        the run then reproduces the eigenvalue to 4.5e-6 (tests/closures).
    newton_rtol : float
        A step given a ``guess`` (the run's linear extrapolation in time) is also converged
        once Newton has reduced the max-norm of the residual by this factor from the guess's:
        tolerance max(``atol``, ``newton_rtol`` × the guess's residual). That residual
        measures the step's change beyond the extrapolation — what the step control holds
        below ``dt_tol`` — so the algebraic error stays this fraction of it; in the linear
        phase the extrapolation is nearly exact and ``atol`` decides. Without a guess (a first
        step, the steady relaxation) ``atol`` alone. Measured (docs/dns.md, *Newton's
        tolerance relative to the step*): P1, L = 1000 from noise to saturation 159 → 89 s
        with 1e-3, the wave the same to 1.3e-6 in ρ̄/⟨ρ̄⟩; at P5's bore (257 × 96, Δt = 8) 262 →
        78 GMRES iterations and 32 → 6 s a step, at a ±80 % wave 82 → 29. 0: ``atol`` alone.
    max_iter : int
        Newton iterations before the step is declared failed (then Δt is halved).
    gmres_rtol : float
        Relative tolerance of each GMRES solve.
    gmres_restart, gmres_maxiter : int
        GMRES restart length and number of restarts (100 × 2; was 40 × 4: at the ±18 % wave
        of P1, L = 1000, nx = 65 the longer restart needs 135 instead of 362 iterations per
        step at Δt = 32, 60 instead of 74 at Δt = 16, the same 13 at Δt = 4; docs/dns.md).
    refresh_after : int
        Rebuild the preconditioner when a step needed more Newton iterations than this.
    refresh_krylov : int
        … or when one GMRES solve needed more iterations than this,
    refresh_every : int
        … but then at most once in this many steps.
    refresh_excess : int
        The dear preconditioners (columns, coupled blocks; rebuilt by the rules above where a
        solve needs twice the first solve's count after their build) also: rebuilt once the GMRES
        iterations of the steps since their build, above the count of the first step after
        it, add up to more than this (signed) — about what a build costs (the column build 5.3 s against
        ≈ 50 ms a GMRES iteration at P5's mapped 129 × 96, 8 s against 85 ms at P1's 225 × 96).
        The frozen coefficients drift from the travelling wave (P1, L = 2000, 225 × 96: 38 → 105
        GMRES a step over 25 steps before the rule of twice the first count rebuilt them).
    chord_ratio : float
        A chord step (preconditioner as Jacobian, no GMRES) is kept when it reduces the
        residual by at least this factor; otherwise GMRES is used.
    preconditioner : {"auto", "mean", "columns", "coupled"}
        ``"mean"``: the per-mode linearisation about the x-averaged state (exact in the
        linear phase); ``"columns"``: the Jacobian of each x-column at the local state
        (:class:`~chuteflow.dns.columns.ColumnPreconditioner`); ``"auto"``: ``"mean"`` until
        one GMRES solve needs more than ``switch_krylov`` iterations, ``"columns"`` from then on;
        ``"coupled"``: ``"mean"`` until one GMRES solve needs more than ``coupled_krylov``
        iterations, then the Jacobian at the local state with each Fourier mode coupled to
        its neighbours ±1 through the first x-harmonics of the coefficients
        (:class:`~chuteflow.dns.coupled.CoupledPreconditioner`): 4–5.5 times fewer GMRES
        iterations than ``"mean"`` at a ±20 % wave and Δt = 32–64, for three to four times
        the seconds per application (docs/dns.md, *Where a nonlinear step's time goes*);
        where even freshly built coupled blocks leave one GMRES solve above
        ``switch_krylov`` iterations (at Δt ≤ the run's Δt under the step control), the
        columns: at a ±40 … 80 % wave the first harmonics miss 30 % of the coefficients and
        Newton with the coupled blocks alone does not converge. Where the freshly built
        columns need more iterations than the coupled blocks they replaced, back to these,
        and to the columns again only once fresh coupled blocks need more than the columns
        did (at P5's steepening bore, L = 2000, 257 × 96, Δt = 8: 77 GMRES iterations a
        step with the coupled blocks, 259 … 286 with the columns).
    coupled_krylov : int
        GMRES iterations of one solve that make ``"coupled"`` leave the x-mean blocks (at any
        Δt: the coupled build costs about three x-mean builds); 0: the coupled blocks from
        the first step.
    switch_krylov : int
        GMRES iterations of one solve that make ``"auto"`` switch to ``"columns"`` (and
        ``"coupled"``, after a solve right after its blocks were built).
    column_order : {2, 4}
        Order of the x-differences of the column preconditioner
        (:func:`~chuteflow.dns.columns.column_blocks`).
    column_y : {"chebyshev", "fd"}
        Its y-derivatives: the exact Chebyshev matrices (default; a dense block per x point,
        factorised by the periodic block-tridiagonal LU,
        :class:`~chuteflow.dns.cyclic.CyclicBlockLU`) or second-order finite differences on
        the Chebyshev nodes (a banded block per x point, the sparse LU). Continuing a state
        for a span of time under the step control: at P5's mapped bore (L = 2000, 129 × 96)
        96 time units in 31 s against 100 s (Δt 8 held against falling to 4); at P1's
        ±80 % wave (L = 2000, 97 × 64) 200 in 41 s against 37 (docs/dns.md, *The
        block-tridiagonal LU*).
    column_x : {"upwind", "central"}
        How the column preconditioner differences each row's transport of its own field in x:
        first-order upwind (default) or, as its other x-derivatives, central
        (:data:`~chuteflow.dns.columns.X_TRANSPORTS`: at P1's ±41 … 77 % wave on 257 × 96,
        37 GMRES iterations a step against 85).
    columns_max_nx : int or None
        Largest x grid (2M + 1 points) on which the column preconditioner is built; on a
        finer one the coupled blocks serve instead (``"columns"`` and ``"auto"`` included).
        None (default): 257 (:data:`~.columns.NX_LIMIT`, :attr:`columns_nx_limit`). The
        factors grow with nx: with the Chebyshev blocks (block-tridiagonal LU, P5's mapped
        bore, N = 96) 0.66 GB and 5.3 s at nx = 129, 1.28 GB and 8.5 s at 257 (linear in
        nx; the general sparse LU of the same matrix took 2.2 GB and 290 s at 129); with the
        finite differences in y (a ±20 % wave of P1, L = 2000) nx = 97, 129, 257, 513 cost
        0.15, 0.21, 0.48, 1.15 GB and 1.6, 2.3, 5.7, 20 s at N = 64, and 0.33, 0.78, 1.76 GB
        and 4.4, 12, 35 s at N = 96 (nx = 129, 257, 513); the coupled blocks cost 1.0 GB and
        5 s at nx = 257, 1.8 GB and 9 s at 513 (docs/dns.md, *The column preconditioner
        (large amplitude)*). The threshold is on nx alone.
    dt_tol : float
        Time-step control (docs/dns.md, *Solver*): 0 (default) keeps the run's Δt; > 0 lets
        :class:`~chuteflow.dns.DnsSimulation` double and halve Δt by the size of the step's
        change beyond the linear extrapolation in time, relative to the wave
        (:meth:`Stepper.step_error`): halved above ``dt_tol`` (the step is repeated above
        2 ``dt_tol``), doubled below ``dt_tol``/8, between the run's Δt (the step known to be
        accurate: the control only lengthens it where the wave changes slowly, e.g. in the
        co-moving frame) and ``dt_max``.
    dt_max : float
        Largest step of the control; 0: 64 times the run's Δt.
    dt_krylov : int
        Cost side of the control: Δt is not doubled after a step that needed more than this
        many GMRES iterations, and halved after one that needed more than twice this (the
        a0/Δt diagonal the preconditioners share with the Jacobian weakens as Δt grows). With
        the control on, ``"auto"`` switches to the columns only at the run's Δt.
    """

    atol: float = 1e-10
    floor_atol: float = 1e-9
    newton_rtol: float = 1e-3
    max_iter: int = 12
    gmres_rtol: float = 1e-6
    gmres_restart: int = 100
    gmres_maxiter: int = 2
    refresh_after: int = 3
    refresh_krylov: int = 30
    refresh_every: int = 20
    refresh_excess: int = 100
    chord_ratio: float = 0.2
    preconditioner: str = "auto"
    switch_krylov: int = 60
    coupled_krylov: int = 20
    column_order: int = 2
    column_y: str = "chebyshev"
    column_x: str = "upwind"
    columns_max_nx: int | None = None
    dt_tol: float = 0.0
    dt_max: float = 0.0
    dt_krylov: int = 60

    def __post_init__(self):
        if self.preconditioner not in PRECONDITIONERS:
            raise ParameterError(
                f"preconditioner = {self.preconditioner!r}: choose one of {', '.join(PRECONDITIONERS)}"
            )
        if not (0 <= self.newton_rtol < 1):
            raise ParameterError(
                f"newton_rtol = {self.newton_rtol!r}: in [0, 1) (the reduction of the step's "
                "starting residual at which Newton stops; 0 for atol alone)"
            )
        if not (0 < self.atol <= self.floor_atol):
            raise ParameterError(
                f"atol = {self.atol!r}, floor_atol = {self.floor_atol!r}: need 0 < atol <= floor_atol "
                "(the residual accepted at the round-off floor is at most floor_atol)"
            )
        check_column_order(self.column_order)
        check_column_y(self.column_y)
        check_column_x(self.column_x)
        if not (math.isfinite(self.dt_tol) and 0.0 <= self.dt_tol < 1.0):
            raise ParameterError(
                f"dt_tol = {self.dt_tol!r} is outside [0, 1): the time-step control's tolerance "
                "(0 keeps Δt fixed; e.g. 1e-3)"
            )
        if self.columns_max_nx is not None and self.columns_max_nx < 1:
            raise ParameterError(f"columns_max_nx = {self.columns_max_nx!r}: ≥ 1 x points")
        if self.coupled_krylov < 0:
            raise ParameterError(f"coupled_krylov = {self.coupled_krylov!r}: ≥ 0 GMRES iterations")
        if self.refresh_excess < 0:
            raise ParameterError(
                f"refresh_excess = {self.refresh_excess!r}: ≥ 0 GMRES iterations (above the first step's "
                "count since the build, after which a column or coupled preconditioner is rebuilt)"
            )
        if self.dt_krylov < 1:
            raise ParameterError(f"dt_krylov = {self.dt_krylov!r}: ≥ 1 GMRES iterations per step")
        if not (math.isfinite(self.dt_max) and self.dt_max >= 0.0):
            raise ParameterError(f"dt_max = {self.dt_max!r}: ≥ 0 (0: 64 times the run's Δt)")

    @property
    def columns_nx_limit(self) -> int:
        """The largest x grid of the column preconditioner: ``columns_max_nx``, by default
        :data:`~.columns.NX_LIMIT` (257)."""
        if self.columns_max_nx is not None:
            return self.columns_max_nx
        return NX_LIMIT


def step_settings(
    dt_tol: float = 0.0, preconditioner: str = "auto", newton_rtol: float | None = None
) -> NewtonSettings | None:
    """The Newton settings of a run's time-step control, preconditioner and Newton tolerance
    relative to the step (None: the default), checked; None where all are the defaults (the
    solver's own settings, a fixed Δt). The one rule behind ``chuteflow dns --dt-tol
    --preconditioner --newton-rtol`` and :meth:`~chuteflow.dns.waves.WaveMapSettings.newton`."""
    settings = NewtonSettings(dt_tol=dt_tol, preconditioner=preconditioner)
    if newton_rtol is not None:
        settings = replace(settings, newton_rtol=newton_rtol)
    return None if settings == NewtonSettings() else settings


@dataclass(frozen=True)
class StepInfo:
    """What one step took: Newton iterations, GMRES iterations, final residual (max-norm of the
    scaled residual) and the tolerance it was solved to (max(``atol``, ``newton_rtol`` × the
    starting residual), :class:`NewtonSettings`)."""

    newton: int
    krylov: int
    residual: float
    tolerance: float = 0.0


@dataclass(frozen=True)
class MeanBlocks:
    """The x-mean preconditioner: the inverses of the Jacobian's per-mode blocks at the
    x-mean state (:meth:`Discretisation.factorise`), with the same ``apply`` as
    :class:`~chuteflow.dns.columns.ColumnPreconditioner`."""

    disc: Discretisation
    inverses: np.ndarray

    def apply(self, R: np.ndarray) -> np.ndarray:
        return self.disc.precondition(self.inverses, R)


class Stepper:
    """BDF2 time stepping of a :class:`Discretisation` (BDF1 for a first step without history).

    Parameters
    ----------
    disc : Discretisation
        Grid and equations.
    settings : NewtonSettings
        Solver tolerances.
    """

    def __init__(self, disc: Discretisation, settings: NewtonSettings | None = None):
        self.disc = disc
        self.settings = settings or NewtonSettings()
        self._lus: MeanBlocks | ColumnPreconditioner | CoupledPreconditioner | None = None
        self._lu_key: tuple | None = None
        self.factorisations = 0
        self._age = 0
        self._base_krylov: int | None = None
        self._base_step: int | None = None  # GMRES iterations of the first step after the build
        self._excess = 0  # … and those of the later steps above it, summed (refresh_excess)
        #: The preconditioner in use: ``"mean"``, ``"coupled"`` or ``"columns"`` (from the
        #: start as ``preconditioner`` names it, ``"coupled"`` only with ``coupled_krylov=0``;
        #: then as :meth:`_escalation` decides).
        pre = self.settings.preconditioner
        self.kind = "mean"
        if disc.modes >= 1 and pre == "columns":
            self.use("columns")
        elif disc.modes >= 1 and pre == "coupled" and self.settings.coupled_krylov == 0:
            self.kind = "coupled"
        #: ``"auto"`` switches to the columns only at steps Δt ≤ this (set by the step
        #: control of :class:`~chuteflow.dns.DnsSimulation` to the run's Δt).
        self.switch_dt = math.inf
        #: GMRES iterations of the first solve after the last build of the coupled blocks
        #: and of the columns where ``"coupled"`` went from one to the other
        #: (:meth:`_escalation`).
        self.fresh_krylov: dict[str, int] = {}
        self._built: tuple | None = None

    @property
    def columns_fit(self) -> bool:
        """Whether the grid is coarse enough for the column preconditioner
        (``NewtonSettings.columns_nx_limit``: its factors grow with nx)."""
        return 2 * self.disc.modes + 1 <= self.settings.columns_nx_limit

    def use(self, kind: str) -> None:
        """Go over to the preconditioner ``kind`` (``"columns"`` becomes ``"coupled"`` on a
        grid too fine for it, :attr:`columns_fit`); rebuilt at the next step."""
        self.kind = "coupled" if kind == "columns" and not self.columns_fit else kind
        self._lus = None

    @property
    def columns(self) -> bool:
        """Whether the column preconditioner is in use."""
        return self.kind == "columns"

    @property
    def coupled(self) -> bool:
        """Whether the mode-coupling preconditioner is in use."""
        return self.kind == "coupled"

    def _escalation(self, krylov: int, dt: float) -> str | None:
        """The preconditioner to go over to after a GMRES solve of ``krylov`` iterations at the
        step ``dt`` (None: keep this one). ``"auto"``: the x-mean blocks give way to the
        columns above ``switch_krylov``; ``"coupled"``: to the coupled blocks above
        ``coupled_krylov``, and these, where freshly built they still need more than
        ``switch_krylov`` (a wave of ±40 % and more, whose coefficients need harmonics
        4–8), to the columns. The columns only at Δt ≤ :attr:`switch_dt`, and only on a grid
        they fit (:attr:`columns_fit`; on a finer grid :meth:`use` takes the coupled blocks)."""
        s = self.settings
        if not self.disc.modes:
            return None
        at_run_dt = dt <= self.switch_dt * (1 + 1e-12)
        if self.kind == "mean":
            # the x-mean no longer describes the Jacobian
            if s.preconditioner == "auto" and krylov > s.switch_krylov and at_run_dt:
                return "columns"  # (the coupled blocks where the grid is too fine: use)
            if s.preconditioner == "coupled" and krylov > s.coupled_krylov:
                return "coupled"
        fresh = self._age <= 1 and self._base_krylov is None
        # (where the columns do not fit, the coupled blocks are already the last resort)
        if self.kind == "coupled" and fresh and krylov > s.switch_krylov and at_run_dt and self.columns_fit:
            if krylov <= self.fresh_krylov.get("columns", 0):
                return None  # the columns needed more when last built
            self.fresh_krylov["coupled"] = krylov
            return "columns"
        if self.kind == "columns" and fresh and krylov > self.fresh_krylov.get("coupled", math.inf):
            # the columns serve worse than the coupled blocks they replaced: back to these
            self.fresh_krylov["columns"] = krylov
            return "coupled"
        return None

    def reset(self) -> None:
        """Forget the preconditioner (it is rebuilt at the next step)."""
        self._lus = None

    def snapshot(self) -> dict[str, np.ndarray]:
        """What the next steps depend on besides the fields, as arrays (saved with a
        checkpoint, :class:`~chuteflow.dns.simulation.DnsState`): the kind of preconditioner,
        the state, history and step it was built at, its age and the memories of
        :meth:`_escalation`. Newton stops within ``newton_rtol`` of its starting residual, so
        its iterates depend on the preconditioner; :meth:`restore` rebuilds the same one, and
        a resumed run takes the same steps as the uninterrupted one."""
        fresh = self.fresh_krylov
        out = {
            "settings": np.array(repr(self.settings)),
            "kind": np.array(self.kind),
            "counters": np.array(
                [
                    self._age,
                    -1 if self._base_krylov is None else self._base_krylov,
                    self.factorisations,
                    fresh.get("coupled", -1),
                    fresh.get("columns", -1),
                    self._excess,
                    -1 if self._base_step is None else self._base_step,
                ],
                dtype=float,
            ),
        }
        if self._lus is not None and self._built is not None:
            C, h0, h1, dt, bdf = self._built
            out.update(C=C, h0=h0, h1=h1, step=np.array([dt, *bdf]))
        return out

    def restore(self, snap: dict[str, np.ndarray]) -> None:
        """Return to a :meth:`snapshot` of a stepper on the same grid with the same settings
        (the preconditioner rebuilt from the state it was built at); a snapshot of another
        grid, or of other settings (a run continued with another ``--preconditioner``), is
        ignored: the stepper starts afresh."""
        if "C" in snap and snap["C"].shape != self.disc.shape:
            return
        if str(snap.get("settings", "")) != repr(self.settings):
            return
        self.kind = str(snap["kind"])
        self._lus = None
        if "C" in snap:
            dt, *bdf = (float(v) for v in snap["step"])
            self._factor(snap["C"], dt, tuple(bdf), (snap["h0"], snap["h1"]))
        age, base, fact, coupled, columns, *more = (int(v) for v in snap["counters"])
        self._age, self.factorisations = age, fact
        # (checkpoints before refresh_excess have neither)
        self._excess = more[0] if more else 0
        self._base_step = more[1] if len(more) > 1 and more[1] >= 0 else None
        self._base_krylov = None if base < 0 else base
        self.fresh_krylov = {k: v for k, v in (("coupled", coupled), ("columns", columns)) if v >= 0}

    def physical(self, C: np.ndarray) -> tuple[np.ndarray, ...]:
        """(ν, u, v, T) on the padded grid: one time level of the history."""
        d = self.disc
        return (np.exp(d.to_physical(C[0])), d.to_physical(C[1]), d.to_physical(C[2]), d.to_physical(C[3]))

    def _factor(self, C, dt, bdf, history):
        # what the build read (snapshot: a resumed run rebuilds the same preconditioner)
        self._built = (np.array(C), np.array(history[0]), np.array(history[1]), float(dt), tuple(bdf))
        if self.kind == "coupled":
            self._lus = CoupledPreconditioner.build(self.disc, C, history, dt, bdf)
        elif self.kind == "columns":
            self._lus = ColumnPreconditioner.build(
                self.disc,
                C,
                history,
                dt,
                bdf,
                self.settings.column_order,
                self.settings.column_y,
                self.settings.column_x,
            )
        else:
            self._lus = MeanBlocks(self.disc, self.disc.factorise(self.disc.linear_blocks(C), dt, bdf[0]))
        self._lu_key = (dt, bdf[0])
        self._base_krylov = self._base_step = None
        self._excess = 0
        self.factorisations += 1
        self._age = 0

    def _key_ok(self, dt: float, bdf) -> bool:
        """Whether the preconditioner's a0/Δt still serves: the same (Δt, a0), or, with the
        step control on, a0/Δt within 25 % of it (after a doubling of Δt the variable-step
        step's a0/Δt and the next constant step's differ by 10 %: one factorisation, not two)."""
        key = self._lu_key
        assert key is not None
        if _close(key, (dt, bdf[0])):
            return True
        if self.settings.dt_tol > 0:
            old, new = key[1] / key[0], bdf[0] / dt
            return abs(new - old) <= 0.25 * old
        return False

    def step(
        self,
        C_now: np.ndarray,
        history: tuple,
        dt: float,
        *,
        first: bool = False,
        guess: np.ndarray | None = None,
        ratio: float = 1.0,
    ):
        """Solve one implicit step from ``C_now``; returns (C_next, :class:`StepInfo`).

        ``history`` = (X^n, X^{n−1}) as from :meth:`physical`; with ``first`` a BDF1 step,
        otherwise BDF2 with step ratio ``ratio`` = Δt_n / Δt_{n−1} (variable-step
        coefficients). ``guess`` is Newton's starting point (default ``C_now``; the caller's
        extrapolation in time saves Newton iterations). On convergence the x-mean of s is
        shifted by the constant δ that makes the discrete total mass
        (:meth:`Discretisation.total_mass`) satisfy the BDF relation exactly; δ is of the
        order of the Newton residual (the mass rows conserve mass up to it, see
        :meth:`Discretisation.mass_source`), so this changes the residual by less than the
        tolerance and makes the conservation hold to round-off.
        Raises :class:`~chuteflow.errors.ConvergenceError` if Newton does not converge.
        Floating-point overflow in a diverging iterate is not reported as a warning: the
        iterate's non-finite residual is what fails the step (and the caller's control
        repeats it with a shorter Δt).
        """
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            out = self._newton(C_now, history, dt, first=first, guess=guess, ratio=ratio)
        self._count_excess(out[1].krylov)
        return out

    def _count_excess(self, krylov: int) -> None:
        """After a step of ``krylov`` GMRES iterations: a dear preconditioner (columns,
        coupled blocks) is dropped, to be rebuilt at the next step's state, once the steps
        since its build have cost more than ``refresh_excess`` iterations above the first
        of them."""
        if self.kind == "mean" or self._lus is None:
            return
        if self._base_step is None:
            self._base_step = krylov
            return
        # (signed: steps that wander about the first one cancel, a drift adds up)
        self._excess += krylov - self._base_step
        if self._excess > self.settings.refresh_excess:
            self.reset()

    def _newton(
        self,
        C_now: np.ndarray,
        history: tuple,
        dt: float,
        *,
        first: bool,
        guess: np.ndarray | None,
        ratio: float,
    ):

        d, s = self.disc, self.settings
        w = float(ratio)
        bdf = BDF1 if first else ((1 + 2 * w) / (1 + w), -(1 + w), w * w / (1 + w))
        if first is False and w == 1.0:
            bdf = BDF2
        if self._lus is None or self._lu_key is None or not self._key_ok(dt, bdf):
            self._factor(C_now, dt, bdf, history)
        self._age += 1
        C = (C_now if guess is None else guess).copy()
        z = d.pack(C)

        def F(zz):
            return d.pack(d.residual(d.unpack(zz), history, dt, bdf))

        r = F(z)
        krylov = 0
        rn_old = np.inf
        seen: list[float] = []
        # the tolerance of this step (NewtonSettings.newton_rtol): relative to the residual of
        # the extrapolated guess where that is looser than atol (without a guess the starting
        # residual is the whole step's, not its change beyond the extrapolation: atol alone)
        rel = s.newton_rtol if guess is not None else 0.0
        tol = max(s.atol, rel * float(np.max(np.abs(r))))
        floor = max(s.floor_atol, tol)
        for it in range(1, s.max_iter + 1):
            rn = float(np.max(np.abs(r)))
            seen.append(rn)
            lus = self._lus
            if atol_floor_reached(seen, tol, floor):
                return self._conserve(d.unpack(z), history, bdf), StepInfo(it - 1, krylov, rn, tol)

            def prec(v, lus=lus):
                return d.pack(lus.apply(d.unpack(v)))

            if rn < tol:
                if it == 1:
                    # a guess within the tolerance still gets one chord step: in the linear
                    # phase it is exact, and the tolerance is absolute (a small wave would
                    # otherwise carry the guess's error)
                    z_try = z - prec(r)
                    r_try = F(z_try)
                    rn_try = float(np.max(np.abs(r_try)))
                    if rn_try < rn:
                        z, rn = z_try, rn_try
                    return self._conserve(d.unpack(z), history, bdf), StepInfo(1, krylov, rn, tol)
                return self._conserve(d.unpack(z), history, bdf), StepInfo(it - 1, krylov, rn, tol)

            if rn < s.chord_ratio * rn_old or it == 1:
                # chord step: the preconditioner as the Jacobian (exact in the linear phase)
                z_try = z - prec(r)
                r_try = F(z_try)
                rn_try = float(np.max(np.abs(r_try)))
                if np.isfinite(rn_try) and rn_try < s.chord_ratio * rn:
                    z, r, rn_old = z_try, r_try, rn
                    continue
            nz = np.linalg.norm(z)

            def jv(v, z=z, r=r, nz=nz):
                nv = np.linalg.norm(v)
                if nv == 0:
                    return np.zeros_like(v)
                eps = 1e-7 * (1.0 + nz) / nv
                return (F(z + eps * v) - r) / eps

            n = z.size
            A = LinearOperator((n, n), matvec=lambda v: jv(prec(v)))
            count = [0]

            def cb(_, count=count):
                count[0] += 1

            # inexact Newton: ask GMRES for the reduction that reaches the tolerance
            rtol = min(max(0.3 * tol / rn, s.gmres_rtol), 0.1)
            y, _info = gmres(
                A,
                -r,
                rtol=rtol,
                atol=0.0,
                restart=s.gmres_restart,
                maxiter=s.gmres_maxiter,
                callback=cb,
                callback_type="pr_norm",
            )
            krylov += count[0]
            z = z + prec(y)
            r, rn_old = F(z), rn
            if not np.all(np.isfinite(r)):
                break
            # a refresh for GMRES's sake at most every `refresh_every` steps: at large
            # amplitude the x-mean preconditioner misses the mode coupling however fresh it is
            nxt = self._escalation(count[0], dt)
            if nxt is not None:
                self.use(nxt)
                self._factor(d.unpack(z), dt, bdf, history)
                continue
            if self._base_krylov is None:
                self._base_krylov = count[0]
            # rebuilt for GMRES's sake at most every refresh_every steps, the dear preconditioners
            # where a solve needs twice what the first after their build needed (and, at the
            # step's end, where the steps since the build have cost about a build more than
            # the first: refresh_excess, _count_excess)
            dear = self.kind != "mean"
            limit = max(s.refresh_krylov, 2 * self._base_krylov) if dear else s.refresh_krylov
            if it > s.refresh_after or (count[0] > limit and self._age >= s.refresh_every):
                self._factor(d.unpack(z), dt, bdf, history)
        rn = float(np.max(np.abs(r)))
        if rn < floor:  # at tol, or at the round-off floor below floor_atol
            return self._conserve(d.unpack(z), history, bdf), StepInfo(s.max_iter, krylov, rn, tol)
        self._lus = None
        self.fresh_krylov.clear()  # (what served before is no guide where Newton failed)
        raise ConvergenceError(
            f"implicit step (Δt = {dt:g}): Newton residual {rn:.2e} after {s.max_iter} iterations"
        )

    @staticmethod
    def step_error(C_new: np.ndarray, guess: np.ndarray) -> float:
        """The step's error indicator: the change beyond the linear extrapolation in time.

        ``guess`` = C^n + ω (C^n − C^{n−1}) (Newton's starting point), so C^{n+1} − guess ≈
        (1 + ω) Δt² ∂_t²C / 2 — one order below BDF2's local error (∝ Δt³ ∂_t³C), a cautious
        indicator. Measured on the density wave: the modes m ≥ 1 of ln ν weighted by
        ν̄_j = exp(ŝ_0(y_j)), ‖ν̄ ΔĈ_s‖₂ / ‖ν̄ Ĉ_s‖₂ (unweighted, the transported noise of the
        dilute top at ν ~ 1e-9 held Δt at a twentieth of the run's; docs/dns.md); 0 without
        modes.
        """
        if C_new.shape[-1] < 2:
            return 0.0
        nubar = np.exp(C_new[0, :, 0].real)[:, None]
        num = float(np.linalg.norm(nubar * (C_new[0, :, 1:] - guess[0, :, 1:])))
        den = float(np.linalg.norm(nubar * C_new[0, :, 1:]))
        return num / max(den, 1e-300)

    def _conserve(self, C: np.ndarray, history: tuple, bdf) -> np.ndarray:
        d = self.disc
        a0, a1, a2 = bdf
        target = a1 * d.total_mass(history[0][0], history[0][3][-1])
        if a2:
            target += a2 * d.total_mass(history[1][0], history[1][3][-1])
        target = -target / a0
        nu = np.exp(d.to_physical(C[0]))
        T_top = d.to_physical(C[3, -1])
        delta = math.log(target / d.total_mass(nu, T_top))
        out = C.copy()
        out[0, :, 0] += delta
        return out


def atol_floor_reached(seen: list[float], atol: float, floor_atol: float) -> bool:
    """Whether Newton's residuals ``seen`` (max-norms, one per iteration) have reached the
    round-off floor (:attr:`NewtonSettings.floor_atol`): above ``atol`` but below
    ``floor_atol`` and not halved over the last two iterations."""
    if len(seen) < 3:
        return False
    rn = seen[-1]
    return atol <= rn < floor_atol and rn > 0.5 * seen[-3]


def _close(a: tuple, b: tuple) -> bool:
    return all(abs(x - y) <= 1e-12 * abs(y) for x, y in zip(a, b))

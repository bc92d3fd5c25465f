"""Existence of the steady flow, decided by shooting on the floor velocity u0(0) (paper §3).

The paper finds the steady flow by shooting: given ν0(0) and a trial slip velocity u0(0),
the floor conditions (eqs 3.11, 3.12) fix T0(0) and T0'(0), the steady equations are
integrated upwards, and u0(0) is adjusted until T0' = 0 where ν0 reaches ``nu_top``
(eq. 3.13). Here that integration is used as a cheap, loose-tolerance *scan* that decides
whether a flow exists and, if so, gives the Chebyshev–Newton solver of
:mod:`chuteflow.steady.newton` a starting profile.

Each trial is classified by the direction in which it misses the top condition:

* **hot** (+): ν0 reaches ``nu_top`` with T0' > 0, or the layer never thins out (T0 grows,
  ν0 does not reach ``nu_top`` below ``y_cap``);
* **cold** (−): ν0 reaches ``nu_top`` with T0' ≤ 0, or T0 → 0, or ν0 → ν_m (the layer
  collapses or packs).

Large u0(0) heats the layer, small u0(0) lets it cool, so the physical flow is the first
sign change hot → cold coming down from large u0(0) (docs/errata.md, numerical note on shooting:
the smallness of |T0'(y_max)| alone is also met by a thin cold layer as u0(0) → 0, whose
trajectories are not followed). No such sign change over the admissible range of u0(0) is a
verdict: every trial hot (the layer cannot be kept cold enough to thin out: at small θ the
thin cold layer has T0'(y_max) > 0), the angle is too small; every trial cold (the layer
collapses or packs at any floor velocity), the angle is too large. A hot → cold change
across which no trial reaches ``nu_top`` is a separatrix (a jump of the miss, not a root:
e.g. a band that packs to ν_m and then either collapses or heats up), not a solution.
A solution thinner than one diameter (§3.2) is reported as such.

The steady ODEs are not typed again here: ν0' follows from the y-momentum residual and T0''
from the energy residual of the derived equations (:mod:`chuteflow.equations`; both are
affine in that highest derivative, so the residual with it set to zero and its coefficient
give it exactly), u0' = tanθ p/μ is the integrated x-momentum balance eq. (3.7) as used by
the Newton solver — derived symbolically once and generated as scalar code
(:mod:`chuteflow.steady._scalar_ode`) — and the floor values come from the floor_x and
floor_energy residuals (eqs 2.9, 2.10) of :func:`chuteflow.equations.compiled_equations`, with
the closures' partials of :meth:`ChuteModel.scalar_evaluator`.

Modules: :mod:`.ode` (the system and the floor values), :mod:`.trajectory` (a trial
integration, shared by the integrators), :mod:`.dopri_compiled` and :mod:`.dopri_scipy` (the
two integrators), :mod:`.shot` (one classified trial), :mod:`.verdict` (the scan).
"""

from .dopri_scipy import integrate
from .ode import SteadyODE
from .shot import Shot, shoot
from .verdict import U_RANGE, ExistenceVerdict, steady_existence

__all__ = ["ExistenceVerdict", "Shot", "SteadyODE", "U_RANGE", "integrate", "shoot", "steady_existence"]

"""Point functions used by the sweep tests (importable by test subprocesses too)."""

from __future__ import annotations

import time

from chuteflow.errors import ConvergenceError
from chuteflow.sweep import PointFunction, Variable, register_point_function

#: A cheap grid inside the existence region of φ = 0.05 (steady solves of ~20 ms).
THETA = (15.0, 16.0)
NU0 = (0.04, 0.05, 0.06, 0.07, 0.08, 0.09)


@register_point_function
class Slow(PointFunction):
    """Sleeps, so that a sweep lasts long enough to be killed mid-run."""

    name = "test_slow"
    version = "1"
    defaults = {"seconds": 0.0}
    variables = (Variable("slept", "s", "seconds slept"),)

    def compute(self, flow, point):
        time.sleep(float(self.options["seconds"]))
        return {"slept": float(self.options["seconds"])}


@register_point_function
class Faulty(PointFunction):
    """Fails in chosen ways at chosen ν0 (to test the per-point status)."""

    name = "test_faulty"
    version = "1"
    defaults = {"diverge_at": -1.0, "crash_at": -1.0, "undeclared_at": -1.0}
    variables = (Variable("twice_h", "sigma", "2 h"),)

    def compute(self, flow, point):
        o = self.options
        if abs(point.nu0 - o["diverge_at"]) < 1e-12:
            raise ConvergenceError("test: did not converge on purpose")
        if abs(point.nu0 - o["crash_at"]) < 1e-12:
            raise ZeroDivisionError("test: crashed on purpose")
        if abs(point.nu0 - o["undeclared_at"]) < 1e-12:
            return {"twice_h": 2 * flow.h, "not_declared": 1.0}
        return {"twice_h": 2 * flow.h}

"""Numbers of docs/closures.md that `chuteflow reproduce --full --stage closures` does not make.

* ``gd_without_mu``: ``garzo_dufty`` with κ_h = 0 (a diagnostic closure, registered here
  only) at the paper's points P1–P5, Q1–Q3 — h, Q0, α1, α2 (long-wave) and α2z
  (transverse), computed as the closures stage does;
* ``garzo_dufty`` itself at the eight points (steady flow or not);
* the κ_h-scaling: ``garzo_dufty`` with κ_h × s at P1 (s = 0, 0.02, 0.05, 0.1, 0.3) and at
  the dense (16°, ν0(0) = 0.2) (s = 0, 1): h.

Run: ``PYTHONPATH=src python scripts/closures_numbers.py`` (a few minutes on one core).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import ClassVar

from chuteflow.closures import ChuteModel, GarzoDuftyClosure
from chuteflow.closures.kinetic import register_transport
from chuteflow.errors import ChuteflowError
from chuteflow.papers.mitarai2004.points import POINTS
from chuteflow.papers.mitarai2004.stages.closures import _point
from chuteflow.steady import solve_steady


@register_transport
@dataclass(frozen=True)
class ScaledMuGarzoDufty(GarzoDuftyClosure):
    """garzo_dufty with its κ_h multiplied by ``s`` (s = 0: ``gd_without_mu``)."""

    name: ClassVar[str] = "gd_scaled_mu"
    s: float = 0.0

    def transport(self, f, T, e):
        out = super().transport(f, T, e)
        out["kappa_h"] = self.s * out["kappa_h"] if self.s else 0
        return out


def _h(theta, nu0, s):
    model = ChuteModel(transport={"name": "gd_scaled_mu", "s": s})
    try:
        return f"{solve_steady(theta=theta, nu0=nu0, model=model, strict=True).h:.4g}"
    except ChuteflowError as exc:
        return "no steady flow (" + str(exc).split(":")[0] + ")"


def main() -> None:
    warnings.simplefilter("ignore", RuntimeWarning)
    print("| point | closure | h | Q0 | Im α1 | Re α2 | long-wave | α2z |")
    for p in POINTS.values():
        r = _point({"transport": {"name": "gd_scaled_mu", "s": 0.0}}, p)
        if "error" in r:
            print(f"| {p.name} | gd_without_mu | {r['error']} |")
            continue
        verdict = "unstable" if r.get("unstable") else "stable"
        print(
            f"| {p.name} | gd_without_mu | {r['h']:.4g} | {r['Q']:.4g} | {r.get('alpha1', float('nan')):.4g} "
            f"| {r.get('alpha2', float('nan')):.4g} | {verdict} | {r.get('alpha2z', float('nan')):.4g} |"
            f"  (α2 conv {r.get('alpha2_conv', float('nan')):.1e},"
            f" α2z conv {r.get('alpha2z_conv', float('nan')):.1e})"
        )
    for p in POINTS.values():
        model = ChuteModel(transport="garzo_dufty", roughness=p.roughness)
        try:
            h = solve_steady(theta=p.theta, nu0=p.nu0, model=model, strict=True).h
            print(f"garzo_dufty at {p.name}: h = {h:.4g}")
        except ChuteflowError as exc:
            print(f"garzo_dufty at {p.name}: no steady flow ({str(exc)[:100]})")
    for s in (0.0, 0.02, 0.05, 0.1, 0.3):
        print(f"P1, κ_h × {s}: h = {_h(16.0, 0.05, s)}")
    for s in (0.0, 1.0):
        print(f"(16°, 0.2), κ_h × {s}: h = {_h(16.0, 0.2, s)}")


if __name__ == "__main__":
    main()

"""chuteflow: hydrodynamic stability of rapid granular chute flows.

Reproduces and extends Mitarai & Nakanishi, "Linear stability analysis of rapid
granular flow down a slope and density wave formation" (kinetic theory of Lun et
al. 1984, Johnson–Jackson floor conditions, Chebyshev collocation).

The package namespace is deliberately light: importing :mod:`chuteflow` loads no
numerics. ``ChuteModel`` and ``solve_steady`` are resolved on first access.
"""

from __future__ import annotations

from importlib import import_module

from ._version import __version__

#: Public names resolved lazily: name -> module that defines it.
_LAZY = {
    "ChuteModel": "chuteflow.closures",
    "solve_steady": "chuteflow.steady",
    "ChuteflowError": "chuteflow.errors",
    "ParameterError": "chuteflow.errors",
    "NoSteadyFlowError": "chuteflow.errors",
    "ConvergenceError": "chuteflow.errors",
}

__all__ = ["__version__", *_LAZY]


def __getattr__(name: str):
    """Import public names on first use (PEP 562)."""
    try:
        module = _LAZY[name]
    except KeyError:
        raise AttributeError(f"module 'chuteflow' has no attribute {name!r}") from None
    value = getattr(import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))

"""Reproduction stages of Mitarai & Nakanishi (2004), one module per part of the paper.

Each module registers its stage(s) with :func:`chuteflow.report.register_stage` when
imported. To add a stage, write ``stages/NAME.py`` and add ``"NAME"`` to
:data:`STAGE_MODULES`. A module that fails to import does not stop the others: its
error is kept in :data:`IMPORT_ERRORS` and ``chuteflow reproduce`` reports it as a
failed checkpoint.
"""

from __future__ import annotations

from importlib import import_module

#: Stage modules, imported in this order (run order is each stage's ``order``).
STAGE_MODULES: tuple[str, ...] = (
    "steady",
    "stability",
    "diagrams",
    "reduced",
    "waves",
    "transverse",
    "dns",
    "spatial",
    "closures",
)

#: Module name -> exception raised while importing it.
IMPORT_ERRORS: dict[str, BaseException] = {}

for _name in STAGE_MODULES:
    try:
        import_module(f"{__name__}.{_name}")
    except Exception as _exc:  # reported by the runner
        IMPORT_ERRORS[_name] = _exc

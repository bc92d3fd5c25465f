"""Reproduction report: checkpoints against the paper, figures, and the stage runner.

- :class:`Checkpoint`, :class:`Figure`, :class:`Report` (``report.py``): content and
  rendering to ``report.md`` / ``report.html`` / ``checkpoints.json``.
- :func:`register_stage`, :class:`StageContext` (``registry.py``): how a stage plugs in.
- :func:`run_reproduce` (``reproduce.py``): runs the stages (``chuteflow reproduce``).
"""

from .registry import (
    Stage,
    StageContext,
    get_stage,
    isolated_registry,
    load_stages,
    register_stage,
    registered_stages,
    select_stages,
)
from .report import Checkpoint, Figure, Report, Section
from .reproduce import StageProgress, run_reproduce, summary_table

__all__ = [
    "Checkpoint",
    "Figure",
    "Report",
    "Section",
    "Stage",
    "StageContext",
    "StageProgress",
    "register_stage",
    "registered_stages",
    "get_stage",
    "select_stages",
    "load_stages",
    "isolated_registry",
    "run_reproduce",
    "summary_table",
]

"""Reproduced papers, one subpackage each, kept apart from the general library.

A paper package ``chuteflow.papers.NAME`` holds everything specific to one publication: its
named parameter points, the defaults of its figures, the checks of its statements and its
reproduction stages. Its ``stages`` subpackage registers the stages with
:func:`chuteflow.report.register_stage` when imported and keeps the errors of stage modules
that failed to import in ``IMPORT_ERRORS``. ``chuteflow reproduce`` loads the papers named
with ``--paper`` (default :data:`DEFAULT_PAPERS`) through :func:`load_paper`.

A second paper is a sibling package: add its name to :data:`PAPERS`.

Layer: a paper package sits at the level of :mod:`chuteflow.figures` and
:mod:`chuteflow.report` and may import everything below; nothing in the library imports it
except the stage discovery of :mod:`chuteflow.report` and the command line.
"""
from __future__ import annotations

from importlib import import_module
from types import ModuleType

from ..errors import ParameterError

__all__ = ["PAPERS", "DEFAULT_PAPERS", "load_paper", "import_errors"]

#: Paper packages: name → one-line citation.
PAPERS: dict[str, str] = {
    "mitarai2004": "N. Mitarai & H. Nakanishi, linear stability analysis of rapid granular "
                   "flow down a slope and density wave formation, J. Fluid Mech. (2004)",
}

#: Papers reproduced when none is named.
DEFAULT_PAPERS: tuple[str, ...] = ("mitarai2004",)


def load_paper(name: str) -> ModuleType:
    """Import ``chuteflow.papers.NAME.stages`` (registering its stages) and return it.

    Raises :class:`~chuteflow.errors.ParameterError` for a name not in :data:`PAPERS`.
    """
    if name not in PAPERS:
        raise ParameterError(f"paper: unknown paper {name!r} (available: "
                             f"{', '.join(PAPERS)})")
    return import_module(f"{__name__}.{name}.stages")


def import_errors(name: str) -> dict[str, BaseException]:
    """Stage modules of paper ``name`` that failed to import: module → exception."""
    return dict(getattr(load_paper(name), "IMPORT_ERRORS", {}))

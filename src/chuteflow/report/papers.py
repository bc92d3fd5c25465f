"""The catalogue of reproduced papers: name → package ``chuteflow.papers.NAME``.

Each reproduced paper is a plug-in package ``chuteflow.papers.NAME`` (one level above this
one: it imports :mod:`chuteflow.report` to register its stages, and nothing here imports it
by name at import time). ``chuteflow reproduce`` loads the papers named with ``--paper``
(default :data:`DEFAULT_PAPERS`) through :func:`load_paper`, which imports the package's
``stages`` subpackage by its module path, as a plug-in loader does. A second paper is a
sibling package plus one entry in :data:`PAPERS` (or :func:`register_paper` at run time).
"""

from __future__ import annotations

from importlib import import_module
from types import ModuleType

from ..errors import ParameterError

__all__ = ["PAPERS", "DEFAULT_PAPERS", "PACKAGE", "load_paper", "import_errors", "register_paper"]

#: The package holding the paper plug-ins.
PACKAGE = "chuteflow.papers"

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
        raise ParameterError(f"paper: unknown paper {name!r} (available: {', '.join(PAPERS)})")
    return import_module(f"{PACKAGE}.{name}.stages")


def import_errors(name: str) -> dict[str, BaseException]:
    """Stage modules of paper ``name`` that failed to import: module → exception."""
    return dict(getattr(load_paper(name), "IMPORT_ERRORS", {}))


def register_paper(name: str, citation: str) -> None:
    """Add paper ``name`` (a package ``chuteflow.papers.NAME`` with a ``stages`` subpackage)
    to the catalogue."""
    PAPERS[name] = citation

"""Reproduced papers, one subpackage each, kept apart from the general library.

A paper package ``chuteflow.papers.NAME`` holds everything specific to one publication: its
named parameter points, the defaults of its figures, the checks of its statements and its
reproduction stages. Its ``stages`` subpackage registers the stages with
:func:`chuteflow.report.register_stage` when imported and keeps the errors of stage modules
that failed to import in ``IMPORT_ERRORS``. ``chuteflow reproduce`` loads the papers named
with ``--paper`` (default :data:`DEFAULT_PAPERS`) through :func:`load_paper`.

A second paper is a sibling package: add its name to :data:`PAPERS`.

Layer: a paper package sits above :mod:`chuteflow.figures` and
:mod:`chuteflow.report` and may import everything below; nothing in the library imports it
except the stage discovery of :mod:`chuteflow.report` and the command line.

The catalogue of papers (:data:`PAPERS`, :func:`load_paper`) lives in
:mod:`chuteflow.report.papers` and is re-exported here.
"""

from __future__ import annotations

from ..report.papers import DEFAULT_PAPERS, PAPERS, import_errors, load_paper, register_paper

__all__ = ["PAPERS", "DEFAULT_PAPERS", "load_paper", "import_errors", "register_paper"]

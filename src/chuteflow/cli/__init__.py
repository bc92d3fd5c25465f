"""Command-line interface: ``chuteflow`` (also ``python -m chuteflow``).

Each command lives in its own module, which adds itself to :data:`app` with
``@app.command()``. To add commands, write ``cli/NAME.py`` and add one import line
below. Modules should import numerics inside the command function, so that
``chuteflow --help`` stays fast.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Sequence

# -- command modules: one line each ------------------------------------------------------
from . import (
    diagram,  # noqa: F401
    dns,  # noqa: F401
    reduced,  # noqa: F401
    reproduce,  # noqa: F401
    stability,  # noqa: F401
    steady,  # noqa: F401
    transverse,  # noqa: F401
)
from ._app import EXIT_USER_ERROR, USER_ERRORS, app, report_user_error

__all__ = ["app", "main"]


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``chuteflow`` script; returns the exit code.

    User errors (:class:`~chuteflow.errors.ChuteflowError`, ``ValueError`` from
    parameter validation) print one ``error: ...`` line on standard error and give exit
    code 2, without a traceback (``CHUTEFLOW_DEBUG=1`` shows it).
    """
    try:
        app(args=list(argv) if argv is not None else None, prog_name="chuteflow")
    except SystemExit as exc:
        code = exc.code
        return code if isinstance(code, int) else (0 if code is None else 1)
    except USER_ERRORS as exc:
        if os.environ.get("CHUTEFLOW_DEBUG"):
            raise
        report_user_error(exc)
        return EXIT_USER_ERROR
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

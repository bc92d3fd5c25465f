"""Command-line interface: ``chuteflow`` (also ``python -m chuteflow``).

Each command lives in its own module, which adds itself to :data:`app` with
``@app.command()``. To add commands, write ``cli/NAME.py`` and add its name to
:data:`COMMANDS`. Modules should import numerics inside the command function, so that
``chuteflow --help`` stays fast.

The typer application is built on first use (``from chuteflow.cli import app`` or
:func:`main`): a plain ``chuteflow steady`` call is answered without it
(:mod:`chuteflow.cli._fast`), since typer and rich cost more to import than the solve.
"""

from __future__ import annotations

import importlib
import os
import sys
from collections.abc import Sequence
from typing import Any

from ._fast import fast_main

__all__ = ["COMMANDS", "app", "main"]

#: The command modules, one name each (imported, in this order, when the app is built).
COMMANDS = (
    "diagram",
    "dns",
    "reduced",
    "reproduce",
    "spatial",
    "stability",
    "steady",
    "transverse",
)


def _application() -> Any:
    for name in COMMANDS:
        importlib.import_module(f"{__name__}.{name}")
    return importlib.import_module(f"{__name__}._app")


def __getattr__(name: str) -> Any:
    if name == "app":
        return _application().app
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``chuteflow`` script; returns the exit code.

    User errors (:class:`~chuteflow.errors.ChuteflowError`, ``ValueError`` from
    parameter validation) print one ``error: ...`` line on standard error and give exit
    code 2, without a traceback (``CHUTEFLOW_DEBUG=1`` shows it).
    """
    args = list(sys.argv[1:] if argv is None else argv)
    code = fast_main(args)
    if code is not None:
        return code
    cli = _application()
    # the command line's own process (sweeps in one process, reproduce, …): see
    # chuteflow._memory.keep_freed_memory (the fast path above allocates too little to care)
    from .._memory import keep_freed_memory

    keep_freed_memory()
    try:
        cli.app(args=args, prog_name="chuteflow")
    except SystemExit as exc:
        return exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    except cli.USER_ERRORS as exc:
        if os.environ.get("CHUTEFLOW_DEBUG"):
            raise
        cli.report_user_error(exc)
        return cli.EXIT_USER_ERROR
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

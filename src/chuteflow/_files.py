"""Files written atomically, with the permissions the user's umask implies.

A result file is written to a temporary file in the same folder and moved into place with
:func:`os.replace`, so a reader never sees a half-written file, whatever kills the process.
:func:`tempfile.mkstemp` creates its file with mode 0600; before the move the file gets the
mode an ordinary ``open(path, "w")`` would have given it (``0666 & ~umask``, e.g. 0644 under
the usual umask 022), so that colleagues sharing a cluster can read the results.
"""

from __future__ import annotations

import os
import tempfile
import threading
from contextlib import contextmanager, suppress
from pathlib import Path

__all__ = ["atomic_target", "atomic_write", "umask_mode"]

_UMASK_LOCK = threading.Lock()


def _current_umask() -> int:
    """The process's umask, read without changing it where the system allows."""
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    with _UMASK_LOCK:  # portable fallback: set and restore
        mask = os.umask(0o022)
        os.umask(mask)
    return mask


def umask_mode(mode: int = 0o666) -> int:
    """``mode`` with the bits of the current umask cleared (what ``open`` would create)."""
    return mode & ~_current_umask()


@contextmanager
def atomic_target(path: str | Path):
    """Yield a temporary path next to ``path``; move it onto ``path`` if the block succeeds.

    A reader (or a resumed sweep) never sees a half-written file, even after SIGKILL. The
    file ends with the mode the umask implies (:func:`umask_mode`), not mkstemp's 0600.
    """
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix="." + path.name + ".", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        yield tmp
        os.chmod(tmp, umask_mode())
        os.replace(tmp, path)
    except BaseException:
        with suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


def atomic_write(path: str | Path, write) -> None:
    """Call ``write(file_object)`` on a temporary file next to ``path``, then move it there."""
    with atomic_target(path) as tmp, open(tmp, "wb") as fh:
        write(fh)
        fh.flush()
        os.fsync(fh.fileno())

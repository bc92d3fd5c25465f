"""Finished tasks on disk: ``<out>.parts/``, one small file per task, written atomically.

Layout::

    <out>.parts/config.json        configuration and its SHA-256 (written first)
    <out>.parts/<task key>.npz     one finished task (values, status, messages, digest)

A part is written to a temporary file in the same folder and moved into place with
:func:`os.replace`, so a part either exists complete or not at all, whatever kills the
process (:func:`chuteflow._files.atomic_target`; the file gets the mode the umask implies).
A folder made for another configuration is never reused silently.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import numpy as np

from .._files import atomic_target, atomic_write
from ..errors import ParameterError
from .runner import TaskResult

__all__ = ["PartStore", "ConfigMismatchError", "parts_dir", "atomic_target", "atomic_write"]


class ConfigMismatchError(ParameterError):
    """Saved results belong to a different sweep configuration."""


def parts_dir(out: str | Path) -> Path:
    """The folder ``OUT.parts`` next to the sweep output ``out`` that holds finished tasks."""
    out = Path(out)
    return out.with_name(out.name + ".parts")


class PartStore:
    """The parts folder of one sweep output.

    Parameters
    ----------
    out : path
        The sweep's final NetCDF file; parts go to ``<out>.parts/``.
    config : SweepConfig
        The configuration; its digest must match the folder's (the manifest also records
        the model's :meth:`~chuteflow.closures.ChuteModel.key`, to say when the model is
        what differs).
    fresh : bool
        Delete parts of a different configuration instead of refusing.
    """

    def __init__(self, out, config, *, fresh: bool = False):
        self.out = Path(out)
        self.dir = parts_dir(out)
        self.config = config
        self.digest = config.digest()
        manifest = self.dir / "config.json"
        if self.dir.exists():
            old, old_model = None, None
            try:
                saved = json.loads(manifest.read_text())
                old = saved["digest"]
                old_model = saved.get("model_key")
            except (OSError, ValueError, KeyError):
                old = None
            if old != self.digest:
                leftovers = [p for p in self.dir.iterdir() if p.name != "config.json"]
                if fresh or (old is None and not leftovers):
                    shutil.rmtree(self.dir)
                else:
                    why = ""
                    if old_model is not None and old_model != config.model.key():
                        why = " with another model (parameters or closures)"
                    raise ConfigMismatchError(
                        f"out: {self.dir} holds partial results of a different sweep "
                        f"configuration{why} (digest {str(old)[:12]}, this one "
                        f"{self.digest[:12]}); use another output file, or fresh=True "
                        "(--fresh) to discard them"
                    )
        if not self.dir.exists():
            self.dir.mkdir(parents=True)
            text = json.dumps(
                {"digest": self.digest, "model_key": config.model.key(), "config": config.to_dict()}, indent=1
            )
            atomic_write(manifest, lambda fh: fh.write(text.encode()))

    def path(self, key: str) -> Path:
        return self.dir / f"{key}.npz"

    def done(self) -> set[str]:
        """Keys of the tasks whose parts exist (and carry this configuration's digest)."""
        keys = set()
        for p in self.dir.glob("*.npz"):
            if p.name.startswith("."):
                continue
            try:
                with np.load(p, allow_pickle=False) as z:
                    if str(z["digest"]) == self.digest:
                        keys.add(p.stem)
            except (OSError, ValueError, KeyError):
                continue  # unreadable: recomputed
        return keys

    def write(self, res: TaskResult) -> None:
        arrays: dict[str, Any] = {f"v_{k}": v for k, v in res.values.items()}
        arrays.update(
            status=res.status,
            message=res.message,
            digest=np.array(res.digest),
            key=np.array(res.key),
            index=np.array([res.i, res.j0, res.j1]),
        )
        atomic_write(self.path(res.key), lambda fh: np.savez(fh, **arrays))

    def read(self, key: str) -> TaskResult:
        with np.load(self.path(key), allow_pickle=False) as z:
            i, j0, j1 = (int(x) for x in z["index"])
            values = {k[2:]: z[k].copy() for k in z.files if k.startswith("v_")}
            return TaskResult(
                key=str(z["key"]),
                digest=str(z["digest"]),
                i=i,
                j0=j0,
                j1=j1,
                values=values,
                status=z["status"].copy(),
                message=z["message"].copy(),
            )

    def remove(self) -> None:
        shutil.rmtree(self.dir, ignore_errors=True)

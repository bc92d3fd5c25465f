"""JSON keys shared by the commands (docs/cli.md, "Keys common to the commands")."""

from __future__ import annotations

__all__ = ["COMMON_KEYS"]

#: The steady flow's parameters, the model's fields (``ChuteModel.to_dict()``) and ν0(y_max):
#: the first keys of every stability command's ``--json``.
COMMON_KEYS: tuple[str, ...] = (
    "theta",
    "nu0",
    "roughness",
    "wall_loss",
    "restitution",
    "nu_max",
    "radial",
    "wall",
    "transport",
    "nu_top",
)

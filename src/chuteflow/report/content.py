"""The content of a report: :class:`Checkpoint`, :class:`Figure` and the per-stage
:class:`Section` that holds them.

Both :mod:`chuteflow.report.report` (the :class:`~chuteflow.report.report.Report` that
collects sections) and :mod:`chuteflow.report.render` (Markdown and HTML) build on these
records; neither imports the other's module for them.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

__all__ = ["Checkpoint", "Figure", "Section", "STATUS_PASS", "STATUS_FAIL", "STATUS_NOT_CHECKED"]

#: The three values of :attr:`Checkpoint.status`.
STATUS_PASS, STATUS_FAIL, STATUS_NOT_CHECKED = "pass", "fail", "not checked"


@dataclass(frozen=True)
class Checkpoint:
    """One statement of the paper checked against chuteflow.

    Parameters
    ----------
    id : str
        Short identifier, unique within a report (e.g. ``"steady.h_theta16"``).
    source : str
        Where the paper says it: section, equation or figure as printed (e.g. ``"§3.2, figure 3"``).
    statement : str
        The paper's words (or a faithful paraphrase), e.g. ``"h ≈ 23 at θ = 16°"``.
    computed : str
        What chuteflow obtained, with the tolerance used, as text.
    passed : bool or None
        ``True``/``False`` for agreement/disagreement; ``None`` if not checked
        (e.g. a qualitative statement only shown in a figure).
    detail : str
        Anything else worth keeping (method, resolution, traceback of a failure).
    """

    id: str
    source: str
    statement: str
    computed: str
    passed: bool | None = None
    detail: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.id, str) or not self.id.strip():
            raise ValueError(f"checkpoint id must be a non-empty string, got {self.id!r}")
        if self.passed is not None:  # accept numpy.bool_ and the like
            object.__setattr__(self, "passed", bool(self.passed))
        for name in ("source", "statement", "computed", "detail"):
            object.__setattr__(self, name, str(getattr(self, name)))

    @property
    def status(self) -> str:
        """``"pass"``, ``"fail"`` or ``"not checked"``."""
        if self.passed is None:
            return STATUS_NOT_CHECKED
        return STATUS_PASS if self.passed else STATUS_FAIL

    @classmethod
    def compare(
        cls,
        id: str,
        *,
        source: str,
        statement: str,
        value: float,
        expected: float,
        rtol: float = 0.0,
        atol: float = 0.0,
        name: str = "value",
        fmt: str = ".4g",
        detail: str = "",
    ) -> Checkpoint:
        """Checkpoint for ``|value − expected| ≤ atol + rtol·|expected|``.

        ``computed`` reads e.g. ``"h = 23.41 (paper 23; |Δ| = 0.41 ≤ 1.15)"``.
        A non-finite ``value`` fails.
        """
        tol = atol + rtol * abs(expected)
        diff = abs(value - expected)
        passed = bool(math.isfinite(value) and diff <= tol)
        computed = (
            f"{name} = {value:{fmt}} (paper {expected:{fmt}}; "
            f"|Δ| = {diff:.2g} {'≤' if passed else '>'} {tol:.2g})"
        )
        return cls(id, source, statement, computed, passed, detail)

    def to_dict(self) -> dict[str, Any]:
        return {**asdict(self), "status": self.status}


@dataclass(frozen=True)
class Figure:
    """A figure file (PNG preferred) with its caption.

    ``source`` names the paper figure it reproduces (e.g. ``"figure 7"``).
    """

    path: Path
    caption: str
    id: str | None = None
    source: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "path", Path(self.path))


@dataclass
class Section:
    """Everything one stage contributed to the report."""

    name: str
    title: str
    checkpoints: list[Checkpoint] = field(default_factory=list)
    figures: list[Figure] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    #: ``"pending"``, ``"running"``, ``"ok"`` or ``"failed"`` (set by the runner).
    status: str = "pending"
    wall_time: float | None = None

"""The one convention for what a solver returns (docs/extending.md, "Results").

Every solver of chuteflow returns a result object that satisfies :class:`Result`:

- ``converged`` (bool): the answer meets the tolerance it was asked for; where it does not,
  the object is still the best estimate found, with its convergence estimates;
- ``note`` (str): empty when converged, else one line saying what missed which tolerance;
- ``to_dict()``: a JSON-ready dict of its scalars (the keys the CLI's ``--json`` prints);
- ``to_xarray()`` where the result has axes (profiles over y, curves over k, maps).

A solver takes ``strict=False`` by default and returns a flagged result; ``strict=True``
raises :class:`~chuteflow.errors.ConvergenceError` instead. Where no answer exists at all
(no steady flow at these parameters, bad input) a :class:`~chuteflow.errors.ChuteflowError`
is raised whatever ``strict`` says.
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

__all__ = ["Result"]


@runtime_checkable
class Result(Protocol):
    """What every solver returns (module docstring)."""

    @property
    def converged(self) -> bool: ...

    @property
    def note(self) -> str: ...

    def to_dict(self) -> dict[str, Any]: ...

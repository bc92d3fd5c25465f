"""Registries of closures: a closure is a small frozen class registered under its ``name``.

Each kind of closure (radial distribution g0, wall condition, transport closure) has one
:class:`Registry`. A new closure is one small frozen dataclass with a class attribute
``name`` and the methods of its base class, plus one registration::

    @register_radial
    @dataclass(frozen=True)
    class Torquato(RadialDistribution):
        name: ClassVar[str] = "torquato"

        def expr(self, nu, nu_max): ...

after which ``ChuteModel(radial="torquato")``, ``chuteflow steady --radial torquato`` and
the sweeps know it; nothing else changes.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from typing import Any, Generic, TypeVar

from ..errors import ParameterError

__all__ = ["Registry"]

T = TypeVar("T")


class Registry(Generic[T]):
    """Closures of one kind, by name.

    Parameters
    ----------
    kind : str
        What the closures are (the :class:`~chuteflow.closures.ChuteModel` field, e.g.
        ``"radial"``); used in error messages.
    base : type
        The base class every registered closure derives from.
    """

    def __init__(self, kind: str, base: type[T]):
        self.kind = kind
        self.base = base
        self._classes: dict[str, type[T]] = {}

    def register(self, cls: type[T]) -> type[T]:
        """Register the frozen dataclass ``cls`` under ``cls.name`` (usable as a decorator)."""
        if not (isinstance(cls, type) and issubclass(cls, self.base)):
            raise TypeError(f"{self.kind}: {cls!r} is not a subclass of {self.base.__name__}")
        params = cls.__dict__.get("__dataclass_params__")  # its own, not a base's
        if params is None or not params.frozen:
            raise TypeError(f"{self.kind}: {cls.__name__} must be a frozen dataclass")
        name = getattr(cls, "name", None)
        if not isinstance(name, str) or not name:
            raise TypeError(f"{self.kind}: {cls.__name__} needs a class attribute 'name'")
        if name in self._classes and self._classes[name] is not cls:
            raise ValueError(f"{self.kind}: the name {name!r} is taken by {self._classes[name].__name__}")
        self._classes[name] = cls
        return cls

    def unregister(self, name: str) -> None:
        """Remove the closure registered as ``name`` (e.g. one a test registered)."""
        self._classes.pop(name, None)

    def names(self) -> tuple[str, ...]:
        """Registered names, sorted."""
        return tuple(sorted(self._classes))

    def __contains__(self, name: object) -> bool:
        return name in self._classes

    def __getitem__(self, name: str) -> type[T]:
        try:
            return self._classes[name]
        except KeyError:
            raise ParameterError(
                f"{self.kind}: unknown closure {name!r}; choose one of {list(self.names())}"
            ) from None

    def create(self, spec: Any) -> T:
        """An instance from a name, a ``{"name": ..., **parameters}`` dict or an instance."""
        if isinstance(spec, self.base):
            return spec
        if isinstance(spec, str):
            return self[spec]()
        if isinstance(spec, Mapping) and isinstance(spec.get("name"), str):
            params = {k: v for k, v in spec.items() if k != "name"}
            try:
                return self[spec["name"]](**params)
            except TypeError as exc:
                raise ParameterError(
                    f"{self.kind}: bad parameters {params!r} for {spec['name']!r}: {exc}"
                ) from None
        raise ParameterError(
            f"{self.kind}: expected a closure name (one of "
            f"{list(self.names())}) or a {self.base.__name__}, got {spec!r}"
        )

    def spec(self, obj: T) -> str | dict[str, Any]:
        """JSON-ready form of ``obj``: its name, or ``{"name", **parameters}`` if it has any.

        Inverse of :meth:`create`.
        """
        name = type(obj).name  # type: ignore[attr-defined]
        if self._classes.get(name) is not type(obj):
            raise ParameterError(
                f"{self.kind}: {type(obj).__name__} is not registered (use the registry's register decorator)"
            )
        params = {f.name: getattr(obj, f.name) for f in dataclasses.fields(obj)}  # type: ignore[arg-type]
        return {"name": name, **params} if params else name

    def __repr__(self) -> str:
        return f"Registry({self.kind!r}, {list(self.names())})"

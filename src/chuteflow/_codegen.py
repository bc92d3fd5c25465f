"""Generated code for derived sympy expressions, cached on disk between processes.

The model is stated once symbolically (:mod:`chuteflow.closures`, :mod:`chuteflow.equations`)
and sympy derives the partial derivatives and linearisation coefficients from it. Deriving
and lambdifying takes seconds, too long to repeat in every process (each CLI call, each pool
or Dask worker). :func:`cached_lambdify` therefore writes the Python source code that
:func:`sympy.lambdify` generates into a small module in the user's cache folder, keyed by
a hash of

* the caller's description of what is derived (e.g. the ``repr`` of the closure objects),
* the source files of the modules that state the expressions, and of this module (so that
  editing a closure, an equation or the generator invalidates the cache without a version
  change),
* the chuteflow and sympy versions and the format of the generated module.

A later process with the same key loads the module (Python keeps its bytecode next to it)
and needs neither the derivation nor sympy itself. Cold and warm runs execute the same
generated source in the same namespace, so they give bitwise identical numbers.

Cache folder: ``$CHUTEFLOW_CACHE_DIR`` if set (an empty value, ``off`` or ``none`` disables
the disk cache), else ``$XDG_CACHE_HOME/chuteflow``, else ``~/.cache/chuteflow``. The code goes
to ``<folder>/codegen/``; every file is written atomically. Whenever the folder cannot be
written or a cached file cannot be used, the code is derived in memory instead, silently.
Deleting the folder is always safe.
"""

from __future__ import annotations

import ast
import builtins
import functools
import hashlib
import importlib
import importlib.util
import inspect
import json
import os
import re
import sys
import types
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, fields, is_dataclass
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any

from . import __version__
from ._files import atomic_write

__all__ = ["GeneratedCode", "cached_lambdify", "cache_dir", "cache_key", "lazy_module", "FORMAT"]

#: Version of the layout of the generated modules; part of every key.
FORMAT = 2

#: Namespace of the generated code: what ``sympy.lambdify(..., modules="numpy")`` provides
#: (its ``MODULES["numpy"]`` import commands and defaults, plus ``builtins`` and ``range``).
#: The public names numpy has already loaded stand in for ``from numpy import *``, which in
#: numpy 2 also imports numpy.f2py, numpy.testing, numpy.ma, … (~0.25 s per process);
#: :func:`_same_names` checks that every name the generated code uses means the same here.
_PRELUDE = """\
import builtins
import numpy
import numpy.linalg
globals().update(
    {_k: _v for _k, _v in vars(numpy).items() if not _k.startswith("_") and type(_v) is not type(numpy)}
)
globals().update({_k: getattr(numpy.linalg, _k) for _k in numpy.linalg.__all__})
I = 1j
Heaviside = numpy.heaviside
"""

#: Namespace of scalar code (``modules="math"``): what ``sympy.lambdify(..., modules="math")``
#: provides (``from math import *`` and its translations). Python floats in, Python floats
#: out, without numpy's per-call overhead (about 5× faster on scalars); outside a function's
#: domain it raises (ValueError, ZeroDivisionError, OverflowError) or returns a complex
#: number (a negative base to a fractional power) instead of giving NaN.
_PRELUDE_MATH = """\
import builtins
import math
globals().update({_k: _v for _k, _v in vars(math).items() if not _k.startswith("_")})
E = math.e
ln = math.log
ceiling = math.ceil
Abs = abs
"""

_PRELUDES = {"numpy": _PRELUDE, "math": _PRELUDE_MATH}

_DISABLED = ("", "0", "off", "none", "false", "no")


@dataclass(frozen=True)
class GeneratedCode:
    """Functions of one cached derivation, and the data that came with them.

    Attributes
    ----------
    functions : dict
        Function name -> numeric function (numpy arrays in, list of results out).
    data : object
        The Python literal returned by the derivation alongside the expressions (e.g. the
        names or the structure of the outputs); ``None`` if it returned none.
    key : str
        SHA-256 of the key material (:func:`cache_key`).
    path : Path or None
        The cached module the functions were loaded from; ``None`` when derived in memory.
    """

    functions: dict[str, Callable]
    data: Any
    key: str
    path: Path | None

    def __getitem__(self, name: str) -> Callable:
        return self.functions[name]


def cache_dir() -> Path | None:
    """The chuteflow cache folder, or ``None`` if disabled via ``CHUTEFLOW_CACHE_DIR``."""
    env = os.environ.get("CHUTEFLOW_CACHE_DIR")
    if env is not None:
        if env.strip().lower() in _DISABLED:
            return None
        return Path(env).expanduser()
    xdg = os.path.expanduser(os.environ.get("XDG_CACHE_HOME", ""))
    if os.path.isabs(xdg):  # the XDG spec ignores relative paths
        return Path(xdg) / "chuteflow"
    try:
        return Path.home() / ".cache" / "chuteflow"
    except RuntimeError:  # no home folder: no disk cache
        return None


def lazy_module(name: str) -> types.ModuleType:
    """A stand-in for module ``name`` that imports it on first attribute access.

    ``sp = lazy_module("sympy")`` at the top of a module that only uses sympy inside
    functions keeps ``import`` of that module free of sympy's import time. If the module is
    already imported, it is returned itself.
    """
    if name in sys.modules:
        return sys.modules[name]
    return _LazyModule(name)


class _LazyModule(types.ModuleType):
    def __getattr__(self, attr: str):
        if attr.startswith("__") and attr.endswith("__"):
            raise AttributeError(attr)
        value = getattr(importlib.import_module(self.__name__), attr)
        setattr(self, attr, value)
        return value


@functools.cache
def _package_version(dist: str) -> str:
    mod = sys.modules.get(dist)
    if mod is not None and isinstance(getattr(mod, "__version__", None), str):
        return mod.__version__
    try:
        return version(dist)
    except PackageNotFoundError:
        return "unknown"


def _source_modules(objs: Iterable[Any]) -> set[str]:
    """Names of the modules whose source defines ``objs`` (modules, names, or instances).

    For an instance: the modules of its class and base classes, and recursively of the
    values of its dataclass fields (e.g. the g0 of a closure).
    """
    out: set[str] = set()

    def visit(obj, depth):
        if depth > 8 or isinstance(obj, (type(None), bool, int, float, complex, str, bytes)):
            return  # plain field values: their repr is in the key already
        if isinstance(obj, types.ModuleType):
            out.add(obj.__name__)
        elif isinstance(obj, (tuple, list, frozenset, set)):
            for o in obj:
                visit(o, depth + 1)
        elif isinstance(obj, Mapping):
            for o in obj.values():
                visit(o, depth + 1)
        else:
            cls = obj if isinstance(obj, type) else type(obj)
            for c in cls.__mro__:
                if c.__module__ not in ("builtins", "abc", "typing"):
                    out.add(c.__module__)
            if is_dataclass(obj) and not isinstance(obj, type):
                for f in fields(obj):
                    visit(getattr(obj, f.name), depth + 1)

    for o in objs:
        if isinstance(o, str):
            out.add(o)  # a module name
        else:
            visit(o, 0)
    return out


def _source_digest(module: str) -> str | None:
    try:
        mod = sys.modules.get(module) or importlib.import_module(module)
    except ImportError:
        return None
    path = getattr(mod, "__file__", None)
    if not path:
        return None
    try:
        return hashlib.sha256(Path(path).read_bytes()).hexdigest()
    except OSError:
        return None


def cache_key(
    name: str, key: str, sources: Iterable[Any] = (), modules: str = "numpy"
) -> tuple[str, str] | None:
    """The key material (JSON) and its SHA-256, or ``None`` if it cannot be made reliable.

    ``None`` when ``key`` shows an object address (a ``repr`` without fields) or a source
    module has no readable file (e.g. a class defined interactively): such derivations
    are not cached on disk.
    """
    if re.search(r" at 0x[0-9a-fA-F]+", key):
        return None
    digests = {}
    for mod in sorted(_source_modules(sources) | {__name__}):  # this generator, too
        d = _source_digest(mod)
        if d is None:
            return None
        digests[mod] = d
    material = json.dumps(
        {
            "format": FORMAT,
            "modules": modules,
            "name": name,
            "key": key,
            "chuteflow": __version__,
            "sympy": _package_version("sympy"),
            "sources": digests,
        },
        sort_keys=True,
    )
    return material, hashlib.sha256(material.encode()).hexdigest()


def cached_lambdify(
    name: str,
    key: str,
    build_exprs: Callable[[], Mapping[str, tuple] | tuple[Mapping[str, tuple], Any]],
    *,
    sources: Iterable[Any] = (),
    cse: bool = True,
    modules: str = "numpy",
) -> GeneratedCode:
    """Numeric functions of derived sympy expressions, from the disk cache when possible.

    Parameters
    ----------
    name : str
        Short name of the derivation (part of the file name and of the key).
    key : str
        Everything the expressions depend on besides the source code, e.g.
        ``repr((closure, wall))`` of frozen dataclasses. Must not contain object addresses.
    build_exprs : callable
        Called only on a cache miss. Returns ``{function name: (args, exprs)}`` (sympy
        symbols, list of sympy expressions; a third item overrides ``cse`` for that
        function) or a pair of that and ``data``, a Python literal (numbers, strings,
        tuples, lists, dicts) stored with the code.
    sources : iterable
        Modules (or module names, or the objects whose classes state the expressions) whose
        source code the expressions come from; their files' hashes are part of the key.
    cse : bool
        Common-subexpression elimination in the generated code.
    modules : {"numpy", "math"}
        Namespace of the generated code: ``"numpy"`` (arrays; NaN outside a function's
        domain) or ``"math"`` (Python scalars only, several times faster on them; raises or
        returns a complex number outside a function's domain).

    Returns
    -------
    GeneratedCode
        ``functions[fname](*args)`` returns the list of expressions' values.
    """
    if modules not in _PRELUDES:
        raise ValueError(f"modules = {modules!r}: expected one of {sorted(_PRELUDES)}")
    made = cache_key(name, key, sources, modules)
    folder = cache_dir()
    path = None
    if made is not None and folder is not None:
        material, digest = made
        path = folder / "codegen" / f"{_safe(name)}-{digest[:32]}.py"
        loaded = _load(path, digest)
        if loaded is not None:
            return loaded
    else:
        material = json.dumps({"name": name, "key": key, "modules": modules, "uncached": True})
        digest = hashlib.sha256(material.encode()).hexdigest()
    try:
        text = _generate(name, material, digest, build_exprs, cse, modules)
    except _NotReproducible as exc:  # code that only lambdify's own namespace can run
        return GeneratedCode(exc.functions, exc.data, digest, None)
    if path is not None:
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            atomic_write(path, lambda fh: fh.write(text.encode("utf-8")))
        except OSError:
            pass
        else:
            _prune(path.parent, _safe(name), keep=path)
            loaded = _load(path, digest)
            if loaded is not None:
                return loaded
    return _from_namespace(_exec(text, f"<chuteflow generated {name}>"), digest, None)


class _NotReproducible(Exception):
    """The generated code needs names that the cached module's namespace lacks."""

    def __init__(self, functions, data):
        super().__init__("generated code not reproducible outside sympy.lambdify")
        self.functions, self.data = functions, data


#: Generated modules kept per derivation name (older ones belong to edited sources or
#: other versions; the oldest beyond this number are deleted when a new one is written).
KEEP = 32


def _prune(folder: Path, stem: str, keep: Path, suffix: str = ".py") -> None:
    """Delete all but the :data:`KEEP` most recent files named ``stem-*<suffix>`` (best
    effort), with their byte code (modules) or C source (libraries, ``suffix=".so"``)."""
    try:
        files = sorted(folder.glob(f"{stem}-*{suffix}"), key=lambda p: p.stat().st_mtime, reverse=True)
        for old in files[KEEP:]:
            if old != keep:
                old.unlink(missing_ok=True)
                old.with_suffix(".c").unlink(missing_ok=True)
                for pyc in (folder / "__pycache__").glob(old.stem + ".*"):
                    pyc.unlink(missing_ok=True)
    except OSError:
        pass


def _safe(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_]+", "_", name) or "code"


def _load(path: Path, digest: str) -> GeneratedCode | None:
    """The cached module at ``path`` if it exists, loads, and carries ``digest``."""
    if not path.is_file():
        return None
    try:
        spec = importlib.util.spec_from_file_location(f"_chuteflow_codegen_{digest[:16]}", path)
        if spec is None or spec.loader is None:
            return None
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        return _from_namespace(vars(module), digest, path)
    except Exception:  # a damaged cache file is never fatal: derive again
        return None


def _from_namespace(ns: Mapping[str, Any], digest: str, path: Path | None) -> GeneratedCode:
    if ns.get("KEY") != digest:
        raise ValueError("generated code carries another key")
    funcs = {}
    for fname, defname in ns["FUNCTIONS"].items():
        f = ns[defname]
        if not callable(f):
            raise ValueError(f"generated code: {fname} is not a function")
        funcs[fname] = f
    return GeneratedCode(funcs, ns["DATA"], digest, path)


def _exec(text: str, filename: str) -> dict[str, Any]:
    ns: dict[str, Any] = {"__name__": "_chuteflow_codegen", "__builtins__": builtins}
    exec(compile(text, filename, "exec"), ns)
    return ns


def _generate(name, material, digest, build_exprs, cse, modules="numpy") -> str:
    """Derive the expressions and return the text of the module holding their code."""
    sp = lazy_module("sympy")  # imported only on a cache miss
    built = build_exprs()
    if isinstance(built, tuple):
        spec, data = built
    else:
        spec, data = built, None
    if data is not None and _literal(repr(data)) != data:
        raise ValueError(f"{name}: data {data!r} is not a Python literal")
    prelude = _exec(_PRELUDES[modules], "<chuteflow codegen prelude>")
    # Python names of the generated functions: never clash with the numpy namespace
    defnames = {fname: f"_generated_{i}_{_safe(fname)}" for i, fname in enumerate(spec)}
    parts = [
        f"# Generated by chuteflow._codegen ({name}); do not edit.",
        "# Delete this file (or the whole folder) to derive the code again.",
        f"KEY = {digest!r}",
        f"MATERIAL = {material!r}",
        f"DATA = {data!r}",
        f"FUNCTIONS = {defnames!r}",
        _PRELUDES[modules],
    ]
    lambdified, reproducible = {}, True
    for fname, item in spec.items():
        args, exprs = item[0], item[1]
        fcse = item[2] if len(item) > 2 else cse
        f = sp.lambdify(tuple(args), list(exprs), modules=modules, cse=fcse)
        lambdified[fname] = f
        src = inspect.getsource(f)
        head = "def _lambdifygenerated("
        reproducible = reproducible and src.startswith(head) and _same_names(f, prelude)
        parts.append(f"def {defnames[fname]}(" + src[len(head) :])
    if not reproducible:
        raise _NotReproducible(lambdified, data)
    return "\n".join(parts) + "\n"


def _same_names(f, prelude) -> bool:
    """Whether every global the generated code uses means the same in the cached module's
    namespace as in lambdify's."""
    names: set[str] = set()
    stack = [f.__code__]
    while stack:
        code = stack.pop()
        names.update(code.co_names)
        stack.extend(c for c in code.co_consts if isinstance(c, types.CodeType))
    glob = f.__globals__
    for n in names:
        if n not in glob:
            continue  # attribute names (numpy.xxx) or builtins
        mine = prelude.get(n, getattr(builtins, n, None))
        theirs = glob[n]
        if mine is not theirs and not (isinstance(theirs, (int, float, complex)) and mine == theirs):
            return False
    return True


def _literal(text: str):
    return ast.literal_eval(text)
